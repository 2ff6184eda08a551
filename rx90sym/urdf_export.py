"""URDF export of a robot with given standard parameters (any robot: URDF or robot file).

A URDF robot: the parameters (standard, Khalil frames) are transformed back into the URDF link
frames. A moving link that carries lumped children (a hand, fingers, fixed links) gets the given
body minus its children, which keep their own inertials: the written URDF reproduces the
torques, though the split between links is not unique. Each chain joint's <dynamics> gets the
viscous (damping) and Coulomb (friction) coefficients; everything else in the file is kept byte
for byte. A robot file: a generated URDF (rx90sym.urdf_generate). Rotor inertia, the coupled
wrist, offsets and the frames go into one companion JSON (rx90sym.model_export.companion).
"""
from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from .description import Robot
from .model_export import (checked_parameters, companion, companion_path, joint_terms, link_bodies,  # noqa: F401
                           parameter_vector, payload_body, write_model)
from .parameters import LINK_PARAMETERS
from .physical import body_problem
from .rigid_body import RigidBody
from .urdf_tree import zero_poses
from .urdf_carried import _children, carried_bodies  # noqa: F401  (carried_bodies: public here too)
from .urdf_generate import dynamics_xml, generated_urdf, gravity_note, inertial_xml
from .urdf_tree import UrdfError

_K = len(LINK_PARAMETERS)


def link_inertials(robot: Robot, params: Mapping[str, float] | Sequence[float]) -> dict[str, RigidBody]:
    """Body of each moving URDF link (its own frame, lumped children taken out), checked physical.

    Raises UrdfError naming the link when the body, or the body minus its children, is not a
    physical rigid body."""
    chain = _chain(robot)
    chi = parameter_vector(robot, params)
    poses = zero_poses(chain.tree)
    out = {}
    for k, link in enumerate(chain.links):
        whole = RigidBody.from_vector(chi[_K * k:_K * k + 10]).expressed_in_parent(*chain.link_to_khalil[k])
        problem = _problem(whole)
        if problem is not None:
            raise UrdfError(f"parameters of link {k + 1} (URDF link {link!r}): not a physical rigid "
                            f"body ({problem})")
        children = [c for c in chain.lumped[k] if c != link]
        own = whole - _children(chain, poses, k)
        problem = _problem(own)
        if problem is not None:
            raise UrdfError(f"URDF link {link!r}: the parameters of link {k + 1} minus the inertials "
                            f"of the links it carries {children} are not a physical rigid body "
                            f"({problem}); those links keep their own inertials")
        out[link] = own
    return out


def _problem(body: RigidBody) -> str | None:
    """rx90sym.physical.body_problem (margin 0: a massless body is allowed)."""
    return body_problem(body.vector())


def write_urdf(robot: Robot, params: Mapping[str, float] | Sequence[float], path: str | Path,
               payload: Mapping[str, float] | None = None) -> list[Path]:
    """Write the robot as a URDF with its links' inertials from ``params`` (standard parameters,
    name -> value or vector), each joint's ``<dynamics damping="FVj" friction="FSj">``, and the
    companion ``NAME.actuation.json`` (companion_path: rotor inertia, the coupled wrist, offsets,
    frames; rx90sym.model_export.companion).

    A URDF robot gets its own file back with only these elements changed (``<limit>`` stays its
    own); a robot file gets a generated URDF (rx90sym.urdf_generate) in the controller's angles.
    payload: the payload's ten parameters XXc..Mc in the payload frame (frame n; a URDF robot's
    tip link), added as a fixed ``payload`` link on the flange.
    Returns the paths written; nothing is written when a link is refused (UrdfError)."""
    return write_model(path, *urdf_export(robot, params, path, payload))


def urdf_export(robot: Robot, params: Mapping[str, float] | Sequence[float], path: str | Path,
                payload: Mapping[str, float] | None = None) -> tuple[str, dict]:
    """(URDF text, companion dict) that :func:`write_urdf` writes to ``path``; nothing written."""
    try:
        chi = checked_parameters(robot, params)
    except ValueError as exc:
        raise UrdfError(str(exc)) from None
    _, FV, FS = joint_terms(robot, chi)
    try:
        body = payload_body(robot, payload) if payload is not None else None
        if robot.urdf is None:
            text = generated_urdf(robot, link_bodies(robot, chi), FV, FS, body)
        else:
            text = _edited_urdf(robot, chi, FV, FS, body)
    except UrdfError:
        raise
    except ValueError as exc:
        raise UrdfError(str(exc)) from None
    try:
        ET.fromstring(text)
    except ET.ParseError as exc:  # pragma: no cover - a bug of the writers
        raise RuntimeError(f"write_urdf produced invalid XML ({exc})") from None
    notes = ["rotor inertia IAj: not in a URDF; add IAj q''j (Pinocchio: model.armature = IA)"]
    if robot.coupling is not None:
        notes.append("coupled wrist: the terms IA_b q''_a, IA_b q''_b, FVM, FSM of eqs. 17-18 are not in a URDF "
                     "(companion 'coupling', 'other')")
    notes += [n for n in (gravity_note(robot),) if n]
    side = companion(robot, chi, path, "urdf", notes)
    side["source_model"] = robot.urdf.path if robot.urdf is not None else (robot.source or None)
    return text, side


def _edited_urdf(robot: Robot, chi: np.ndarray, FV: np.ndarray, FS: np.ndarray,
                 payload: RigidBody | None) -> str:
    """The robot's own URDF text with the inertials, dynamics (and a payload link) replaced."""
    chain = _chain(robot)
    text = chain.tree.text
    for link, body in link_inertials(robot, chi).items():
        text = replace_inertial(text, link, body)
    for k, joint in enumerate(chain.joints):
        text = replace_dynamics(text, joint, FV[k], FS[k])
    if payload is not None:
        end = text.rfind("</robot>")
        block = (f'  <joint name="payload_joint" type="fixed">\n    <parent link="{chain.tip}"/>\n'
                 f'    <child link="payload"/>\n    <origin xyz="0 0 0" rpy="0 0 0"/>\n  </joint>\n'
                 f'  <link name="payload">\n    {inertial_xml(payload, "    ")}\n  </link>\n')
        text = text[:end] + block + text[end:]
    return text


def replace_dynamics(text: str, joint: str, damping: float, friction: float) -> str:
    """``text`` with the <dynamics> of ``<joint name=joint>`` replaced (or added)."""
    m = re.search(r"<joint\b[^>]*?\bname\s*=\s*([\"'])" + re.escape(joint) + r"\1[^>]*?>", text)
    end = re.compile(r"</joint\s*>").search(text, m.end()) if m is not None else None
    if m is None or end is None:
        raise UrdfError(f"joint {joint!r} not found in the URDF text")
    inner = text[m.end():end.start()]
    block = dynamics_xml(damping, friction)
    old = re.search(r"<dynamics\b[^>]*/>|<dynamics\b.*?</dynamics\s*>", inner, flags=re.S)
    if old is not None:
        inner = inner[:old.start()] + block + inner[old.end():]
    else:
        line_start = text.rfind("\n", 0, m.start()) + 1
        indent = re.match(r"[ \t]*", text[line_start:m.start()]).group(0)
        inner = inner.rstrip() + f"\n{indent}  {block}\n{indent}"
    return text[:m.end()] + inner + text[end.start():]


def replace_inertial(text: str, link: str, body: RigidBody) -> str:
    """``text`` with the <inertial> of ``<link name=link>`` replaced (or added) by ``body``."""
    m = re.search(r"<link\b[^>]*?\bname\s*=\s*([\"'])" + re.escape(link) + r"\1[^>]*?(/?)>", text)
    if m is None:
        raise UrdfError(f"link {link!r} not found in the URDF text")
    line_start = text.rfind("\n", 0, m.start()) + 1
    indent = re.match(r"[ \t]*", text[line_start:m.start()]).group(0)
    block = inertial_xml(body, indent + "  ")
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


def _chain(robot: Robot):
    if robot.urdf is None:
        raise ValueError(f"robot {robot.name!r} was not loaded from a URDF: nothing to write into")
    return robot.urdf
