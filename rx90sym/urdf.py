"""URDF import: the Khalil-Kleinfinger description of the chain from the URDF root to a tip link.

- Joint values, signs and zeros are the URDF's own: z_j is the URDF joint axis (its direction),
  and the table's theta_j (revolute) or r_j (prismatic) offsets are the URDF zero pose.
- The table comes from the joint axes at the zero pose: x_j on the common normal of z_j and
  z_j+1 (pointing from z_j to z_j+1); intersecting axes: x_j = z_j x z_j+1, origin at the
  intersection; parallel axes: the origin is the foot of x_j-1 on z_j (r_j = 0), or for the first
  joint the foot of the URDF root origin on z_1. Frame 0 is frame 1 at q = 0; frame n has
  x_n = x_n-1 and r_n = 0.
- Gravity is -9.81 m/s^2 along z of the URDF root, given to the model as a vector in frame 0
  (a tilted first axis makes MX1, MY1 identifiable).
- Links hanging rigidly on the chain (fixed joints, joints off the chain locked at 0: a hand,
  fingers) are lumped into the moving link they hang on, as Pinocchio's buildReducedModel does.
- The inertials are the description's prior, never a gate: those that are no physical rigid body
  load, named in one warning with the prior used instead (rx90sym.description_prior).
"""
from __future__ import annotations

import difflib
import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from .description import GRAVITY, Limits, Robot, robot_from_table
from .parameters import LINK_PARAMETERS
from .rigid_body import RigidBody
from .defaults import ACCELERATION_CAP, ACCELERATION_DEFAULT_TEXT, ACCELERATION_PER_VELOCITY
from .urdf_snap import SNAP_LENGTH_M, SNAP_RAD
from .urdf_tree import _EPS, MOVABLE, Pose, UrdfError, UrdfTree, _clean, read_urdf, relative_pose, zero_poses

# A URDF has no acceleration limits: min(ACCELERATION_PER_VELOCITY x the velocity limit, the cap) unless given
# (rx90sym.defaults; the commands that use limits, excite and simulate, say so).
DEFAULT_ACCELERATION = ACCELERATION_CAP  # rad/s^2, m/s^2: the ceiling


@dataclass(frozen=True, eq=False)
class UrdfChain:
    """How a Robot relates to its URDF (kept on ``Robot.urdf``).

    joints/links: the chain's movable joints and the URDF link moved by each;
    lumped[k]: the URDF links whose inertials make up moving link k (itself first if it has one);
    link_to_khalil[k]: pose of Khalil frame k+1 in URDF link ``links[k]``;
    root_to_frame0: pose of Khalil frame 0 in the URDF root link; tip_in_frame_n: pose of the
    tip link in Khalil frame n (the payload frame of a URDF robot is the tip frame);
    nominal: the standard parameters from the URDF (``urdf_parameters``).
    """

    tree: UrdfTree
    tip: str
    joints: tuple[str, ...]
    links: tuple[str, ...]
    lumped: tuple[tuple[str, ...], ...]
    link_to_khalil: tuple[Pose, ...]
    root_to_frame0: Pose
    tip_in_frame_n: Pose
    nominal: dict[str, float]

    @property
    def path(self) -> str:
        return self.tree.path

    @property
    def snap(self) -> float:
        """Angle tolerance [rad] the joint origins were snapped with (0: as written)."""
        return self.tree.snap

    @property
    def snap_length(self) -> float:
        """Length tolerance [m] the joint origins were snapped with (0: as written)."""
        return self.tree.snap_length


def assumed_acceleration(qd_max: Any, prismatic: Any) -> np.ndarray:
    """The acceleration limits assumed for a URDF joint [rad/s^2, m/s^2]: ACCELERATION_PER_VELOCITY x
    its velocity limit, at most ACCELERATION_CAP (the cap where no velocity limit is given)."""
    cap = np.array([ACCELERATION_CAP["prismatic" if p else "revolute"] for p in prismatic])
    qd = np.asarray(qd_max, dtype=float)
    return np.where(np.isfinite(qd), np.minimum(ACCELERATION_PER_VELOCITY * qd, cap), cap)


def default_acceleration(robot: Any) -> bool:
    """True when ``robot`` comes from a URDF and its acceleration limits are the assumed ones
    (:func:`assumed_acceleration`: a URDF gives none), not limits given with ``acceleration=``."""
    if getattr(robot, "urdf", None) is None:
        return False
    return bool(np.array_equal(robot.limits.qdd_max, assumed_acceleration(robot.limits.qd_max, robot.sigma)))


def acceleration_note(robot: Any) -> str | None:
    """What a command that uses the limits (excite, simulate) says once about a URDF's assumed
    accelerations, or None when they were given."""
    if not default_acceleration(robot):
        return None
    return (f"the URDF gives no acceleration limits: assumed {ACCELERATION_DEFAULT_TEXT}; give --acceleration "
            f"(Python: acceleration=) to set them")


def _unit(v: np.ndarray) -> np.ndarray:
    return _clean(v / np.linalg.norm(v))


def _perpendicular(z: np.ndarray, hint: np.ndarray | None) -> np.ndarray:
    """A unit vector normal to z: the hint made normal if possible, else a fixed choice."""
    for cand in ([hint] if hint is not None else []) + [np.array([1.0, 0, 0]), np.array([0, 1.0, 0])]:
        v = cand - (cand @ z) * z
        if np.linalg.norm(v) > 1e-6:
            return _unit(v)
    raise AssertionError("unreachable")


def khalil_frames(points: Sequence[np.ndarray], axes: Sequence[np.ndarray],
                  root_origin: np.ndarray) -> list[Pose]:
    """Frames 1..n (axes as columns x, y, z; origin) from the joint axis lines (point, unit
    direction) at the zero pose, by the rules of the module docstring."""
    n = len(axes)
    z = [_unit(a) for a in axes]
    origins: list[np.ndarray] = []
    xs: list[np.ndarray] = []
    foot = None  # foot of x_j-1 on axis j
    for j in range(n):
        if j == n - 1:
            O = foot if foot is not None else _foot(root_origin, points[j], z[j])
            x = xs[-1] if xs else _perpendicular(z[j], None)
            x = _perpendicular(z[j], x)
        else:
            p1, u1, p2, u2 = points[j], z[j], points[j + 1], z[j + 1]
            cross = np.cross(u1, u2)
            if np.linalg.norm(cross) < 1e-9:  # parallel axes: common normal through O_j
                O = foot if foot is not None else _foot(root_origin, p1, u1)
                f = _foot(O, p2, u2)
            else:
                w0 = p1 - p2
                b, dd, e = u1 @ u2, u1 @ w0, u2 @ w0
                den = 1.0 - b * b
                O = p1 + ((b * e - dd) / den) * u1
                f = p2 + ((e - b * dd) / den) * u2
            v = f - O
            if np.linalg.norm(cross) >= 1e-9:
                # skew or intersecting axes: the common normal is along u1 x u2, pointing to z_j+1
                # (f - O is a difference of nearly equal points when the axes almost meet)
                x = _unit(cross) if v @ cross >= 0 or np.linalg.norm(v) <= _EPS else -_unit(cross)
            elif np.linalg.norm(v) > _EPS:
                x = _unit(v)
            else:
                x = _perpendicular(z[j], xs[-1] if xs else None)  # coincident axes
            foot = f
        O = _clean(O)
        xs.append(x)
        origins.append(O)
    return [(np.column_stack([xs[j], _clean(np.cross(z[j], xs[j])), z[j]]), origins[j]) for j in range(n)]


def _foot(point: np.ndarray, p: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Foot of the perpendicular from ``point`` on the line (p, u)."""
    return p + ((point - p) @ u) * u


def _angle(c: float, s: float) -> float:
    a = math.atan2(s, c)
    for k in (-2, -1, 0, 1, 2):  # exact right angles for the structural zeros of the model
        if abs(a - k * math.pi / 2) < 1e-9:
            return k * math.pi / 2 if k != -2 else math.pi
    return a


def _length(v: float) -> float:
    return 0.0 if abs(v) < 1e-10 else float(v)


def khalil_table(frames: Sequence[Pose]) -> list[tuple[float, float, float, float]]:
    """(alpha, d, theta, r) of each joint from consecutive frames (frame 0 = frame 1 at q = 0)."""
    rows = [(0.0, 0.0, 0.0, 0.0)]
    for j in range(1, len(frames)):
        (Rp, Op), (R, O) = frames[j - 1], frames[j]
        xp, zp, x, z = Rp[:, 0], Rp[:, 2], R[:, 0], R[:, 2]
        alpha = _angle(zp @ z, np.cross(zp, z) @ xp)
        theta = _angle(xp @ x, np.cross(xp, x) @ z)
        v = O - Op
        d = v @ xp
        r = v @ z
        rows.append((alpha, _length(d), theta, _length(r)))
    return rows


def _check_table(path: str, rows: list, frames: Sequence[Pose], names: list[str]) -> None:
    """The table must rebuild the frames it came from (a guard on degenerate geometries)."""
    R, p = frames[0]
    for j in range(1, len(rows)):
        alpha, d, theta, r = rows[j]
        ca_, sa, ct, st = math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta)
        Rj = np.array([[1, 0, 0], [0, ca_, -sa], [0, sa, ca_]]) @ np.array([[ct, -st, 0], [st, ct, 0], [0, 0, 1]])
        p = p + R @ np.array([d, -sa * r, ca_ * r])
        R = R @ Rj
        if np.abs(R - frames[j][0]).max() > 1e-9 or np.abs(p - frames[j][1]).max() > 1e-9:
            raise RuntimeError(f"{path}: the Khalil table does not rebuild the frame of joint "
                               f"{names[j]!r} (a bug for this geometry; please report it)")


def load_urdf(path: str | Path, tip: str | None = None,
              acceleration: float | Sequence[float] | None = None, snap: float = SNAP_RAD,
              snap_length: float = SNAP_LENGTH_M) -> Robot:
    """Robot of the chain from the URDF root to link ``tip`` (default: the only leaf, if one).

    acceleration: joint acceleration limits [rad/s^2 or m/s^2] (a URDF has none); by default
    min(2 x the velocity limit, 10 rad/s^2) (:func:`assumed_acceleration`). snap [rad], snap_length [m]: joint origin angles within
    snap of a multiple of pi/2 and lengths within snap_length of 0 are made exact, each change
    listed in one warning (rx90sym.urdf_snap, docs/urdf.md; 1.5708 written for pi/2 otherwise
    leaves a near-singular model); snap=0 turns both off. Raises UrdfError naming the file and
    the element, ValueError for a tolerance out of range.
    """
    tree = read_urdf(path, snap, snap_length)
    tip = _check_tip(tree, tip)
    chain = tree.path_from_root(tip)
    for j in chain:
        if j.type in ("floating", "planar"):
            raise UrdfError(f"{tree.path}: joint {j.name!r} between the root and tip {tip!r} is "
                            f"{j.type}: only revolute, continuous, prismatic and fixed joints are supported")
        if j.type in MOVABLE and j.mimic:
            raise UrdfError(f"{tree.path}: joint {j.name!r} on the chain to {tip!r} is a <mimic> "
                            f"joint: not supported")
    movable = [j for j in chain if j.type in MOVABLE]
    if not movable:
        raise UrdfError(f"{tree.path}: no movable joint between the root {tree.root!r} and tip {tip!r}")
    poses = zero_poses(tree)
    points, axes = [], []
    for j in movable:
        R, p = poses[j.child]
        points.append(p)
        axes.append(R @ j.axis)
    frames = khalil_frames(points, axes, np.zeros(3))
    rows = khalil_table(frames)
    _check_table(tree.path, rows, frames, [j.name for j in movable])
    moving = [j.child for j in movable]
    lumped = _lumped(tree, moving)
    link_to_khalil = tuple(relative_pose(poses[link], frames[k]) for k, link in enumerate(moving))
    nominal = {}
    for k, links in enumerate(lumped):
        body = RigidBody.zero()
        for link in links:
            body = body + tree.inertials[link].expressed_in_parent(*poses[link])
        body = body.expressed_in_child(*frames[k])
        for name, value in zip(LINK_PARAMETERS[:10], body.vector()):
            nominal[f"{name}{k + 1}"] = float(value)
        nominal[f"IA{k + 1}"] = 0.0
        nominal[f"FS{k + 1}"] = movable[k].friction
        nominal[f"FV{k + 1}"] = movable[k].damping
    R0 = frames[0][0]
    g0 = _clean(R0.T @ np.array([0.0, 0.0, -1.0])) * GRAVITY
    gravity = GRAVITY if np.array_equal(g0, [0.0, 0.0, -GRAVITY]) else tuple(float(x) for x in g0)
    urdf = UrdfChain(tree, tip, tuple(j.name for j in movable), tuple(moving), lumped,
                     link_to_khalil, frames[0], relative_pose(frames[-1], poses[tip]), nominal)
    sigma = [1 if j.type == "prismatic" else 0 for j in movable]
    table = [(s, a, d, th, r) for s, (a, d, th, r) in zip(sigma, rows)]
    # The joint variable starts from the zero pose: prismatic offsets are r_j at q = 0.
    robot = robot_from_table(table, name=tree.name, limits=_limits(tree.path, movable, acceleration),
                             gravity=gravity, urdf=urdf, source=tree.path,
                             description=f"URDF {Path(tree.path).name}, root {tree.root!r} to tip {tip!r}")
    # The inertials are a prior, never a gate: those that are not physical are said once, with the prior used.
    from .description_prior import DescriptionWarning, description_warning

    said = description_warning(robot)
    if said:
        warnings.warn(said, DescriptionWarning, stacklevel=2)
    return robot


def urdf_parameters(robot: Robot) -> dict[str, float]:
    """The URDF's inertials as standard parameters (name -> value, Khalil frames, SI), lumped
    children included; IA = 0, FS = <dynamics friction>, FV = <dynamics damping>; OFF = 0."""
    if robot.urdf is None:
        raise ValueError(f"robot {robot.name!r} was not loaded from a URDF")
    out = dict(robot.urdf.nominal)
    return {p: out.get(p, 0.0) for p in robot.parameter_names}


def _check_tip(tree: UrdfTree, tip: str | None) -> str:
    if tip is None:
        leaves = [l for l in tree.links if not tree.children(l)]
        if len(leaves) == 1:
            return leaves[0]
        # Leaves that hang by fixed joints from one moving link (a maker's ee_link and tool0): one chain, the
        # same dynamics whichever is the tip (fixed children are carried by the moving link).
        end_of = {leaf: _last_moving_link(tree, leaf) for leaf in leaves}
        ends = set(end_of.values()) - {None}  # frames fixed to the base left out
        if len(ends) == 1:
            end = ends.pop()
            hanging = [leaf for leaf in leaves if end_of[leaf] == end]
            warnings.warn(f"{tree.path}: leaf links {hanging[:6]} hang by fixed joints from {end!r}: the "
                          f"chain ends there (the same model whichever of them ends it); give tip=LINK (--tip LINK) "
                          f"for a tool frame (the excitation's tool point, a payload's frame)", stacklevel=3)
            return end
        raise UrdfError(f"{tree.path}: several leaf links {leaves[:6]}: choose the chain's end "
                        f"with tip=LINK (--tip LINK)")
    if tip not in tree.links:
        close = difflib.get_close_matches(tip, tree.links, n=1)
        raise UrdfError(f"{tree.path}: tip link {tip!r} is not a <link> of the file"
                        + (f" (did you mean {close[0]!r}?)" if close else f" (links: {list(tree.links)[:8]})"))
    if tip == tree.root:
        raise UrdfError(f"{tree.path}: tip {tip!r} is the root link: it is not below the root "
                        f"(no joint between them)")
    return tip


def _last_moving_link(tree: UrdfTree, link: str) -> str | None:
    """The child link of the last movable joint on the path from the root to ``link`` (None: none)."""
    moving = [j for j in tree.path_from_root(link) if j.type in MOVABLE]
    return moving[-1].child if moving else None


def _lumped(tree: UrdfTree, moving: list[str]) -> tuple[tuple[str, ...], ...]:
    """Links with an inertial carried by each moving link (rigidly, or off the chain at q = 0)."""
    owned: list[list[str]] = [[] for _ in moving]
    index = {link: k for k, link in enumerate(moving)}
    for link in tree.links:
        if link not in tree.inertials:
            continue
        up = link
        while up not in index and up in tree.parent_joint:
            up = tree.joints[tree.parent_joint[up]].parent
        if up in index:
            owned[index[up]].append(link)
    for k, link in enumerate(moving):
        if link in owned[k]:
            owned[k].remove(link)
            owned[k].insert(0, link)
    return tuple(tuple(o) for o in owned)


def _limits(path: str, joints: list, acceleration: float | Sequence[float] | None) -> Limits:
    n = len(joints)
    inf = np.inf

    def value(x: float | None, default: float) -> float:
        return default if x is None else x

    q_min = np.array([-inf if j.type == "continuous" else value(j.lower, -inf) for j in joints])
    q_max = np.array([inf if j.type == "continuous" else value(j.upper, inf) for j in joints])
    open_ended = [j.name for j in joints if j.type == "revolute" and (j.lower is None or j.upper is None)]
    if open_ended:  # one line for all (a maker's continuous joints written as revolute)
        warnings.warn(f"{path}: revolute joint(s) {', '.join(repr(name) for name in open_ended)} without <limit lower "
                      f"upper>: no position limit (read as continuous)", stacklevel=3)
    for j, lo, hi in zip(joints, q_min, q_max):
        if lo > hi:
            raise UrdfError(f"{path}: joint {j.name!r}: <limit lower> {lo:g} > upper {hi:g}")
    # URDF: velocity/effort <= 0 or absent means no limit given.
    qd = np.array([j.velocity if j.velocity and j.velocity > 0 else inf for j in joints])
    tau = np.array([j.effort if j.effort and j.effort > 0 else inf for j in joints])
    if acceleration is None:  # no warning here: excite and simulate, which use the limits, say it once
        qdd = assumed_acceleration(qd, [j.type == "prismatic" for j in joints])
    else:
        given = np.atleast_1d(np.asarray(acceleration, dtype=float))
        if given.size not in (1, n):
            raise ValueError(f"{path}: acceleration limits: expected 1 or {n} numbers (one per joint of "
                             f"the chain), got {given.size}")
        qdd = np.broadcast_to(given.ravel(), (n,)).copy()
        if np.any(~np.isfinite(qdd)) or np.any(qdd <= 0):
            raise ValueError(f"acceleration limits must be finite and > 0, got {acceleration!r}")
    return Limits(q_min, q_max, qd, qdd, tau)


def payload_matrix(robot: Robot) -> np.ndarray:
    """T (10 x 10) with payload parameters in frame n = T @ payload parameters in the tip frame
    (PAYLOAD_NAMES order: XXc..ZZc about the frame origin, MXc MYc MZc, Mc). The payload frame of
    a URDF robot is its tip link; for any other robot it is frame n and T is the identity."""
    if robot.urdf is None:
        return np.eye(10)
    R, p = robot.urdf.tip_in_frame_n
    # The frame change is linear in (J, h, m): its matrix, column by column.
    return np.column_stack([RigidBody.from_vector(e).expressed_in_parent(R, p).vector() for e in np.eye(10)])


def payload_in_tip_frame(robot: Robot, values: np.ndarray, covariance: np.ndarray | None = None
                         ) -> tuple[np.ndarray, np.ndarray | None]:
    """Payload parameters estimated in frame n -> (values, std) in the payload frame (the tip
    link of a URDF robot; unchanged otherwise); std from the (10 x 10) covariance if given."""
    Tinv = np.linalg.inv(payload_matrix(robot))
    values = Tinv @ np.asarray(values, dtype=float)
    std = None if covariance is None else np.sqrt(np.maximum(np.diag(Tinv @ covariance @ Tinv.T), 0.0))
    return values, std
