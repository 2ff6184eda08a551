"""The compiled path of the excitation NLP (kernels.py, criterion_callback.py, the torque rows of
envelope_rows.through_samples): the same criterion, constraints and derivatives as CasADi's one
graph in its VM (OptimiserOptions(compiled=False)), and gradients against central differences."""
from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest

import excitation
from excitation.constraints import torque_rows
from excitation.envelope_rows import through_samples
from excitation.fourier import FourierSeries
from excitation.kernels import SampleKernel, evaluate_samples
from excitation.optimiser import _Problem, initial_free, start_rng
from excitation.trajectory import sample_times
from test_excitation import BETA, FAST, toy_model, toy_regressor

FORM = FourierSeries(4.0, 3)


def _problem(compiled: bool, criterion: str) -> _Problem:
    """The toy NLP with a floor (envelope row) and torque rows on every third grid time."""
    model = toy_model(tau_max=(30.0, 8.0), z_min=-0.6)
    objective = excitation.make_objective(model, criterion, nominal_base=BETA)
    options = dataclasses.replace(FAST, criterion=objective, compiled=compiled,
                                  p_schedule=(4, 16))
    grid = sample_times(FORM.duration, options.constraint_grid_rate(FORM.max_frequency_hz))
    return _Problem(model, FORM, options, grid, grid[::3])


def _points(n: int = 3) -> list[np.ndarray]:
    model = toy_model(z_min=-0.6)
    grid = sample_times(FORM.duration, 10.0)
    return [initial_free(model, FORM, start_rng(5, k), (0.4, 0.9), grid, FAST.margins).flatten(order="F")
            for k in range(1, n + 1)]


@pytest.mark.parametrize("criterion", ["sigma", "cond-columns", "logdet"])
def test_compiled_nlp_equals_the_one_graph_in_value_and_derivatives(criterion):
    fast, graph = _problem(True, criterion), _problem(False, criterion)
    assert fast.lbg.size == graph.lbg.size and np.array_equal(fast.lbg, graph.lbg)
    for stage in range(len(fast.solvers)):
        for name in ("nlp_f", "nlp_grad_f", "nlp_g", "nlp_jac_g"):
            a_f, b_f = fast.solvers[stage].get_function(name), graph.solvers[stage].get_function(name)
            for x in _points():
                a = [np.asarray(ca.densify(v)) for v in a_f.call([x, []])]
                b = [np.asarray(ca.densify(v)) for v in b_f.call([x, []])]
                for u, v in zip(a, b):
                    np.testing.assert_allclose(u, v, rtol=1e-9, atol=1e-9 * max(1.0, np.max(np.abs(v))))


def test_criterion_gradient_against_central_differences():
    problem = _problem(True, "sigma")
    grad_f = problem.solvers[0].get_function("nlp_grad_f")
    rng = np.random.default_rng(2)
    for x in _points(2):
        f0, g = (np.asarray(v).ravel() for v in grad_f.call([x, []]))
        h = 1e-6
        for k in rng.choice(x.size, 5, replace=False):
            e = np.zeros(x.size)
            e[k] = h
            fd = (float(problem.stage_values(x + e)[0]) - float(problem.stage_values(x - e)[0])) / (2 * h)
            assert fd == pytest.approx(g[k], rel=1e-5, abs=1e-7 * max(1.0, np.max(np.abs(g))))


@pytest.mark.parametrize("compile", [True, False])
def test_torque_rows_jacobian_equals_casadi_ad(compile):
    model = toy_model(tau_max=(30.0, np.inf))  # joint 2 unlimited: its row is left out
    f, lo, hi = torque_rows(model, FAST.margins)
    assert f.size1_out(0) == 1 and lo[0] == pytest.approx(-0.95 * 30.0) and hi[0] == -lo[0]
    t = np.linspace(0.1, 3.9, 9)
    bases = [b @ FORM.rest_basis() for b in FORM.basis(t)]
    rows = through_samples(f, bases, model.n, compile)
    x = ca.MX.sym("x", rows.size1_in(0))
    z = ca.reshape(x, bases[0].shape[1], model.n)
    direct = ca.vec(model.torque.map(t.size, "serial")(*[ca.mtimes(ca.DM(b), z).T for b in bases])[0, :])
    both = ca.Function("both", [x], [rows(x), ca.jacobian(rows(x), x), direct, ca.jacobian(direct, x)])
    for x0 in _points():
        g, j, g_ref, j_ref = (np.asarray(ca.densify(v)) for v in both(x0))
        np.testing.assert_allclose(g, g_ref, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(j, j_ref, rtol=1e-10, atol=1e-10 * np.max(np.abs(j_ref)))


def test_sample_evaluation_of_a_sparse_output_matches_per_sample_calls():
    """The regressor has structural zeros: the zero-copy evaluation must lay them out densely."""
    sym = toy_regressor().sx_in()
    reg = ca.Function("sparse_regressor", sym, [ca.sparsify(toy_regressor()(*sym))])
    assert not reg.sparsity_out(0).is_dense()
    rng = np.random.default_rng(0)
    q, qd, qdd = (rng.uniform(-2, 2, (7, 2)) for _ in range(3))
    out = evaluate_samples(reg, q, qd, qdd)
    assert out.shape == (7, 2, 11)
    for k in range(7):
        np.testing.assert_array_equal(out[k], np.asarray(ca.densify(reg(q[k], qd[k], qdd[k]))))
    with pytest.raises(ValueError, match="dense"):
        SampleKernel(reg, 7, compile=False)


def test_compiled_start_holds_every_limit_on_the_fine_check():
    """One start with torque repairs and a floor on the compiled path: feasible on a 2 kHz grid
    finer than the optimiser's own check."""
    model = toy_model(tau_max=(30.0, 8.0), z_min=-0.6)
    objective = excitation.make_objective(model, "sigma", nominal_base=BETA)
    traj = excitation.optimise_model(model, FORM, seed=0, starts=1, progress=False,
                                     options=dataclasses.replace(FAST, criterion=objective))
    t, q, qd, qdd = traj.sample(rate=2000.0, closed=True)
    report = excitation.check_limits(model, q, qd, qdd, 2000.0)
    assert report.feasible, report.violations
    assert np.isfinite(traj.cond) and traj.usage.feasible


def test_a_motionless_point_is_an_evaluation_error_for_ipopt_not_an_exception():
    """G is singular for a constant pose: the one graph fails to evaluate; the callback gives NaN
    (IPOPT cuts its step back either way) instead of raising through CasADi."""
    problem = _problem(True, "sigma")
    x = FORM.constant(np.array([0.3, 0.2])).flatten(order="F")
    f, g = (np.asarray(v).ravel() for v in problem.solvers[0].get_function("nlp_grad_f").call([x, []]))
    assert np.isnan(f).all() and np.isnan(g).all()
    with pytest.raises(RuntimeError, match="Evaluation failed"):
        _problem(False, "sigma").solvers[0].get_function("nlp_f").call([x, []])
