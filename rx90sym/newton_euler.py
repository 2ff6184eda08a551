"""Symbolic Newton-Euler inverse dynamic model (eq. 1) and its regressor (eq. 2), in CasADi SX.

Khalil's recursive formulation with the inertia and first moments of each link expressed about
the origin of its own frame, which keeps the model linear in the standard parameters (eq. 4).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Sequence

import casadi as ca

from .geometry import frame_transforms
from .parameters import LINK_PARAMETERS

if TYPE_CHECKING:  # for annotations only
    from .description import Robot


@dataclass(frozen=True)
class Body:
    """Inertial parameters of one body about its frame origin, in its frame (SX or numbers)."""

    J: ca.SX   # 3x3 inertia
    ms: ca.SX  # 3 first moments MX, MY, MZ
    m: Any     # mass


def body_from_vector(p: Any) -> Body:
    """Body from XX XY XZ YY YZ ZZ MX MY MZ M (the first ten of eq. 4)."""
    XX, XY, XZ, YY, YZ, ZZ, MX, MY, MZ, M = (p[i] for i in range(10))
    J = ca.vertcat(ca.horzcat(XX, XY, XZ), ca.horzcat(XY, YY, YZ), ca.horzcat(XZ, YZ, ZZ))
    return Body(ca.SX(J), ca.SX(ca.vertcat(MX, MY, MZ)), M)


def rigid_body_torques(robot: Robot, q: ca.SX, qd: ca.SX, qdd: ca.SX, bodies: Sequence[Body],
                       gravity: Sequence[float]) -> ca.SX:
    """Joint torques of the rigid-body chain (no friction, rotor inertia or coupling).

    gravity: the gravity acceleration in frame 0 (3-vector, e.g. (0, 0, -g)); it is introduced
    as the base acceleration -gravity.
    """
    n = robot.n
    z = ca.SX([0, 0, 1])
    w = ca.SX.zeros(3, 1)
    wd = ca.SX.zeros(3, 1)
    vd = ca.SX([0.0 - float(x) for x in gravity])  # 0.0 - 0.0 is +0: structural zeros stay
    U_prev = ca.SX.zeros(3, 3)
    transforms = frame_transforms(robot, q)
    forces, moments = [], []
    for j in range(n):
        R, P = transforms[j]
        Rt = R.T
        w_in = ca.mtimes(Rt, w)
        wd_in = ca.mtimes(Rt, wd)
        vd = ca.mtimes(Rt, vd + ca.mtimes(U_prev, P))
        if robot.sigma[j] == 0:
            w = w_in + qd[j] * z
            wd = wd_in + qdd[j] * z + qd[j] * ca.cross(w_in, z)
        else:
            w, wd = w_in, wd_in
            vd = vd + qdd[j] * z + 2 * qd[j] * ca.cross(w_in, z)
        U = ca.skew(wd) + ca.mtimes(ca.skew(w), ca.skew(w))
        b = bodies[j]
        forces.append(b.m * vd + ca.mtimes(U, b.ms))
        moments.append(ca.mtimes(b.J, wd) + ca.cross(w, ca.mtimes(b.J, w)) + ca.cross(b.ms, vd))
        U_prev = U
    tau = []
    f = ca.SX.zeros(3, 1)
    m = ca.SX.zeros(3, 1)
    for j in reversed(range(n)):
        if j < n - 1:
            R, P = transforms[j + 1]
            f_next = ca.mtimes(R, f)
            m = moments[j] + ca.mtimes(R, m) + ca.cross(P, f_next)
            f = forces[j] + f_next
        else:
            f, m = forces[j], moments[j]
        tau.append(f[2] if robot.sigma[j] == 1 else m[2])
    return ca.vertcat(*reversed(tau))


def actuation_torques(robot: Robot, qd: ca.SX, qdd: ca.SX, chi: ca.SX) -> ca.SX:
    """Rotor inertia, friction (eq. 5; asymmetric Coulomb on robot.asymmetric_coulomb), the wrist
    coupling (eqs. 16-18) and torque offsets."""
    n = robot.n
    k = len(LINK_PARAMETERS)
    IA, FS, FV = (LINK_PARAMETERS.index(p) for p in ("IA", "FS", "FV"))
    tau = [chi[k * j + IA] * qdd[j] + chi[k * j + FV] * qd[j]
           + (0 if j in robot.asymmetric_coulomb else chi[k * j + FS] * ca.sign(qd[j]))
           for j in range(n)]
    extra = k * n
    if robot.coupling is not None:
        a, b = robot.coupling.joints
        fvm, fsm = chi[extra], chi[extra + 1]
        ia_b = chi[k * b + IA]
        if robot.coupling.coulomb_sign == "paper":
            sign_a, sign_b = ca.sign(qd[b]), ca.sign(qd[a])  # eqs. 17-18
        else:
            # Motor-b speed is proportional to qd_a + qd_b (eq. 16): one Coulomb term, both rows.
            sign_a = sign_b = ca.sign(qd[a] + qd[b])
        tau[a] = tau[a] + ia_b * qdd[b] + fvm * qd[b] + fsm * sign_a   # eq. 17
        tau[b] = tau[b] + ia_b * qdd[a] + fvm * qd[a] + fsm * sign_b   # eq. 18
        extra += 2
    for j in robot.asymmetric_coulomb:
        # FSPj·[qd > 0] − FSNj·[qd < 0], both >= 0; 0 at rest.
        s = ca.sign(qd[j])
        tau[j] = tau[j] + chi[extra] * (s + s * s) / 2 + chi[extra + 1] * (s - s * s) / 2
        extra += 2
    if robot.offsets:
        tau = [tau[j] + chi[extra + j] for j in range(n)]
    return ca.vertcat(*tau)


def inverse_dynamics_expression(robot: Robot, q: ca.SX, qd: ca.SX, qdd: ca.SX, chi: ca.SX) -> ca.SX:
    """Gamma = ID(q, qd, qdd; chi) (eq. 1), spring excluded."""
    k = len(LINK_PARAMETERS)
    bodies = [body_from_vector(chi[k * j:k * j + 10]) for j in range(robot.n)]
    return rigid_body_torques(robot, q, qd, qdd, bodies, robot.gravity_vector) + actuation_torques(
        robot, qd, qdd, chi)


def regressor_expression(robot: Robot, q: ca.SX, qd: ca.SX, qdd: ca.SX, chi: ca.SX) -> ca.SX:
    """Phi with Gamma = Phi chi (eq. 2): the model is linear in chi, so its Jacobian is exact."""
    tau = inverse_dynamics_expression(robot, q, qd, qdd, chi)
    return ca.jacobian(tau, chi)
