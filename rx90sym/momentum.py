"""Generalised momentum and the β term of the momentum observer, linear in the parameters (CasADi SX).

For the rigid chain with rotor inertias (and the wrist coupling's rotor inertia):

    p = M(q) q̇ = Φ_p(q, q̇) χ                 generalised momentum
    β = g(q) − C(q, q̇)ᵀ q̇ = Φ_β(q, q̇) χ     so that ṗ = τ − f − β     (De Luca & Mattone 2005)

where C is the Christoffel Coriolis matrix (Ṁ = C + Cᵀ) and τ − f the torque net of friction,
offsets and spring (handled apart, by the fit's own friction model). Both follow from the
inverse dynamic model of :mod:`rx90sym.newton_euler` without a joint acceleration:
M = ∂τ/∂q̈ (so rotor inertias and the 5-6 coupling enter exactly as in τ), g = τ(q, 0, 0) of the
rigid chain, and Cᵀq̇ = ∇_q (½ q̇ᵀ M(q) q̇) (the gradient of the kinetic energy at fixed q̇).
Linear in χ, their Jacobians in χ are the exact regressors; like the torque regressor they
reduce to the base parameters through the same columns: Φ_x χ = Φ_x[:, independent] (K χ).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

import casadi as ca

from .newton_euler import body_from_vector, inverse_dynamics_expression, rigid_body_torques
from .parameters import LINK_PARAMETERS

if TYPE_CHECKING:  # for annotations only
    from .description import Robot

__all__ = ["momentum_expressions", "momentum_regressors", "base_momentum_regressors"]


def momentum_expressions(robot: Robot, q: ca.SX, qd: ca.SX, chi: ca.SX) -> tuple[ca.SX, ca.SX]:
    """(p, β) as SX expressions of (q, q̇, χ): p = M(q) q̇ [N·m·s], β = g − Cᵀq̇ [N·m]."""
    n = robot.n
    qdd = ca.SX.sym("qdd_aux", n)
    zero = ca.SX.zeros(n, 1)
    # τ(q, 0, q̈) = M(q) q̈ + g + offsets (friction is 0 at q̇ = 0): its derivative along q̇ is M q̇.
    tau = inverse_dynamics_expression(robot, q, zero, qdd, chi)
    p = ca.substitute(ca.jtimes(tau, qdd, qd), qdd, zero)
    k = len(LINK_PARAMETERS)
    bodies = [body_from_vector(chi[k * j:k * j + 10]) for j in range(n)]
    g = rigid_body_torques(robot, q, zero, zero, bodies, robot.gravity_vector)
    ct_qd = ca.gradient(0.5 * ca.dot(qd, p), q)  # Cᵀq̇ = ∂T/∂q, T = ½ q̇ᵀ M(q) q̇
    return p, g - ct_qd


def momentum_regressors(robot: Robot) -> ca.Function:
    """casadi.Function (q, qd) -> (Phi_p, Phi_beta), each n x len(parameter_names):
    p = Phi_p χ, β = g − Cᵀq̇ = Phi_beta χ (standard parameters)."""
    q, qd = ca.SX.sym("q", robot.n), ca.SX.sym("qd", robot.n)
    chi = ca.SX.sym("chi", len(robot.parameter_names))
    p, beta = momentum_expressions(robot, q, qd, chi)
    return ca.Function("momentum_regressors", [q, qd], [ca.jacobian(p, chi), ca.jacobian(beta, chi)],
                       ["q", "qd"], ["Phi_p", "Phi_beta"])


def base_momentum_regressors(base: Any) -> ca.Function:
    """casadi.Function (q, qd) -> (Phi_p_b, Phi_beta_b), n x nb, on the base parameters of
    ``base`` (:class:`rx90sym.BaseParameters`): Phi_x χ = Phi_x_b (K χ)."""
    robot = base.robot
    f = momentum_regressors(robot)
    q, qd = ca.SX.sym("q", robot.n), ca.SX.sym("qd", robot.n)
    phi_p, phi_beta = f(q, qd)
    cols = list(base.independent)
    return ca.Function("base_momentum_regressors", [q, qd], [phi_p[:, cols], phi_beta[:, cols]],
                       ["q", "qd"], ["Phi_p_b", "Phi_beta_b"])


def momentum_terms(base: Any, values: Any) -> ca.Function:
    """casadi.Function (q, qd) -> (p, β) for the base parameter values ``values`` (nb numbers in
    ``base.names`` order), the regressors multiplied out (what an observer evaluates per sample)."""
    robot = base.robot
    f = base_momentum_regressors(base)
    q, qd = ca.SX.sym("q", robot.n), ca.SX.sym("qd", robot.n)
    phi_p, phi_beta = f(q, qd)
    b = ca.DM([float(v) for v in values])
    return ca.Function("momentum_terms", [q, qd], [ca.mtimes(phi_p, b), ca.mtimes(phi_beta, b)],
                       ["q", "qd"], ["p", "beta"])
