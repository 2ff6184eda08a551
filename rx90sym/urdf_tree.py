"""A URDF file read into plain data: links with their inertials, joints, the kinematic tree.

Only what the dynamic model needs is read (inertials, joint placements, axes, limits,
dynamics); every error names the file and the element (link or joint) at fault.
"""
from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .rigid_body import RigidBody
from .urdf_snap import SNAP_LENGTH_M, SNAP_RAD, change_line, check_tolerances, rpy_rotation, snap_origin

MOVABLE = ("revolute", "continuous", "prismatic")
JOINT_TYPES = MOVABLE + ("fixed", "floating", "planar")
# Rotation entries this close to 0 or +-1 are made exact by rpy_matrix (the collision geometry's
# frames). Joint origins are snapped by rx90sym.urdf_snap (tolerances snap, snap_length).
SNAP = 1e-9


_EPS = 1e-12  # round-off of the frame construction (lengths in m, cosines)

Pose = tuple[np.ndarray, np.ndarray]  # (R, p): a frame's axes and origin in another frame


class UrdfError(ValueError):
    """A URDF that cannot be used; the message names the file and the element."""


@dataclass(frozen=True, eq=False)
class UrdfJoint:
    name: str
    type: str
    parent: str
    child: str
    R: np.ndarray          # origin rotation (child joint frame in parent link frame)
    p: np.ndarray          # origin translation [m]
    axis: np.ndarray       # unit axis in the joint frame
    lower: float | None
    upper: float | None
    effort: float | None
    velocity: float | None
    damping: float
    friction: float
    mimic: bool


@dataclass(frozen=True, eq=False)
class UrdfTree:
    path: str
    name: str
    text: str
    links: tuple[str, ...]
    inertials: dict[str, RigidBody]     # link -> its own body in its frame (absent: no inertial)
    joints: dict[str, UrdfJoint]
    parent_joint: dict[str, str]        # child link -> joint
    root: str
    snap: float = SNAP_RAD              # joint origin tolerances used [rad], [m] (rx90sym.urdf_snap)
    snap_length: float = SNAP_LENGTH_M
    snapped: tuple[str, ...] = ()       # the joint origins changed: 'joint NAME: written -> used'

    def children(self, link: str) -> list[UrdfJoint]:
        return [j for j in self.joints.values() if j.parent == link]

    def path_from_root(self, link: str) -> list[UrdfJoint]:
        """Joints from the root down to ``link``."""
        out = []
        while link in self.parent_joint:
            j = self.joints[self.parent_joint[link]]
            out.append(j)
            link = j.parent
        return out[::-1]


def rpy_matrix(r: float, p: float, y: float, snap: float = SNAP) -> np.ndarray:
    """URDF fixed-axis roll-pitch-yaw: R = Rz(y) Ry(p) Rx(r), entries within ``snap`` of 0, +-1
    made exact."""
    return snap_rotation(rpy_rotation((r, p, y)), snap)


def snap_rotation(R: np.ndarray, snap: float = SNAP) -> np.ndarray:
    """Entries within ``snap`` of 0, +-1 made exact when the result stays a rotation (to 1e-12)."""
    S = R.copy()
    for v in (0.0, 1.0, -1.0):
        S[np.abs(S - v) < snap] = v
    if np.abs(S.T @ S - np.eye(3)).max() < 1e-12:
        return S
    return R


def _floats(elem: ET.Element, attr: str, count: int, where: str, default: list[float]) -> list[float]:
    if elem is None or attr not in elem.attrib:
        return list(default)
    try:
        vals = [float(x) for x in elem.attrib[attr].split()]
    except ValueError:
        vals = []
    if len(vals) != count or not all(math.isfinite(v) for v in vals):
        raise UrdfError(f"{where}: <{elem.tag} {attr}=\"{elem.attrib[attr]}\"> needs {count} finite number{'s' if count > 1 else ''}")
    return vals


def _number(elem: ET.Element | None, attr: str, where: str) -> float | None:
    if elem is None or attr not in elem.attrib:
        return None
    return _floats(elem, attr, 1, where, [])[0]


def _origin(elem: ET.Element, where: str, snap: float = SNAP) -> tuple[np.ndarray, np.ndarray]:
    o = elem.find("origin")
    xyz = _floats(o, "xyz", 3, where, [0.0, 0.0, 0.0])
    rpy = _floats(o, "rpy", 3, where, [0.0, 0.0, 0.0])
    return rpy_matrix(*rpy, snap=snap), np.array(xyz)


def _inertial(link: ET.Element, where: str) -> RigidBody | None:
    el = link.find("inertial")
    if el is None:
        return None
    where = f"{where} <inertial>"
    m = _number(el.find("mass"), "value", where)
    if m is None:
        raise UrdfError(f"{where}: missing <mass value=...>")
    iel = el.find("inertia")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    vals = {k: (_number(iel, k, where) or 0.0) for k in keys}
    I = np.array([[vals["ixx"], vals["ixy"], vals["ixz"]], [vals["ixy"], vals["iyy"], vals["iyz"]],
                  [vals["ixz"], vals["iyz"], vals["izz"]]])
    R, c = _origin(el, where)
    return RigidBody.from_com(m, c, R, I)


def read_urdf(path: str | Path, snap: float = SNAP_RAD, snap_length: float = SNAP_LENGTH_M) -> UrdfTree:
    """Parse and check a URDF: one root, a tree (no link with two parents, no loop), known links.

    snap [rad], snap_length [m]: joint origin angles this close to a multiple of pi/2 and lengths
    this close to 0 are made exact (rx90sym.urdf_snap; snap 0 turns both off); one warning lists
    every change (joint, written, used)."""
    check_tolerances(snap, snap_length)
    if snap == 0:
        snap_length = 0.0
    path = Path(path)
    text, root_el = _robot_element(path)
    links, inertials = _links(root_el, path)
    joints: dict[str, UrdfJoint] = {}
    parent_joint: dict[str, str] = {}
    changes: list[str] = []
    would: list[str] = []  # snap 0: what the default tolerances would change
    for el in root_el.findall("joint"):
        joint, change = _joint(el, path, links, joints, parent_joint, snap, snap_length)
        joints[joint.name] = joint
        parent_joint[joint.child] = joint.name
        (would if snap == 0 else changes).extend([change] if change else [])
    if not links:
        raise UrdfError(f"{path}: no <link>")
    if changes:
        warnings.warn(f"{path}: {len(changes)} joint origin(s) snapped to right angles (within {snap:g} rad) "
                      f"and zero lengths (within {snap_length:g} m), written -> used: " + "; ".join(changes)
                      + " (snap=0 in Python, --snap 0 on the command line, keeps them as written)", stacklevel=3)
    if would:
        warnings.warn(f"{path}: snapping off (snap=0): joint origins kept as written, {len(would)} of them "
                      f"within {SNAP_RAD:g} rad of a right angle or {SNAP_LENGTH_M:g} m of zero: "
                      + "; ".join(w.split(":")[0] for w in would), stacklevel=3)
    root = _single_root(path, links, joints, parent_joint)
    return UrdfTree(str(path), root_el.attrib.get("name", path.stem), text, tuple(links),
                    inertials, joints, parent_joint, root, snap, snap_length, tuple(changes))


def _robot_element(path: Path) -> tuple[str, ET.Element]:
    """The file's text and its <robot> element."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise UrdfError(f"{path}: cannot read URDF ({exc.strerror or exc})") from None
    try:
        root_el = ET.fromstring(text)
    except ET.ParseError as exc:
        raise UrdfError(f"{path}: not valid XML ({exc})") from None
    if root_el.tag != "robot":
        raise UrdfError(f"{path}: the top element is <{root_el.tag}>, not <robot> (not a URDF)")
    return text, root_el


def _links(root_el: ET.Element, path: Path) -> tuple[list[str], dict[str, RigidBody]]:
    """The link names in file order and the inertials of those that have one."""
    links: list[str] = []
    inertials: dict[str, RigidBody] = {}
    for el in root_el.findall("link"):
        name = el.attrib.get("name")
        if not name:
            raise UrdfError(f"{path}: a <link> has no name")
        if name in links:
            raise UrdfError(f"{path}: link {name!r} is defined twice")
        links.append(name)
        body = _inertial(el, f"{path}: link {name!r}")
        if body is not None:
            inertials[name] = body
    return links, inertials


def _joint(el: ET.Element, path: Path, links: list[str], joints: dict[str, UrdfJoint],
           parent_joint: dict[str, str], snap: float, snap_length: float) -> tuple[UrdfJoint, str]:
    """One <joint>, checked against the links and the joints read before it, and its origin's
    change ('' if none; snap 0: what the default tolerances would change)."""
    name = el.attrib.get("name")
    where = f"{path}: joint {name!r}"
    if not name:
        raise UrdfError(f"{path}: a <joint> has no name")
    if name in joints:
        raise UrdfError(f"{where} is defined twice")
    jtype = el.attrib.get("type")
    if jtype not in JOINT_TYPES:
        raise UrdfError(f"{where}: unknown type {jtype!r} (expected one of {list(JOINT_TYPES)})")
    ends = {}
    for tag in ("parent", "child"):
        e = el.find(tag)
        ends[tag] = None if e is None else e.attrib.get("link")
        if ends[tag] is None:
            raise UrdfError(f"{where}: missing <{tag} link=...>")
        if ends[tag] not in links:
            raise UrdfError(f"{where}: {tag} link {ends[tag]!r} is not a <link> of the file")
    child = ends["child"]
    if child in parent_joint:
        raise UrdfError(f"{where}: link {child!r} is already the child of joint "
                        f"{parent_joint[child]!r}: the URDF has a loop (a URDF must be a tree)")
    o = el.find("origin")
    rpy, xyz = _floats(o, "rpy", 3, where, [0.0, 0.0, 0.0]), _floats(o, "xyz", 3, where, [0.0, 0.0, 0.0])
    origin = snap_origin(rpy, xyz, snap, snap_length)
    probe = origin if snap else snap_origin(rpy, xyz)
    change = change_line(name, rpy, xyz, probe) if probe.changed else ""
    axis = np.array(_floats(el.find("axis"), "xyz", 3, where, [1.0, 0.0, 0.0]))
    norm = float(np.linalg.norm(axis))
    if jtype in MOVABLE and norm < 1e-12:
        raise UrdfError(f"{where}: <axis> has zero length")
    axis = axis / norm if norm > 0 else axis
    limit, dyn = el.find("limit"), el.find("dynamics")
    return UrdfJoint(name, jtype, ends["parent"], child, origin.R, origin.p, axis,
                     _number(limit, "lower", where), _number(limit, "upper", where),
                     _number(limit, "effort", where), _number(limit, "velocity", where),
                     _number(dyn, "damping", where) or 0.0, _number(dyn, "friction", where) or 0.0,
                     el.find("mimic") is not None), change


def _single_root(path: Path, links: list[str], joints: dict[str, UrdfJoint], parent_joint: dict[str, str]) -> str:
    """The one root link; every link below it (no loop)."""
    roots = [l for l in links if l not in parent_joint]
    if not roots:
        raise UrdfError(f"{path}: every link has a parent joint: the URDF has a loop (no root link)")
    if len(roots) > 1:
        raise UrdfError(f"{path}: several root links {roots[:5]}: the links do not form one tree")
    # One root and one parent per link; a cycle elsewhere would leave links unreachable.
    seen, stack = {roots[0]}, [roots[0]]
    while stack:
        link = stack.pop()
        for j in joints.values():
            if j.parent == link and j.child not in seen:
                seen.add(j.child)
                stack.append(j.child)
    unreachable = [l for l in links if l not in seen]
    if unreachable:
        j = parent_joint[unreachable[0]]
        raise UrdfError(f"{path}: joint {j!r} closes a loop (link {unreachable[0]!r} is not below "
                        f"the root {roots[0]!r})")
    return roots[0]


def zero_poses(tree: UrdfTree) -> dict[str, Pose]:
    """Pose of every link frame in the root frame with every joint at 0."""
    poses: dict[str, Pose] = {tree.root: (np.eye(3), np.zeros(3))}
    stack = [tree.root]
    while stack:
        link = stack.pop()
        R, p = poses[link]
        for j in tree.children(link):
            poses[j.child] = (R @ j.R, p + R @ j.p)
            stack.append(j.child)
    return poses


def _clean(v: np.ndarray) -> np.ndarray:
    """Round-off of the frame construction removed: entries within _EPS of 0, +-1 made exact."""
    v = np.array(v, dtype=float)
    for target in (0.0, 1.0, -1.0):
        v[np.abs(v - target) < _EPS] = target
    return v


def relative_pose(a: Pose, b: Pose) -> Pose:
    """Pose of frame b in frame a (both given in a common frame)."""
    Ra, pa = a
    Rb, pb = b
    return _clean(Ra.T @ Rb), Ra.T @ (pb - pa)
