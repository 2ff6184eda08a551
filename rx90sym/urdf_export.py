"""URDF export: the robot's URDF with each moving link's <inertial> replaced by given parameters.

The parameters (standard, Khalil frames) are transformed back into the URDF link frames. A moving
link that carries lumped children (a hand, fingers, fixed links) gets the given body minus its
children, which keep their own inertials: the written URDF reproduces the torques, though the
split between links is not unique. Everything else in the file is kept byte for byte. Rotor
inertia, friction (and coupling friction, torque offsets) go into a companion JSON.
"""
from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from .description import Robot
from .files import atomic_write, write_json
from .parameters import LINK_PARAMETERS
from .rigid_body import RigidBody, physical_problem
from .urdf import relative_pose, zero_poses
from .urdf_tree import UrdfError

_K = len(LINK_PARAMETERS)


def companion_path(path: str | Path) -> Path:
    """Where write_urdf puts rotor inertia and friction: ``NAME.urdf`` -> ``NAME.actuation.json``."""
    path = Path(path)
    return path.with_name(path.stem + ".actuation.json")


def link_inertials(robot: Robot, params: Mapping[str, float] | Sequence[float]) -> dict[str, RigidBody]:
    """Body of each moving URDF link (its own frame, lumped children taken out), checked physical.

    Raises UrdfError naming the link when the body, or the body minus its children, is not a
    physical rigid body."""
    chain = _chain(robot)
    chi = _vector(robot, params)
    poses = zero_poses(chain.tree)
    out = {}
    for k, link in enumerate(chain.links):
        whole = RigidBody.from_vector(chi[_K * k:_K * k + 10]).expressed_in_parent(*chain.link_to_khalil[k])
        problem = _problem(whole)
        if problem is not None:
            raise UrdfError(f"parameters of link {k + 1} (URDF link {link!r}): not a physical rigid "
                            f"body ({problem})")
        children = [c for c in chain.lumped[k] if c != link]
        own = whole
        for c in children:
            own = own - chain.tree.inertials[c].expressed_in_parent(*relative_pose(poses[link], poses[c]))
        problem = _problem(own)
        if problem is not None:
            raise UrdfError(f"URDF link {link!r}: the parameters of link {k + 1} minus the inertials "
                            f"of the links it carries {children} are not a physical rigid body "
                            f"({problem}); those links keep their own inertials")
        out[link] = own
    return out


def _problem(body: RigidBody) -> str | None:
    """physical_problem, except that a body with all parameters exactly 0 (massless) is allowed."""
    if body.m == 0 and not np.any(body.h) and not np.any(body.J):
        return None
    return physical_problem(body)


def write_urdf(robot: Robot, params: Mapping[str, float] | Sequence[float], path: str | Path) -> list[Path]:
    """Write the robot's URDF with the moving links' inertials from ``params`` (standard
    parameters, name -> value or vector) to ``path``, and IA/FS/FV to companion_path(path).

    Returns the paths written. Nothing is written when a link is refused (UrdfError)."""
    chain = _chain(robot)
    chi = _vector(robot, params)
    bodies = link_inertials(robot, chi)
    text = chain.tree.text
    for link, body in bodies.items():
        text = replace_inertial(text, link, body)
    try:
        ET.fromstring(text)
    except ET.ParseError as exc:  # pragma: no cover - a bug of replace_inertial
        raise RuntimeError(f"write_urdf produced invalid XML ({exc})") from None
    names = robot.parameter_names
    values = dict(zip(names, (float(x) for x in chi)))
    joints = {j: {p: values[f"{p}{k + 1}"] for p in ("IA", "FS", "FV")}
              for k, j in enumerate(chain.joints)}
    companion = {
        "robot": robot.name, "urdf": str(Path(path).name), "source_urdf": chain.path,
        "units": {"IA": "kg m^2 (or kg, prismatic), on the joint side",
                  "FS": "N m (or N)", "FV": "N m s/rad (or N s/m)"},
        "joints": joints,
        "other": {p: values[p] for p in names[_K * robot.n:]},  # coupling friction, offsets
    }
    out = Path(path)
    atomic_write(out, lambda fh: fh.write(text))
    return [out, write_json(companion_path(out), companion)]


def replace_inertial(text: str, link: str, body: RigidBody) -> str:
    """``text`` with the <inertial> of ``<link name=link>`` replaced (or added) by ``body``."""
    m = re.search(r"<link\b[^>]*?\bname\s*=\s*([\"'])" + re.escape(link) + r"\1[^>]*?(/?)>", text)
    if m is None:
        raise UrdfError(f"link {link!r} not found in the URDF text")
    line_start = text.rfind("\n", 0, m.start()) + 1
    indent = re.match(r"[ \t]*", text[line_start:m.start()]).group(0)
    block = _inertial_xml(body, indent + "  ")
    if m.group(2) == "/":  # <link name="x"/>
        opening = text[m.start():m.end() - 2].rstrip() + ">"
        return text[:m.start()] + f"{opening}\n{indent}  {block}\n{indent}</link>" + text[m.end():]
    end = re.compile(r"</link\s*>").search(text, m.end())
    if end is None:
        raise UrdfError(f"link {link!r}: no </link>")
    inner = text[m.end():end.start()]
    old = re.search(r"<inertial\b[^>]*/>|<inertial\b.*?</inertial\s*>", inner, flags=re.S)
    if old is not None:
        inner = inner[:old.start()] + block + inner[old.end():]
    else:
        inner = inner.rstrip() + f"\n{indent}  {block}\n{indent}"
    return text[:m.end()] + inner + text[end.start():]


def _inertial_xml(body: RigidBody, indent: str) -> str:
    if body.m > 0:
        c, I = body.com_inertia()
    else:
        c, I = np.zeros(3), np.zeros((3, 3))
    f = lambda x: repr(float(x)) if x != 0 else "0"  # noqa: E731 - shortest exact round trip
    return (f"<inertial>\n{indent}  <origin xyz=\"{f(c[0])} {f(c[1])} {f(c[2])}\" rpy=\"0 0 0\"/>\n"
            f"{indent}  <mass value=\"{f(body.m)}\"/>\n"
            f"{indent}  <inertia ixx=\"{f(I[0, 0])}\" ixy=\"{f(I[0, 1])}\" ixz=\"{f(I[0, 2])}\" "
            f"iyy=\"{f(I[1, 1])}\" iyz=\"{f(I[1, 2])}\" izz=\"{f(I[2, 2])}\"/>\n{indent}</inertial>")


def _chain(robot: Robot):
    if robot.urdf is None:
        raise ValueError(f"robot {robot.name!r} was not loaded from a URDF: nothing to write into")
    return robot.urdf


def _vector(robot: Robot, params: Mapping[str, float] | Sequence[float]) -> np.ndarray:
    if isinstance(params, Mapping):
        return robot.parameter_vector(dict(params), strict=True)
    chi = np.asarray(params, dtype=float)
    if chi.shape != (len(robot.parameter_names),):
        raise ValueError(f"params: expected {len(robot.parameter_names)} standard parameters of "
                         f"robot {robot.name!r}, got shape {chi.shape}")
    return chi
