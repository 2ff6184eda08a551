"""The momentum and β regressors (rx90sym.momentum) against Pinocchio and against the torque regressor."""
from __future__ import annotations

import numpy as np
import pytest

import rx90sym
from conftest import RANDOM_TABLE, random_chi
from rx90sym.momentum import base_momentum_regressors, momentum_regressors, momentum_terms

ROBOTS = ["rx90", "tx40", "panda", "random"]


def _robot(name: str) -> rx90sym.Robot:
    return rx90sym.robot_from_table(RANDOM_TABLE, name="random") if name == "random" else rx90sym.load_robot(name)


def _rigid(robot: rx90sym.Robot, chi: np.ndarray) -> np.ndarray:
    """chi with rotor inertias, friction and extras set to 0 (what Pinocchio's chain holds)."""
    out = chi.copy()
    for j in range(robot.n):
        out[13 * j + 10:13 * j + 13] = 0.0
    out[13 * robot.n:] = 0.0
    return out


@pytest.mark.parametrize("name", ROBOTS)
def test_momentum_and_beta_match_pinocchio(name):
    pin = pytest.importorskip("pinocchio")
    robot = _robot(name)
    f = momentum_regressors(robot)
    rng = np.random.default_rng(3)
    for _ in range(4):
        chi = random_chi(robot, rng)
        model = rx90sym.pinocchio_model(robot, _rigid(robot, chi))
        data = model.createData()
        q, qd = rng.uniform(-np.pi, np.pi, robot.n), rng.normal(0, 2, robot.n)
        phi_p, phi_b = (np.asarray(x.full()) for x in f(q, qd))
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        C = pin.computeCoriolisMatrix(model, data, q, qd)
        g = pin.computeGeneralizedGravity(model, data, q)
        p_ref, b_ref = M @ qd, g - C.T @ qd
        tol = 1e-9 * max(1.0, np.abs(p_ref).max(), np.abs(b_ref).max())
        # The rigid chain against Pinocchio.
        assert np.abs(phi_p @ _rigid(robot, chi) - p_ref).max() < tol
        assert np.abs(phi_b @ _rigid(robot, chi) - b_ref).max() < tol
        # Rotor inertias (and the wrist coupling's) add to M only: Ia q̇ on p, nothing on β.
        ia = chi - _rigid(robot, chi)
        M_rot = np.diag([ia[13 * j + 10] for j in range(robot.n)])
        if robot.coupling is not None:
            a, b = robot.coupling.joints
            M_rot[a, b] = M_rot[b, a] = ia[13 * b + 10]
        assert np.abs(phi_p @ chi - (p_ref + M_rot @ qd)).max() < tol
        assert np.abs(phi_b @ chi - b_ref).max() < tol


def _stencil(fun, t: float, h: float) -> np.ndarray:
    """Five-point central derivative (error O(h⁴))."""
    return (fun(t - 2 * h) - 8 * fun(t - h) + 8 * fun(t + h) - fun(t + 2 * h)) / (12 * h)


@pytest.mark.parametrize("name", ["rx90", "panda", "random"])
def test_torque_identity_along_a_trajectory(name):
    """τ = d/dt(p) + β + friction: column by column, Φ(q, q̇, q̈) = d/dt Φ_p + Φ_β on the rigid and
    rotor columns (friction columns: Φ_p = Φ_β = 0), on the base parameters too."""
    robot = _robot(name)
    base = rx90sym.base_parameters(robot)
    rng = np.random.default_rng(5)
    A, w, ph = rng.uniform(0.3, 1.0, robot.n), rng.uniform(0.5, 2.0, robot.n), rng.uniform(0, 6, robot.n)

    def q_of(t):
        return A * np.sin(w * t + ph)

    def qd_of(t):
        return A * w * np.cos(w * t + ph)

    def qdd_of(t):
        return -A * w ** 2 * np.sin(w * t + ph)

    f, fb = momentum_regressors(robot), base_momentum_regressors(base)
    h = 1e-3
    for t in np.linspace(0.0, 3.0, 5):
        phi = np.asarray(robot.regressor(q_of(t), qd_of(t), qdd_of(t)).full())
        dphi_p = _stencil(lambda s: np.asarray(f(q_of(s), qd_of(s))[0].full()), t, h)
        phi_beta = np.asarray(f(q_of(t), qd_of(t))[1].full())
        friction = [i for i, nm in enumerate(robot.parameter_names)
                    if nm.rstrip("0123456789") in ("FS", "FV", "FVM", "FSM", "FSP", "FSN", "OFF")]
        rest = np.setdiff1d(np.arange(phi.shape[1]), friction)
        tol = 1e-9 * max(1.0, np.abs(phi).max())
        assert np.abs(phi[:, rest] - (dphi_p + phi_beta)[:, rest]).max() < tol
        assert np.abs(dphi_p[:, friction]).max() == 0.0 and np.abs(phi_beta[:, friction]).max() == 0.0
        phi_b = np.asarray(base.regressor(q_of(t), qd_of(t), qdd_of(t)).full())
        dpb = _stencil(lambda s: np.asarray(fb(q_of(s), qd_of(s))[0].full()), t, h)
        pbb = np.asarray(fb(q_of(t), qd_of(t))[1].full())
        keep = [i for i, nm in enumerate(base.names) if not nm.startswith(("FS", "FV", "OFF"))]
        assert np.abs(phi_b[:, keep] - (dpb + pbb)[:, keep]).max() < tol


def test_base_terms_equal_standard_terms():
    """p and β from the base values K χ equal those from χ (the reduction to the base set holds)."""
    robot = rx90sym.load_robot("rx90")
    base = rx90sym.base_parameters(robot)
    rng = np.random.default_rng(8)
    chi = random_chi(robot, rng)
    f, terms = momentum_regressors(robot), momentum_terms(base, base.beta(chi))
    for _ in range(3):
        q, qd = rng.uniform(-3, 3, robot.n), rng.normal(0, 2, robot.n)
        phi_p, phi_b = (np.asarray(x.full()) for x in f(q, qd))
        p, beta = (np.asarray(x.full()).ravel() for x in terms(q, qd))
        assert np.abs(p - phi_p @ chi).max() < 1e-9 * max(1, np.abs(p).max())
        assert np.abs(beta - phi_b @ chi).max() < 1e-9 * max(1, np.abs(beta).max())
