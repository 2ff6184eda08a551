"""A Pinocchio model built from the same Khalil-Kleinfinger table (independent oracle).

Pinocchio is only imported here, lazily, so the symbolic model does not depend on it.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from .geometry import exact_trig
from .parameters import LINK_PARAMETERS

if TYPE_CHECKING:  # for annotations only
    from .description import Robot

# Pinocchio's dynamic parameters per body: m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz (about
# the joint frame origin), matching our XX XY XZ YY YZ ZZ MX MY MZ M through this order.
PINOCCHIO_ORDER: tuple[str, ...] = ("M", "MX", "MY", "MZ", "XX", "XY", "YY", "XZ", "YZ", "ZZ")


def _placement(alpha: float, d: float, theta: float, r: float) -> Any:
    import pinocchio as pin

    ca_, sa = exact_trig(alpha)
    ct, st = exact_trig(theta)
    Rx = np.array([[1, 0, 0], [0, ca_, -sa], [0, sa, ca_]])
    Rz = np.array([[ct, -st, 0], [st, ct, 0], [0, 0, 1]])
    R = Rx @ Rz
    p = np.array([d, -sa * r, ca_ * r])
    return pin.SE3(R, p)


def pinocchio_model(robot: Robot, chi: Sequence[float] | None = None) -> Any:
    """pinocchio.Model of the robot's rigid-body chain, with link inertias from chi if given.

    Joint j is a revolute (RZ) or prismatic (PZ) joint placed at Rot(x, alpha) Trans(x, d)
    Rot(z, theta) Trans(z, r): Rot(z, q) and Trans(z, r) commute, so the KK transform at q is
    placement * joint motion. Gravity is robot.gravity_vector (in frame 0).
    """
    import pinocchio as pin

    model = pin.Model()
    model.gravity.linear[:] = robot.gravity_vector
    parent = 0
    for j in range(robot.n):
        joint = pin.JointModelRZ() if robot.sigma[j] == 0 else pin.JointModelPZ()
        placement = _placement(robot.alpha[j], robot.d[j], robot.theta[j], robot.r[j])
        parent = model.addJoint(parent, joint, placement, f"joint{j + 1}")
        model.appendBodyToJoint(parent, pin.Inertia.Zero(), pin.SE3.Identity())
    if chi is not None:
        set_inertias(model, robot, chi)
    return model


def link_dynamic_parameters(robot: Robot, chi: Sequence[float], link: int) -> np.ndarray:
    """Pinocchio's 10 dynamic parameters of link ``link`` (0-based) from the standard chi."""
    k = len(LINK_PARAMETERS)
    block = {p: float(chi[k * link + i]) for i, p in enumerate(LINK_PARAMETERS)}
    return np.array([block[p] for p in PINOCCHIO_ORDER])


def set_inertias(model: Any, robot: Robot, chi: Sequence[float]) -> None:
    """Write every link's inertia from chi into a Pinocchio model."""
    import pinocchio as pin

    for j in range(robot.n):
        model.inertias[j + 1] = pin.Inertia.FromDynamicParameters(link_dynamic_parameters(robot, chi, j))


def pinocchio_columns(robot: Robot) -> np.ndarray:
    """Index of each Pinocchio regressor column in robot.parameter_names (shape 10 n)."""
    names = list(robot.parameter_names)
    return np.array([names.index(f"{p}{j + 1}") for j in range(robot.n) for p in PINOCCHIO_ORDER])
