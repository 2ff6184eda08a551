"""Forward dynamics of the model (solving the IDM for qdd, eqs. 1-5, 16-18), mass matrix, Coulomb terms."""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable

import casadi as ca
import numpy as np


if TYPE_CHECKING:  # for annotations only
    from .description import Robot


# --------------------------------------------------------------------------- plant model (SX)
def coulomb_torques(robot: Robot, qd: Any, chi: Any, sign: Callable[[Any], Any]) -> Any:
    """Coulomb terms of eq. 5 and eqs. 17-18 with a given sign function (SX) [N m]."""
    fs = robot.parameter_index([f"FS{j}" for j in range(1, robot.n + 1)])
    tau = [chi[fs[j]] * sign(qd[j]) for j in range(robot.n)]
    if robot.coupling is not None:
        a, b = robot.coupling.joints
        fsm = chi[robot.parameter_index([f"FSM{b + 1}"])[0]]
        if robot.coupling.coulomb_sign == "paper":
            tau[a] = tau[a] + fsm * sign(qd[b])   # eq. 17
            tau[b] = tau[b] + fsm * sign(qd[a])   # eq. 18
        else:
            s = sign(qd[a] + qd[b])
            tau[a], tau[b] = tau[a] + fsm * s, tau[b] + fsm * s
    return ca.vertcat(*tau)


def coulomb_mask(robot: Robot) -> np.ndarray:
    """1 for every parameter except the Coulomb ones (FSj, FSM): chi * mask has no Coulomb term."""
    mask = np.ones(len(robot.parameter_names))
    for i, p in enumerate(robot.parameter_names):
        if p.startswith("FS"):
            mask[i] = 0.0
    return mask


def mass_and_bias(robot: Robot, q: Any, qd: Any, chi: Any, sign: Callable[[Any], Any]) -> tuple[ca.SX, ca.SX]:
    """(M(q), b(q, qd)) with IDM = M qdd + b, Coulomb friction through ``sign`` (SX).

    The IDM is affine in qdd, so M = d IDM / d qdd is exact.
    """
    qdd = ca.SX.sym("qdd", robot.n)
    tau = robot.inverse_dynamics(q, qd, qdd, chi * coulomb_mask(robot)) + coulomb_torques(robot, qd, chi, sign)
    return ca.jacobian(tau, qdd), ca.substitute(tau, qdd, ca.SX.zeros(robot.n))


def _tanh_sign(smoothing: Any) -> Callable[[Any], Any]:
    return lambda v: ca.tanh(v / smoothing)


def forward_dynamics(robot: Robot, smoothing: float = 0.0) -> ca.Function:
    """casadi.Function (q, qd, tau, chi) -> qdd [rad/s^2] of the model, solving
    IDM(q, qd, qdd; chi) = tau (tau = everything applied at the joints: motors + spring).

    smoothing > 0 [rad/s]: Coulomb friction FS tanh(qd / smoothing) instead of FS sign(qd).
    """
    n = robot.n
    q, qd, u = (ca.SX.sym(s, n) for s in ("q", "qd", "tau"))
    chi = ca.SX.sym("chi", len(robot.parameter_names))
    M, bias = mass_and_bias(robot, q, qd, chi, _tanh_sign(smoothing) if smoothing > 0 else ca.sign)
    return ca.Function("forward_dynamics", [q, qd, u, chi], [ca.solve(M, u - bias)],
                       ["q", "qd", "tau", "chi"], ["qdd"])


def mass_matrix(robot: Robot) -> ca.Function:
    """casadi.Function (q, chi) -> M(q) (n x n) [kg m^2], rotor inertias and coupling included."""
    n = robot.n
    q, qd, qdd = (ca.SX.sym(s, n) for s in ("q", "qd", "qdd"))
    chi = ca.SX.sym("chi", len(robot.parameter_names))
    M = ca.jacobian(robot.inverse_dynamics(q, qd, qdd, chi), qdd)
    return ca.Function("mass_matrix", [q, chi], [M], ["q", "chi"], ["M"])
