"""The safety envelope of an excitation experiment (on by default in ``rx90 excite``).

- Height: no moving point (frame origins after joint 1, the lower surface of every capsule end
  on a link after joint 1, the tool point) below z_min = max(mounting plane + margin, floor).
- Experiment limits narrower than the robot's: position ranges (given, or ``position_fraction``
  of each range about its centre), velocities x ``velocity_scale``, accelerations x
  ``acceleration_scale`` (a URDF without acceleration limits: the conservative default
  URDF_ACCELERATION_PER_VELOCITY x its velocity limit first).
- Cartesian speed: the tool point and every capsule end below ``max_speed`` [m/s].
- Self-collision and obstacle boxes (collision.py), with the robot's own capsules
  (robot_geometry.py).
- A centre pose inside the envelope, about which random starts are drawn: the centre of the
  ranges if it is inside, else the nearest pose inside (found by IPOPT), or the one given.

Defaults and their reasons: docs/excitation.md ("Safety envelope").
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Sequence

import casadi as ca
import numpy as np

from .collision import CollisionModel, _segment_distance
from .constraints import Margins, position_bounds
from .model import ExcitationModel, JointLimits

if TYPE_CHECKING:
    import rx90sym
    from .robot_geometry import ArmGeometry

DEFAULT_MARGIN = 0.05          # [m] above the mounting plane
DEFAULT_MAX_SPEED = 1.0        # [m/s] tool point and capsule ends (UR's default TCP limit: 1.5)
POSITION_FRACTION = 0.9        # of each joint range, about its centre
VELOCITY_SCALE = 0.7           # of the robot's joint velocity limits
ACCELERATION_SCALE = 0.5       # of the robot's joint acceleration limits
URDF_ACCELERATION_PER_VELOCITY = 2.0  # [1/s] a URDF without accelerations: full speed in 0.5 s


@dataclass(frozen=True)
class Envelope:
    """Settings of the safety envelope (see the module docstring); angles are model angles [rad].

    margin [m] above the mounting plane; floor [m above the mounting plane] or None; max_speed [m/s];
    position_limits ((lo, hi) per joint) or None for position_fraction of each range;
    velocity_scale, acceleration_scale in (0, 1]; centre: pose to start from, or None (found);
    urdf_acceleration: the robot's acceleration limits are a URDF loader's default (replaced by
    the conservative URDF_ACCELERATION_PER_VELOCITY x velocity limit).
    """

    margin: float = DEFAULT_MARGIN
    floor: float | None = None
    max_speed: float = DEFAULT_MAX_SPEED
    position_fraction: float = POSITION_FRACTION
    velocity_scale: float = VELOCITY_SCALE
    acceleration_scale: float = ACCELERATION_SCALE
    position_limits: tuple[tuple[float, float], ...] | None = None
    centre: tuple[float, ...] | None = None
    urdf_acceleration: bool = False

    def __post_init__(self) -> None:
        for name in ("position_fraction", "velocity_scale", "acceleration_scale"):
            value = getattr(self, name)
            if not 0.0 < value <= 1.0:
                raise ValueError(f"envelope: {name} must be in (0, 1], got {value}")
        if not 0.0 < self.max_speed <= 1.5:
            raise ValueError(f"envelope: Cartesian speed limit must be in (0, 1.5] m/s, got {self.max_speed}")
        if self.margin < 0.0:
            raise ValueError(f"envelope: margin above the mounting plane must be >= 0 m, got {self.margin}")

    def z_min(self, geometry: ArmGeometry) -> float:
        """Lowest height [m, frame 0] any moving point may reach: the mounting plane plus the
        margin or the floor (a height above the mounting plane), whichever is higher."""
        above = self.margin if self.floor is None else max(self.margin, float(self.floor))
        return geometry.mounting_z + above

    def joint_limits(self, limits: Any) -> JointLimits:
        """The experiment's limits from the robot's; ValueError naming the joint when given
        position limits are empty or outside the robot's ranges."""
        lo, hi = np.asarray(limits.q_min, float), np.asarray(limits.q_max, float)
        n = lo.size
        if self.position_limits is None:
            centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo) * self.position_fraction
            with np.errstate(invalid="ignore"):
                q_lo = np.where(np.isfinite(half), centre - half, lo)
                q_hi = np.where(np.isfinite(half), centre + half, hi)
        else:
            given = np.asarray(self.position_limits, float)
            if given.shape != (n, 2):
                raise ValueError(f"position limits: {given.size // 2} (min, max) pairs for a {n}-joint robot")
            q_lo, q_hi = given[:, 0], given[:, 1]
            for j in range(n):
                if not q_hi[j] > q_lo[j]:
                    raise ValueError(f"position limits of joint {j + 1}: max {q_hi[j]:.6g} rad is not above "
                                     f"min {q_lo[j]:.6g} rad (zero or negative width)")
                if q_lo[j] < lo[j] - 1e-12 or q_hi[j] > hi[j] + 1e-12:
                    raise ValueError(f"position limits of joint {j + 1}: [{q_lo[j]:.6g}, {q_hi[j]:.6g}] rad "
                                     f"leave the robot's range [{lo[j]:.6g}, {hi[j]:.6g}] rad")
        qd = np.asarray(limits.qd_max, float)
        qdd = np.asarray(limits.qdd_max, float)
        if self.urdf_acceleration:
            qdd = np.where(np.isfinite(qd), np.minimum(qdd, URDF_ACCELERATION_PER_VELOCITY * qd), qdd)
        return JointLimits(q_lo, q_hi, qd * self.velocity_scale, qdd * self.acceleration_scale,
                           limits.tau_max)


def envelope_functions(robot: rx90sym.Robot, geometry: ArmGeometry, capsules: Any
                       ) -> tuple[ca.Function, tuple[str, ...], ca.Function, tuple[str, ...]]:
    """(heights q -> (k,) [m], their names, squared speeds (q, qd) -> (m,) [m^2/s^2], their names).

    Heights: origins of frames 2..n, capsule ends on frames >= 2 minus their radius, the tool
    point. Speeds: the tool point and the ends of every capsule on a moving link."""
    q, qd = ca.SX.sym("q", robot.n), ca.SX.sym("qd", robot.n)
    t0n, origins = robot.forward_kinematics(q)
    tool = ca.mtimes(t0n, ca.DM([*geometry.tool_point, 1.0]))[:3]
    candidates, points, p_names = [], [tool], ["tool point"]
    for j in range(1, robot.n):  # origin of frame j+1
        candidates.append((origins[2, j], f"origin of frame {j + 1}"))
    ends = capsules.segments(q)
    for i, (name, r) in enumerate(zip(capsules.names, capsules.radii)):
        link = capsules.links[i] if capsules.links else 1
        for e, label in ((2 * i, "a"), (2 * i + 1, "b")):
            if link >= 2:
                candidates.append((ends[2, e] - r, f"capsule {name!r} end {label} (lower surface)"))
            if link >= 1:
                points.append(ends[:, e])
                p_names.append(f"capsule {name!r} end {label}")
    candidates.append((tool[2], "tool point"))
    # Points whose height no joint changes (on the first, vertical axis: a UR's shoulder) cannot
    # move below anything: they are the fixed part, checked once (fixed_heights).
    moving = [(z, n) for z, n in candidates if ca.depends_on(z, q)]
    heights, h_names = [z for z, _ in moving], [n for _, n in moving]
    pts = ca.horzcat(*points)
    vel = ca.jtimes(pts, q, qd)  # dp/dt = J(q) qd, exact
    speeds = ca.sum1(vel * vel).T
    return (ca.Function("heights", [q], [ca.vertcat(*heights)], ["q"], ["z"]), tuple(h_names),
            ca.Function("speeds2", [q, qd], [speeds], ["q", "qd"], ["v2"]), tuple(p_names))


def fixed_heights(robot: rx90sym.Robot, geometry: ArmGeometry, capsules: Any) -> list[tuple[str, float]]:
    """(name, z [m]) of the frame origins after joint 1 and capsule ends on frames >= 2 whose
    height no joint changes."""
    q = ca.SX.sym("q", robot.n)
    origins = robot.forward_kinematics(q)[1]
    ends = capsules.segments(q)
    out = [(f"origin of frame {j + 1}", origins[2, j]) for j in range(1, robot.n)]
    for i, (name, r) in enumerate(zip(capsules.names, capsules.radii)):
        if (capsules.links[i] if capsules.links else 1) >= 2:
            out += [(f"capsule {name!r} end {lab} (lower surface)", ends[2, e] - r)
                    for e, lab in ((2 * i, "a"), (2 * i + 1, "b"))]
    zero = np.zeros(robot.n)
    return [(n, float(ca.Function("z", [q], [z])(zero))) for n, z in out if not ca.depends_on(z, q)]


def envelope_model(model: ExcitationModel, robot: rx90sym.Robot, envelope: Envelope,
                   geometry: ArmGeometry, collision: CollisionModel,
                   margins: Margins = Margins()) -> ExcitationModel:
    """``model`` within the envelope: experiment limits, heights, speeds, collisions, centre."""
    heights, h_names, speeds, s_names = envelope_functions(robot, geometry, collision.capsules)
    out = dataclasses.replace(model, limits=envelope.joint_limits(robot.limits), heights=heights,
                              z_min=envelope.z_min(geometry), speeds=speeds, speed_max=envelope.max_speed,
                              collision=collision, point_names=(h_names, s_names), centre=None)
    if envelope.centre is not None:
        centre = np.asarray(envelope.centre, float)
        bad = pose_violations(out, centre, margins)
        if bad:
            raise ValueError(f"centre pose: {bad[0]}")
        return dataclasses.replace(out, centre=centre)
    return dataclasses.replace(out, centre=find_centre(out, margins))


def pose_violations(model: ExcitationModel, q: Sequence[float], margins: Margins | None = None) -> list[str]:
    """What the pose q [rad, model angles] breaks: experiment ranges, heights (naming the point),
    collisions (naming the capsules or box). With margins, the optimiser's margins count too."""
    q = np.asarray(q, dtype=float)
    lim = model.limits
    dz = 0.0 if margins is None else margins.height
    dc = 0.0 if margins is None else margins.clearance
    out = [f"joint {j + 1} at {q[j]:.6g} rad is outside the experiment's range [{lim.q_min[j]:.6g}, "
           f"{lim.q_max[j]:.6g}] rad" for j in range(q.size) if not lim.q_min[j] <= q[j] <= lim.q_max[j]]
    if model.heights is not None:
        z = np.asarray(model.heights(q)).ravel()
        for k in np.flatnonzero(z < model.z_min + dz):
            out.append(f"{model.point_names[0][k]} at z = {z[k]:.4f} m, below the lowest allowed "
                       f"z = {model.z_min + dz:.4f} m")
    if model.collision is not None:
        out += collision_violations(model.collision, q, dc)
    return out


def collision_violations(collision: CollisionModel, q: np.ndarray, clearance: float = 0.0) -> list[str]:
    """Capsule pairs (self-collision) and capsule/box pairs closer than ``clearance`` [m] at q."""
    from .collision import _box_distance

    caps = collision.capsules
    ends = np.asarray(caps.segments(q)).reshape(3, -1, order="F")
    a, b = ends[:, 0::2], ends[:, 1::2]
    out = []
    if collision.self_collision:
        for i, j in caps.pairs:
            d = _segment_distance(a[:, i][None], b[:, i][None], a[:, j][None], b[:, j][None])[0]
            gap = d - caps.radii[i] - caps.radii[j]
            if gap < clearance:
                out.append(f"capsules {caps.names[i]!r} and {caps.names[j]!r} {gap:.4f} m apart "
                           f"(at least {clearance:g} m required)")
    s = np.linspace(0.0, 1.0, 50)[:, None]
    for box in collision.boxes:
        for i, r in enumerate(caps.radii):
            gap = float(np.min(_box_distance(a[:, i] + (b[:, i] - a[:, i]) * s, box))) - r
            if gap < clearance:
                out.append(f"capsule {caps.names[i]!r} {gap:.4f} m from obstacle box {box.lo}-{box.hi}")
    return out


def find_centre(model: ExcitationModel, margins: Margins = Margins(), slack: float = 0.1) -> np.ndarray:
    """The centre of the joint ranges if it is inside the envelope (with the optimiser's margins
    plus ``slack`` [m], 0.1 m: room for the random starts), else the nearest such pose (IPOPT, ranges scaled to 1). ValueError when
    none is found (e.g. a floor the arm cannot clear), naming what the best pose breaks."""
    lim = model.limits
    lo, hi = position_bounds(model, margins.position)
    centre = np.where(np.isfinite(lo + hi), 0.5 * (lo + hi), 0.0)
    inflated = Margins(height=margins.height + slack, clearance=margins.clearance + slack)
    if not pose_violations(model, centre, inflated) and _cover_ok(model, centre, inflated.clearance):
        return centre
    q = ca.MX.sym("q", model.n)
    scale = np.where(np.isfinite(hi - lo), 0.5 * (hi - lo), 1.0)
    g, lbg = [], []
    if model.heights is not None:
        g.append(model.heights(q))
        lbg.append(np.full(g[-1].shape[0], model.z_min + inflated.height))
    if model.collision is not None and model.collision.clearance is not None:
        g.append(model.collision.clearance(q))
        lbg.append(np.full(g[-1].shape[0], inflated.clearance))
    nlp = {"x": q, "f": ca.sumsqr((q - ca.DM(centre)) / ca.DM(scale)), "g": ca.vertcat(*g)}
    solver = ca.nlpsol("centre", "ipopt", nlp, {"ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": False,
                                                "error_on_fail": False, "ipopt.max_iter": 500})
    best = None
    for k, guess in enumerate([centre] + [centre + 0.5 * scale * np.random.default_rng([7, k]).uniform(-1, 1, model.n)
                                          for k in range(1, 6)]):
        sol = solver(x0=np.clip(guess, lo, hi), lbx=lo, ubx=hi, lbg=np.concatenate(lbg), ubg=np.inf)
        x = np.asarray(sol["x"]).ravel()
        turns = np.round((x - centre) / (2.0 * np.pi))  # the same pose one turn nearer the centre
        x = np.where((x - 2.0 * np.pi * turns >= lo) & (x - 2.0 * np.pi * turns <= hi), x - 2.0 * np.pi * turns, x)
        if not pose_violations(model, x, margins) and _cover_ok(model, x, margins.clearance):
            if best is None or np.sum(((x - centre) / scale) ** 2) < np.sum(((best - centre) / scale) ** 2):
                best = x
    if best is None:
        problems = pose_violations(model, centre, margins)
        raise ValueError("safety envelope: no pose of the arm lies inside the envelope near the centre "
                         f"of its ranges (at the centre: {problems[0] if problems else 'the optimiser cover'}"
                         f"); lower the floor, move the obstacles or widen the position limits")
    return best


def _cover_ok(model: ExcitationModel, q: np.ndarray, clearance: float) -> bool:
    """The optimiser's ball cover keeps ``clearance`` [m] at q (what IPOPT will impose)."""
    if model.collision is None or model.collision.clearance is None:
        return True
    return float(np.min(np.asarray(model.collision.clearance(q)))) >= clearance


def path_violations(model: ExcitationModel, q_from: Sequence[float], q_to: Sequence[float],
                    samples: int = 200, what: str = "approach path") -> list[str]:
    """Envelope violations (no margins) on the joint-space straight line from q_from to q_to
    (a movej's path and the quintic approach's), naming the first pose that breaks it."""
    a, b = np.asarray(q_from, float), np.asarray(q_to, float)
    for s in np.linspace(0.0, 1.0, samples):
        bad = [v for v in pose_violations(model, a + s * (b - a)) if "outside the experiment" not in v]
        if bad:
            return [f"{what}, {100 * s:.0f} % of the way: {bad[0]}"]
    return []


def describe(envelope: Envelope, geometry: ArmGeometry, model: ExcitationModel, robot_limits: Any) -> dict[str, Any]:
    """JSON-ready description of the envelope as applied (printed with every trajectory)."""
    lim = model.limits
    caps = model.collision.capsules if model.collision is not None else None
    return {
        "mounting_plane_z_m": geometry.mounting_z, "mounting_plane_source": geometry.mounting_source,
        "margin_above_mounting_m": envelope.margin, "floor_above_mounting_m": envelope.floor,
        "z_min_m": model.z_min,
        "height_points": list(model.point_names[0]),
        "max_point_speed_m_s": envelope.max_speed, "speed_points": list(model.point_names[1]),
        "position_limits_rad": np.c_[lim.q_min, lim.q_max].tolist(),
        "velocity_limits_rad_s": lim.qd_max.tolist(), "velocity_scale": envelope.velocity_scale,
        "acceleration_limits_rad_s2": lim.qdd_max.tolist(), "acceleration_scale": envelope.acceleration_scale,
        "urdf_default_acceleration": envelope.urdf_acceleration,
        "centre_pose_rad": None if model.centre is None else model.centre.tolist(),
        "centre_given": envelope.centre is not None,
        "capsules_source": geometry.source,
        "capsules": None if caps is None else [{"name": n, "radius_m": r} for n, r in zip(caps.names, caps.radii)],
        "self_collision": bool(model.collision is not None and model.collision.self_collision),
        "pairs_checked": 0 if caps is None else len(caps.pairs),
        "obstacles": [] if model.collision is None else [[*b.lo, *b.hi] for b in model.collision.boxes],
        "fixed_points_below_z_min": [],
    }


def describe_robot(envelope: Envelope, geometry: ArmGeometry, model: ExcitationModel,
                   robot: rx90sym.Robot) -> dict[str, Any]:
    """:func:`describe` plus the points no joint moves that lie below z_min (left out: the floor
    then cuts the arm's fixed part, which the user should know)."""
    out = describe(envelope, geometry, model, robot.limits)
    caps = model.collision.capsules if model.collision is not None else None
    if caps is not None:
        out["fixed_points_below_z_min"] = [f"{n} at z = {z:.4f} m" for n, z in fixed_heights(robot, geometry, caps)
                                           if z < model.z_min]
    return out


def summary_lines(info: dict[str, Any]) -> list[str]:
    """Human-readable lines of :func:`describe` (printed by ``rx90 excite``)."""
    deg = np.degrees
    pos = ", ".join(f"[{deg(lo):.0f}, {deg(hi):.0f}]" for lo, hi in info["position_limits_rad"])
    return [
        f"safety envelope: no moving point below z = {info['z_min_m']:.3f} m in frame 0 (mounting plane z = "
        f"{info['mounting_plane_z_m']:.3f} m: {info['mounting_plane_source']}; margin {info['margin_above_mounting_m']:g} m"
        + (f"; floor {info['floor_above_mounting_m']:g} m above the mounting plane"
           if info["floor_above_mounting_m"] is not None else "") + ")",
        f"  joint ranges [deg]: {pos}",
        f"  velocities x{info['velocity_scale']:g}: {', '.join(f'{v:.3g}' for v in info['velocity_limits_rad_s'])} rad/s; "
        f"accelerations x{info['acceleration_scale']:g}: {', '.join(f'{v:.3g}' for v in info['acceleration_limits_rad_s2'])} rad/s^2"
        + (" (URDF: no acceleration limits given, conservative default)" if info["urdf_default_acceleration"] else ""),
        f"  Cartesian speed <= {info['max_point_speed_m_s']:g} m/s at the tool point and {len(info['speed_points']) - 1} capsule ends",
        f"  self-collision: {info['pairs_checked']} capsule pairs ({len(info['capsules'] or [])} capsules from "
        f"{info['capsules_source']}); {len(info['obstacles'])} obstacle box(es)",
        f"  centre pose [deg]: {', '.join(f'{v:.1f}' for v in deg(info['centre_pose_rad']))}"
        + (" (given)" if info["centre_given"] else ""),
    ] + ([f"  note: {len(info['fixed_points_below_z_min'])} point(s) no joint moves lie below z_min and are "
          f"left out (the floor cuts the arm's fixed part), e.g. {info['fixed_points_below_z_min'][0]}"]
         if info.get("fixed_points_below_z_min") else [])


def shrink_to_envelope(model: ExcitationModel, form: Any, z: np.ndarray, z_centre: np.ndarray,
                       times: np.ndarray, margins: Margins, tries: int = 12) -> np.ndarray:
    """Free coefficients z pulled towards the constant centre pose z_centre (factor 0.7 per try)
    until heights, speeds and collisions hold with margins at ``times``: random starts begin
    inside the envelope. Returns z unchanged for a model without an envelope."""
    if model.heights is None and model.speeds is None and model.collision is None:
        return z
    rest = form.rest_basis()
    f = 1.0
    for _ in range(tries):
        trial = z_centre + f * (z - z_centre)
        q, qd, _qdd = (b @ rest @ trial for b in form.basis(times))
        if _inside(model, q, qd, margins):
            return trial
        f *= 0.7
    return z_centre + f * (z - z_centre)


def _inside(model: ExcitationModel, q: np.ndarray, qd: np.ndarray, margins: Margins) -> bool:
    from .constraints import evaluate_heights, evaluate_speeds

    z = evaluate_heights(model, q)
    if z is not None and np.min(z) < model.z_min + margins.height:
        return False
    v = evaluate_speeds(model, q, qd)
    if v is not None and np.max(v) > (1.0 - margins.velocity) * model.speed_max:
        return False
    if model.collision is not None and model.collision.clearance is not None:
        c = np.asarray(model.collision.clearance.map(q.shape[0], "serial")(q.T))
        if np.min(c) < margins.clearance:
            return False
    return True
