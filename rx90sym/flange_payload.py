"""A payload in the controller's form: mass, centre of gravity and inertia at it, in the maker's
tool-flange frame; and the lines a UR or Franka controller takes.

The toolkit identifies a payload as ten parameters XXc..Mc in the payload frame (frame n of a
robot file, the tip link of a URDF robot) about its origin. Controllers want (Universal Robots'
``set_target_payload(m, cog, inertia)``, Franka's ``setLoad(mass, F_x_Cload, load_inertia)``):

- mass [kg];
- centre of gravity [m] in the tool-flange frame (rx90sym.model_export.flange_pose);
- inertia [kg m^2] about the centre of gravity, in the flange frame's axes.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .description import Robot
from .model_export import payload_in_flange
from .rigid_body import RigidBody, physical_problem

__all__ = ["FlangePayload", "controller_family", "flange_payload", "franka_load", "ur_script"]


@dataclass(frozen=True, eq=False)
class FlangePayload:
    """mass [kg], cog (3,) [m] and inertia (3, 3) [kg m^2] at the CoG, flange axes; robot: the
    robot's name; frame: which flange; problem: why it is not a physical body (None if it is)."""

    robot: str
    frame: str
    mass: float
    cog: np.ndarray
    inertia: np.ndarray
    problem: str | None

    def inertia_list(self) -> list[float]:
        """[Ixx, Iyy, Izz, Ixy, Ixz, Iyz] (UR's order)."""
        I = self.inertia
        return [float(I[0, 0]), float(I[1, 1]), float(I[2, 2]), float(I[0, 1]), float(I[0, 2]), float(I[1, 2])]

    def to_dict(self) -> dict[str, Any]:
        return {"robot": self.robot, "frame": self.frame, "mass_kg": self.mass,
                "cog_m": [float(x) for x in self.cog], "inertia_at_cog_kg_m2": self.inertia_list(),
                "inertia_order": ["Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz"],
                "physical": self.problem is None, "problem": self.problem}

    @classmethod
    def from_dict(cls, d: Any, where: str = "payload JSON") -> "FlangePayload":
        """The block written by :meth:`to_dict`; ValueError naming the field otherwise."""
        if not isinstance(d, Mapping):
            raise ValueError(f"{where}: 'flange' must be an object (the payload in the flange frame)")
        try:
            mass = float(d["mass_kg"])
            cog = np.array([float(x) for x in d["cog_m"]])
            xx, yy, zz, xy, xz, yz = (float(x) for x in d["inertia_at_cog_kg_m2"])
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"{where}: 'flange' lacks or mangles {exc} (mass_kg, cog_m, "
                             f"inertia_at_cog_kg_m2)") from None
        if cog.shape != (3,) or not np.all(np.isfinite([mass, *cog, xx, yy, zz, xy, xz, yz])):
            raise ValueError(f"{where}: 'flange' needs a finite mass, 3 CoG and 6 inertia numbers")
        I = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        problem = _problem(mass, I)
        return cls(str(d.get("robot", "")), str(d.get("frame", "")), mass, cog, I, problem)


def _problem(mass: float, I: np.ndarray) -> str | None:
    if not mass > 0:
        return f"mass {mass:g} kg is not > 0"
    return physical_problem(RigidBody.from_com(mass, np.zeros(3), np.eye(3), I))


def flange_payload(robot: Robot, payload: Mapping[str, float]) -> FlangePayload:
    """The payload (XXc..Mc in the payload frame) in the flange frame of ``robot``."""
    body = payload_in_flange(robot, payload)
    frame = ("the URDF tip link" if robot.urdf is not None else
             "the robot file's [flange]" if robot.flange is not None else "frame n (the robot file has no [flange])")
    if body.m <= 0:
        return FlangePayload(robot.name, frame, float(body.m), np.zeros(3), np.zeros((3, 3)),
                             f"mass {body.m:g} kg is not > 0")
    cog, I = body.com_inertia()
    return FlangePayload(robot.name, frame, float(body.m), cog, I, _problem(float(body.m), I))


def controller_family(robot_name: str) -> str | None:
    """The controller whose payload form a robot takes, told by its name: "ur" (ur3, ur5e, ur10e,
    ...), "franka" (panda, fr3), "staubli" (rx.., tx..), None when the name does not tell."""
    name = robot_name.strip().lower()
    if re.match(r"ur\d", name):
        return "ur"
    if name.startswith(("panda", "fr3", "franka")):
        return "franka"
    if re.match(r"(rx|tx)\d", name) or name.startswith("staubli"):
        return "staubli"
    return None


def _checked(p: FlangePayload, family: str) -> None:
    # The flange frame is the robot's own: another maker's controller would read it in its frame.
    known = controller_family(p.robot)
    if known is not None and known != family:
        raise ValueError(f"the payload was identified on robot '{p.robot}' (a {known} controller): it is not "
                         f"in the form or the flange frame of a {family} controller")
    if p.problem is not None:
        raise ValueError(f"the payload is not a physical rigid body ({p.problem}); identify it with the "
                         f"constrained fit (pseudo-inertia positive semidefinite)")


def ur_script(p: FlangePayload) -> str:
    """URScript: ``set_target_payload(m, [cx, cy, cz], [Ixx, Iyy, Izz, Ixy, Ixz, Iyz])`` (UR's
    e-Series; mass kg, CoG m from the tool flange, inertia kg m^2 at the CoG in flange axes)."""
    _checked(p, "ur")
    cog = ", ".join(repr(float(x)) for x in p.cog)
    inertia = ", ".join(repr(x) for x in p.inertia_list())
    return f"set_target_payload({float(p.mass)!r}, [{cog}], [{inertia}])\n"


def franka_load(p: FlangePayload) -> dict[str, Any]:
    """Franka's load, as libfranka's ``Robot::setLoad(load_mass, F_x_Cload, load_inertia)`` takes
    it: mass [kg], CoG [m] in the flange frame F, inertia [kg m^2] at the CoG, 3x3 column-major."""
    _checked(p, "franka")
    return {"load_mass": float(p.mass), "F_x_Cload": [float(x) for x in p.cog],
            "load_inertia": [float(x) for x in p.inertia.T.reshape(-1)],
            "note": "libfranka Robot::setLoad(load_mass, F_x_Cload, load_inertia); inertia about the CoG, "
                    "column-major, flange frame F"}
