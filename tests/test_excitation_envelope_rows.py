"""The envelope's IPOPT rows (excitation/envelope_rows.py): the chain-rule Jacobian through the
joint samples against CasADi's own differentiation of the composed expression and central finite
differences; the soft extremes against the exact extremes of the UR5's points."""
from __future__ import annotations

import warnings
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import excitation
import rx90sym
from excitation.envelope_rows import sample_rows, through_samples

UR5 = Path(__file__).parent / "data" / "urdf" / "ur5.urdf"


@pytest.fixture(scope="module")
def ur5_model():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the URDF's missing acceleration limits
        robot = rx90sym.load_robot(UR5, tip="tool0")
    base = rx90sym.base_parameters(robot)
    chi = robot.parameter_vector(rx90sym.nominal_parameters(robot))
    return excitation.safe_model(robot, chi, base, excitation.Envelope())[0]


def _direct(f: ca.Function, sq: np.ndarray, sqd: np.ndarray, n: int) -> ca.Function:
    """The same rows composed plainly (CasADi differentiates everything itself)."""
    x = ca.MX.sym("x", sq.shape[1] * n)
    z = ca.reshape(x, sq.shape[1], n)
    g = ca.vec(f.map(sq.shape[0], "serial")(ca.mtimes(ca.DM(sq), z).T, ca.mtimes(ca.DM(sqd), z).T))
    return ca.Function("direct", [x], [g, ca.jacobian(g, x)])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_chain_rule_jacobian_equals_casadi_ad_and_finite_differences(ur5_model, seed):
    rng = np.random.default_rng(seed)
    form = excitation.FourierSeries(10.0, 3)
    t = np.sort(rng.uniform(0.0, 10.0, 7))
    bq, bd, _ = form.basis(t)
    sq, sqd = bq @ form.rest_basis(), bd @ form.rest_basis()
    f, lo, hi = sample_rows(ur5_model, 0.02, 0.01, 0.01)
    rows = through_samples(f, (sq, sqd), ur5_model.n)
    x = ca.MX.sym("x", rows.size1_in(0))
    chained = ca.Function("chained", [x], [rows(x), ca.jacobian(rows(x), x)])
    z = form.constant(ur5_model.centre) + 0.3 * form.random_free(rng, ur5_model.n)
    x0 = z.flatten(order="F")
    g_c, j_c = (np.asarray(v) for v in chained(x0))
    g_d, j_d = (np.asarray(v) for v in _direct(f, sq, sqd, ur5_model.n)(x0))
    assert g_c.shape == (f.size1_out(0) * t.size, 1) and lo.size == f.size1_out(0)
    np.testing.assert_allclose(g_c, g_d, rtol=0, atol=1e-12)
    scale = np.max(np.abs(j_d))
    np.testing.assert_allclose(j_c, j_d, rtol=0, atol=1e-10 * scale)
    h = 1e-6
    for k in rng.choice(x0.size, 6, replace=False):  # central differences along some coefficients
        e = np.zeros(x0.size)
        e[k] = h
        fd = (np.asarray(rows(x0 + e)) - np.asarray(rows(x0 - e))).ravel() / (2 * h)
        np.testing.assert_allclose(j_c[:, k], fd, rtol=0, atol=1e-5 * max(scale, 1.0))


def test_soft_rows_are_never_optimistic(ur5_model):
    """Lowest height and clearance rows never above, the squared-speed row never below, the exact
    extremes of the points they cover, at random poses and speeds."""
    f, lo, hi = sample_rows(ur5_model, 0.02, 0.01, 0.01)
    rng = np.random.default_rng(3)
    lim = ur5_model.limits
    for _ in range(50):
        q = rng.uniform(lim.q_min, lim.q_max)
        qd = rng.uniform(-lim.qd_max, lim.qd_max)
        height, clearance, speed2 = np.asarray(f(q, qd)).ravel()
        assert height <= np.min(np.asarray(ur5_model.heights(q))) + 1e-12
        assert clearance <= np.min(np.asarray(ur5_model.collision.clearance(q))) + 1e-12
        assert speed2 >= np.max(np.asarray(ur5_model.speeds(q, qd))) - 1e-12
    assert lo[0] == ur5_model.z_min + 0.01 and lo[1] == 0.01
    assert hi[2] == pytest.approx((0.95 * ur5_model.speed_max) ** 2)
