"""The robot's own geometry for the safety envelope: mounting plane, tool point, link capsules.

Sources, in order:

- a robot file's ``[excitation]`` table (``mounting_plane_z`` [m, frame 0], ``tool_point`` [m,
  frame n], default the ``[flange]`` translation) and its ``[[capsules]]`` (``name``, ``frame`` j, end points ``a``, ``b`` [m, frame j],
  ``radius`` [m]);
- a URDF: the mounting plane is the root link's z = 0, the tool point the tip link's origin, and
  one capsule per ``<collision>`` element: a cylinder (or capsule) becomes the capsule of the same
  axis, length and radius; a sphere a capsule of zero length; a box the capsule along its longest
  side with the half diagonal of the other two as radius (it contains the box); a mesh, whose
  vertices are not read, the capsule from the link's origin to each child joint's origin,
  shortened by its radius at both ends, of radius ``mesh_radius`` (MESH_RADIUS = 0.04 m unless given);
- otherwise the segments between distinct frame origins (collision.arm_capsules), reported as such.

Every capsule is fixed in one Khalil frame j (0: the base); pairs on the same or adjacent
capsule-carrying links are not checked (a joint always touches its neighbours; links without
geometry are skipped, as MoveIt's adjacency does).
"""
from __future__ import annotations

import dataclasses
import tomllib
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from .collision import CapsuleSet, _segment_distance, arm_capsules

if TYPE_CHECKING:
    import rx90sym

MESH_RADIUS = 0.04  # [m] radius of the bounding capsule of a URDF mesh (vertices not read)
NEVER_DISTANCE = 0.06  # [m] pairs always farther apart than this in random poses: "never in collision"
NEVER_POSES = 3000


@dataclass(frozen=True)
class CapsuleSpec:
    """One capsule: segment a-b [m] fixed in Khalil frame ``frame`` (0: base), radius [m]."""

    name: str
    frame: int
    a: tuple[float, float, float]
    b: tuple[float, float, float]
    radius: float


@dataclass(frozen=True)
class ArmGeometry:
    """mounting_z [m]: z in frame 0 of the plane the robot stands on; tool_point [m, frame n];
    capsules; source: where the capsules come from; mounting_source: where the plane comes from."""

    mounting_z: float
    tool_point: tuple[float, float, float]
    capsules: tuple[CapsuleSpec, ...]
    source: str
    mounting_source: str


def arm_geometry(robot: rx90sym.Robot, mesh_radius: float = MESH_RADIUS) -> ArmGeometry:
    """The geometry of ``robot`` (see the module docstring)."""
    if getattr(robot, "urdf", None) is not None:
        return _urdf_geometry(robot, mesh_radius)
    table: dict = {}
    capsules: list = []
    data: dict = {}
    path = Path(robot.source) if robot.source else None
    if path is not None and path.suffix == ".toml" and path.exists():
        data = tomllib.loads(path.read_text(encoding="utf-8"))
        table, capsules = data.get("excitation", {}), data.get("capsules", [])
    where = robot.source or robot.name
    specs = tuple(_spec(c, i, robot.n, where) for i, c in enumerate(capsules))
    flange = data.get("flange", {}).get("translation", (0.0, 0.0, 0.0)) if capsules or table else (0.0, 0.0, 0.0)
    tool = tuple(float(x) for x in table.get("tool_point", flange))
    if len(tool) != 3:
        raise ValueError(f"{where}: [excitation] tool_point needs 3 numbers [m, frame {robot.n}]")
    if "mounting_plane_z" in table:
        return ArmGeometry(float(table["mounting_plane_z"]), tool, specs,
                           f"{where} [[capsules]]" if specs else "segments between frame origins",
                           f"{where} [excitation] mounting_plane_z")
    return ArmGeometry(0.0, tool, specs, f"{where} [[capsules]]" if specs else
                       "segments between frame origins", "frame 0 (the robot file gives no mounting plane)")


def _spec(c: dict, index: int, n: int, where: str) -> CapsuleSpec:
    at = f"{where}: [[capsules]] number {index + 1}"
    try:
        frame, radius = int(c["frame"]), float(c["radius"])
        a, b = (tuple(float(x) for x in c[k]) for k in ("a", "b"))
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{at}: needs frame (0..{n}), a, b (3 numbers each, m) and radius (m): {exc}") from None
    if not 0 <= frame <= n or len(a) != 3 or len(b) != 3 or not radius > 0.0:
        raise ValueError(f"{at}: frame must be in 0..{n}, a and b 3 numbers, radius > 0")
    return CapsuleSpec(str(c.get("name", f"capsule {index + 1}")), frame, a, b, radius)  # type: ignore[arg-type]


def _pose_mul(a: tuple, b: tuple) -> tuple:
    return a[0] @ b[0], a[1] + a[0] @ b[1]


def _urdf_geometry(robot: rx90sym.Robot, mesh_radius: float) -> ArmGeometry:
    from rx90sym.urdf_tree import relative_pose, zero_poses
    from rx90sym.urdf_tree import rpy_matrix

    chain = robot.urdf
    tree = chain.tree
    poses = zero_poses(tree)
    khalil = [chain.root_to_frame0] + [_pose_mul(poses[link], chain.link_to_khalil[k])
                                       for k, link in enumerate(chain.links)]
    moving = {link: k + 1 for k, link in enumerate(chain.links)}
    specs = []
    for elem in ET.fromstring(tree.text).findall("link"):
        name = elem.get("name")
        if name not in poses:
            continue
        owner = name
        while owner not in moving and owner in tree.parent_joint:
            owner = tree.joints[tree.parent_joint[owner]].parent
        frame = moving.get(owner, 0)
        in_frame = relative_pose(khalil[frame], poses[name])  # this link in Khalil frame `frame`
        for c, col in enumerate(elem.findall("collision")):
            origin = col.find("origin")
            xyz = np.array([float(x) for x in (origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split()])
            rpy = [float(x) for x in (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()]
            pose = _pose_mul(in_frame, (rpy_matrix(*rpy), xyz))
            for a, b, r in _primitive(col.find("geometry"), tree, name, mesh_radius):
                specs.append(CapsuleSpec(f"{name}#{c + 1}" if c else name, frame,
                                         tuple(pose[0] @ a + pose[1]), tuple(pose[0] @ b + pose[1]), r))
    R0, p0 = chain.root_to_frame0
    mounting = float((R0.T @ (np.zeros(3) - p0))[2])  # root origin's z in frame 0
    tool = tuple(float(x) for x in chain.tip_in_frame_n[1])
    src = f"{Path(tree.path).name} <collision> elements"
    return ArmGeometry(mounting, tool, tuple(specs), src, f"{Path(tree.path).name} root link z = 0")


def _primitive(geometry: ET.Element | None, tree: object, link: str, mesh_radius: float
               ) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """(a, b, radius) in the collision element's frame for its geometry."""
    if geometry is None or len(geometry) == 0:
        return []
    g = geometry[0]
    if g.tag in ("cylinder", "capsule"):
        r, half = float(g.get("radius")), 0.5 * float(g.get("length"))
        return [(np.array([0, 0, -half]), np.array([0, 0, half]), r)]
    if g.tag == "sphere":
        return [(np.zeros(3), np.zeros(3), float(g.get("radius")))]
    if g.tag == "box":
        size = np.array([float(x) for x in g.get("size").split()])
        i = int(np.argmax(size))
        axis = np.eye(3)[i] * 0.5 * size[i]
        return [(-axis, axis, float(0.5 * np.linalg.norm(np.delete(size, i))))]
    # A mesh: the capsule between the link's origin and each child joint's origin, shortened by
    # its radius at both ends (the joint housings belong to both neighbours, which are not checked).
    out = []
    for p in [np.asarray(j.p, float) for j in tree.children(link)] or [np.zeros(3)]:  # type: ignore[attr-defined]
        length = float(np.linalg.norm(p))
        if length <= 2.0 * mesh_radius:
            out.append((0.5 * p, 0.5 * p, mesh_radius))
        else:
            u = p / length
            out.append((mesh_radius * u, p - mesh_radius * u, mesh_radius))
    return out


def capsule_set(robot: rx90sym.Robot, geometry: ArmGeometry) -> CapsuleSet:
    """CapsuleSet of the specs (segments in frame 0 as a function of q); pairs on the same or
    adjacent capsule-carrying links are left out. Without specs: collision.arm_capsules."""
    if not geometry.capsules:
        return arm_capsules(robot, tool_point=geometry.tool_point if any(geometry.tool_point) else (0.0, 0.0, 0.1))
    from rx90sym.geometry import frame_transforms

    q = ca.SX.sym("q", robot.n)
    frames = [(ca.SX.eye(3), ca.SX.zeros(3, 1))]
    for Rj, Pj in frame_transforms(robot, q):
        R, p = frames[-1]
        frames.append((ca.mtimes(R, Rj), p + ca.mtimes(R, Pj)))
    cols = []
    for s in geometry.capsules:
        R, p = frames[s.frame]
        cols += [p + ca.mtimes(R, ca.DM(s.a)), p + ca.mtimes(R, ca.DM(s.b))]
    links = sorted({s.frame for s in geometry.capsules})
    rank = [links.index(s.frame) for s in geometry.capsules]
    k = len(geometry.capsules)
    pairs = tuple((i, j) for i in range(k) for j in range(i + 1, k) if abs(rank[i] - rank[j]) > 1)
    caps = CapsuleSet(ca.Function("capsules", [q], [ca.horzcat(*cols)], ["q"], ["ends"]),
                      tuple(s.radius for s in geometry.capsules), tuple(s.name for s in geometry.capsules),
                      pairs, links=tuple(s.frame for s in geometry.capsules))
    return dataclasses.replace(caps, never=never_close(caps, robot.limits))


def never_close(capsules: CapsuleSet, limits: object, distance: float = NEVER_DISTANCE,
                poses: int = NEVER_POSES, seed: int = 0) -> tuple[tuple[int, int], ...]:
    """Pairs whose exact clearance stays above ``distance`` [m] over ``poses`` random poses in
    the joint ranges (clipped to +-pi): MoveIt's "never in collision" test. They are left out of
    the optimiser's ball cover (cheaper, and a cover inflated by up to 41 % of the radius would
    see such a pair closer than it is) but still checked exactly on every verified trajectory."""
    lo = np.clip(np.asarray(limits.q_min, float), -np.pi, np.pi)  # type: ignore[attr-defined]
    hi = np.clip(np.asarray(limits.q_max, float), -np.pi, np.pi)  # type: ignore[attr-defined]
    q = np.random.default_rng(seed).uniform(lo, hi, (poses, lo.size))
    ends = np.asarray(capsules.segments.map(poses, "serial")(q.T)).reshape(3, -1, poses, order="F")
    a, b = ends[:, 0::2, :], ends[:, 1::2, :]
    out = []
    for i, j in capsules.pairs:
        d = _segment_distance(a[:, i].T, b[:, i].T, a[:, j].T, b[:, j].T) - capsules.radii[i] - capsules.radii[j]
        if np.min(d) > distance:
            out.append((i, j))
    return tuple(out)
