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

Angles: the settings (position_limits, centre) and every message are in controller angles
(q_controller = q_model + robot.controller_offsets: what the user types and the logs hold);
the model and the functions' pose arguments are in model angles (Khalil). The JSON block and
printed lines: envelope_description.py.

Defaults and their reasons: docs/excitation.md ("Safety envelope").
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Sequence

import casadi as ca
import numpy as np

from rx90sym.defaults import ACCELERATION_PER_VELOCITY

from .collision import CollisionModel, _segment_distance
from .constraints import Margins, position_bounds
from .model import ExcitationModel, JointLimits
from .kernels import evaluate_samples

if TYPE_CHECKING:
    import rx90sym
    from .robot_geometry import ArmGeometry

DEFAULT_MARGIN = 0.05          # [m] above the mounting plane
DEFAULT_MAX_SPEED = 1.0        # [m/s] tool point and capsule ends (UR's default TCP limit: 1.5)
POSITION_FRACTION = 0.9        # of each joint range, about its centre
VELOCITY_SCALE = 0.7           # of the robot's joint velocity limits
ACCELERATION_SCALE = 0.5       # of the robot's joint acceleration limits
URDF_ACCELERATION_PER_VELOCITY = ACCELERATION_PER_VELOCITY  # [1/s] a URDF without accelerations (rx90sym.defaults)


@dataclass(frozen=True)
class Envelope:
    """Settings of the safety envelope (see the module docstring); angles are CONTROLLER angles
    [rad] (q_controller = q_model + robot.controller_offsets).

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

    def joint_limits(self, limits: Any, offsets: Sequence[float]) -> JointLimits:
        """The experiment's limits (model angles) from the robot's ``limits`` (model angles) and
        its controller ``offsets`` [rad]. ValueError naming the joint, in controller angles, when
        the given position limits are empty or leave the robot's ranges, or the given centre
        pose lies outside the experiment's ranges."""
        lo, hi = np.asarray(limits.q_min, float), np.asarray(limits.q_max, float)
        offsets = np.asarray(offsets, float)
        n = lo.size
        if self.position_limits is None:
            with np.errstate(invalid="ignore"):  # a joint without position limits: inf - inf
                centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo) * self.position_fraction
                q_lo = np.where(np.isfinite(half), centre - half, lo)
                q_hi = np.where(np.isfinite(half), centre + half, hi)
        else:
            given = np.asarray(self.position_limits, float)
            if given.shape != (n, 2):
                raise ValueError(f"position limits: {given.size // 2} (min, max) pairs for a {n}-joint robot")
            for j, (a, b) in enumerate(given):
                if not b > a:
                    raise ValueError(f"position limits of joint {j + 1}: max {b:.6g} rad is not above "
                                     f"min {a:.6g} rad (zero or negative width)")
                if a < lo[j] + offsets[j] - 1e-12 or b > hi[j] + offsets[j] + 1e-12:
                    raise ValueError(f"position limits of joint {j + 1}: [{a:.6g}, {b:.6g}] rad leave the robot's "
                                     f"range [{lo[j] + offsets[j]:.6g}, {hi[j] + offsets[j]:.6g}] rad "
                                     f"(controller angles)")
            q_lo, q_hi = given[:, 0] - offsets, given[:, 1] - offsets
        if self.centre is not None:
            bad = range_violations(np.asarray(self.centre, float), q_lo + offsets, q_hi + offsets, "experiment's")
            if bad:
                raise ValueError(f"centre pose: {bad[0]}")
        qd = np.asarray(limits.qd_max, float)
        qdd = np.asarray(limits.qdd_max, float)
        if self.urdf_acceleration:
            qdd = np.where(np.isfinite(qd), np.minimum(qdd, URDF_ACCELERATION_PER_VELOCITY * qd), qdd)
        return JointLimits(q_lo, q_hi, qd * self.velocity_scale, qdd * self.acceleration_scale,
                           limits.tau_max)


def range_violations(q: np.ndarray, lo: np.ndarray, hi: np.ndarray, whose: str) -> list[str]:
    """The joints of pose q outside [lo, hi], all [rad, controller angles], quoting q as given
    (``whose``: "robot's" or "experiment's" range)."""
    return [f"joint {j + 1} at {q[j]:.6g} rad is outside the {whose} range [{lo[j]:.6g}, {hi[j]:.6g}] rad "
            f"(controller angles)" for j in range(q.size) if not lo[j] <= q[j] <= hi[j]]


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
    limits = envelope.joint_limits(robot.limits, model.controller_offsets)
    out = dataclasses.replace(model, limits=limits, heights=heights,
                              z_min=envelope.z_min(geometry), speeds=speeds, speed_max=envelope.max_speed,
                              collision=collision, point_names=(h_names, s_names), centre=None)
    if envelope.centre is not None:  # given in controller angles
        centre = np.asarray(envelope.centre, float) - model.controller_offsets
        bad = pose_violations(out, centre, margins)
        if bad:
            typed = ", ".join(f"{v:.6g}" for v in envelope.centre)
            raise ValueError(f"centre pose {typed} rad (controller angles) is outside the safety envelope: {bad[0]}")
        return dataclasses.replace(out, centre=centre)
    return dataclasses.replace(out, centre=find_centre(out, margins))


def pose_violations(model: ExcitationModel, q: Sequence[float], margins: Margins | None = None) -> list[str]:
    """What the pose q [rad, model angles] breaks, said in controller angles: experiment ranges,
    heights (naming the point), collisions (naming the capsules or box). With margins, the
    optimiser's margins count too (said apart from the limits the user set)."""
    q = np.asarray(q, dtype=float)
    lim, offsets = model.limits, model.controller_offsets
    dz = 0.0 if margins is None else margins.height
    dc = 0.0 if margins is None else margins.clearance
    out = range_violations(q + offsets, lim.q_min + offsets, lim.q_max + offsets, "experiment's")
    if model.heights is not None:
        z = np.asarray(model.heights(q)).ravel()
        for k in np.flatnonzero(z < model.z_min + dz):
            out.append(height_violation(model.point_names[0][k], float(z[k]), model.z_min, dz))
    if model.collision is not None:
        out += collision_violations(model.collision, q, dc)
    return out


def height_violation(point: str, z: float, z_min: float, extra: float) -> str:
    """A point at height z [m] below z_min + extra: z_min is the floor or mounting plane plus
    the margin the user set, ``extra`` [m] the optimiser's own further margin."""
    further = f" (the optimiser keeps a further {extra:g} m)" if extra > 0.0 else ""
    if z < z_min:
        return f"{point} at z = {z:.4f} m, below the lowest allowed z = {z_min:.4f} m{further}"
    return (f"{point} at z = {z:.4f} m, less than the optimiser's further {extra:g} m above the lowest "
            f"allowed z = {z_min:.4f} m")


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
    with np.errstate(invalid="ignore"):  # a joint without position limits: inf - inf
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
        c = evaluate_samples(model.collision.clearance, q)
        if np.min(c) < margins.clearance:
            return False
    return True
