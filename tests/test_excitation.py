"""Tests of the excitation package on a toy 2-link planar arm (and the RX90 when marked slow).

The toy arm moves in a vertical plane (gravity along -y), link 1 of length 0.5 m; its base
regressor has 11 columns: ZZ1R MX1R MY1 ZZ2 MX2 MY2 IA2 FS1 FV1 FS2 FV2 (Lagrange, by hand).
"""
from __future__ import annotations

import dataclasses
import io
import json
from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest

import excitation
from excitation.constraints import check_limits
from excitation.criterion import log_cond_surrogate, smooth_friction_regressor
from excitation.fourier import FourierSeries
from excitation.model import ExcitationModel, JointLimits
from excitation.multistart import optimise_model
from excitation.options import OptimiserOptions
from excitation.via_points import ViaPointSpline

L1, G = 0.5, 9.81
NAMES = ("ZZ1R", "MX1R", "MY1", "ZZ2", "MX2", "MY2", "IA2", "FS1", "FV1", "FS2", "FV2")
BETA = np.array([2.0, 1.5, 0.05, 0.3, 0.6, 0.02, 0.4, 3.0, 4.0, 2.0, 1.5])


def toy_regressor() -> ca.Function:
    """Base regressor (2 x 11) of the planar 2R arm in a vertical plane."""
    q, qd, qdd = ca.SX.sym("q", 2), ca.SX.sym("qd", 2), ca.SX.sym("qdd", 2)
    c1, s1, c2, s2 = ca.cos(q[0]), ca.sin(q[0]), ca.cos(q[1]), ca.sin(q[1])
    c12, s12 = ca.cos(q[0] + q[1]), ca.sin(q[0] + q[1])
    a12 = qdd[0] + qdd[1]
    cor = 2 * qd[0] * qd[1] + qd[1] ** 2
    phi = ca.SX.zeros(2, 11)
    phi[0, 0] = qdd[0]
    phi[0, 1] = G * c1
    phi[0, 2] = -G * s1
    phi[0, 3] = a12
    phi[0, 4] = L1 * ((2 * qdd[0] + qdd[1]) * c2 - cor * s2) + G * c12
    phi[0, 5] = -L1 * ((2 * qdd[0] + qdd[1]) * s2 + cor * c2) - G * s12
    phi[0, 7] = ca.sign(qd[0])
    phi[0, 8] = qd[0]
    phi[1, 3] = a12
    phi[1, 4] = L1 * (qdd[0] * c2 + qd[0] ** 2 * s2) + G * c12
    phi[1, 5] = L1 * (-qdd[0] * s2 + qd[0] ** 2 * c2) - G * s12
    phi[1, 6] = qdd[1]
    phi[1, 9] = ca.sign(qd[1])
    phi[1, 10] = qd[1]
    return ca.Function("toy_regressor", [q, qd, qdd], [phi], ["q", "qd", "qdd"], ["Phi"])


def toy_limits(tau_max=(80.0, 30.0)) -> JointLimits:
    return JointLimits(q_min=[-2.5, -2.0], q_max=[2.5, 2.0], qd_max=[3.0, 4.0],
                       qdd_max=[15.0, 20.0], tau_max=list(tau_max))


def toy_torque() -> ca.Function:
    """Motor torque with the nominal parameters (no spring on the toy)."""
    reg = toy_regressor()
    q, qd, qdd = ca.SX.sym("q", 2), ca.SX.sym("qd", 2), ca.SX.sym("qdd", 2)
    return ca.Function("toy_torque", [q, qd, qdd], [ca.mtimes(reg(q, qd, qdd), BETA)])


def toy_heights() -> ca.Function:
    """Height [m] of the tip of link 2 (0.4 m long): must stay above a floor."""
    q = ca.SX.sym("q", 2)
    return ca.Function("toy_heights", [q], [L1 * ca.sin(q[0]) + 0.4 * ca.sin(q[0] + q[1])])


def toy_model(torque: bool = True, tau_max=(80.0, 30.0), z_min=None) -> ExcitationModel:
    return ExcitationModel(regressor=toy_regressor(), limits=toy_limits(tau_max), names=NAMES,
                           torque=toy_torque() if torque else None,
                           heights=toy_heights() if z_min is not None else None, z_min=z_min,
                           controller_offsets=np.array([0.0, np.pi / 2]), name="toy")


class ToyRobot(SimpleNamespace):
    """Duck-typed rx90sym.Robot for the robot-level API (chi = base parameters for the toy)."""


def toy_robot() -> ToyRobot:
    reg = toy_regressor()
    q, qd, qdd, chi = (ca.SX.sym(s, k) for s, k in (("q", 2), ("qd", 2), ("qdd", 2), ("chi", 11)))
    idm = ca.Function("idm", [q, qd, qdd, chi], [ca.mtimes(reg(q, qd, qdd), chi)])
    spring = ca.Function("spring", [q], [ca.vertcat(0, 0)])
    fk = ca.Function("fk", [q], [ca.SX.eye(4), ca.SX.zeros(3, 2)])
    lim = toy_limits()
    return ToyRobot(name="toy", n=2, limits=lim, controller_offsets=np.array([0.0, np.pi / 2]),
                    inverse_dynamics=idm, spring_torque=spring, forward_kinematics=fk,
                    to_controller=lambda x: np.asarray(x) + np.array([0.0, np.pi / 2]))


TOY_BASE = SimpleNamespace(regressor=toy_regressor(), names=NAMES, beta=lambda chi: np.asarray(chi))
FAST = OptimiserOptions(grid_rate=8.0, verify_rate=400.0, cond_rate=100.0, max_iter=150)


# --------------------------------------------------------------------------- Fourier series
def test_fourier_derivatives_match_analytic_and_finite_differences():
    form = FourierSeries(duration=7.0, harmonics=4)
    rng = np.random.default_rng(1)
    c = rng.standard_normal((form.n_coefficients, 3))
    t = np.linspace(0.0, 7.0, 301)
    q, qd, qdd = form.evaluate(c, t)
    # analytic, written out independently of the basis matrices
    w = form.base_frequency
    parts = form.split(c)
    q_ref = np.tile(parts["q0"], (t.size, 1))
    qd_ref = np.zeros_like(q_ref)
    qdd_ref = np.zeros_like(q_ref)
    for l in range(1, 5):
        a, b = parts["a"][:, l - 1], parts["b"][:, l - 1]
        s, co = np.sin(l * w * t)[:, None], np.cos(l * w * t)[:, None]
        q_ref += a / (l * w) * s - b / (l * w) * co
        qd_ref += a * co + b * s
        qdd_ref += -a * l * w * s + b * l * w * co
    np.testing.assert_allclose(q, q_ref, atol=1e-12)
    np.testing.assert_allclose(qd, qd_ref, atol=1e-12)
    np.testing.assert_allclose(qdd, qdd_ref, atol=1e-12)
    h = 1e-5
    qp, qdp, _ = form.evaluate(c, t + h)
    qm, qdm, _ = form.evaluate(c, t - h)
    np.testing.assert_allclose((qp - qm) / (2 * h), qd, atol=1e-7)
    np.testing.assert_allclose((qdp - qdm) / (2 * h), qdd, atol=1e-6)


def test_fourier_rest_to_rest_at_both_ends():
    form = FourierSeries(duration=10.0, harmonics=5)
    rng = np.random.default_rng(2)
    z = rng.standard_normal((form.rest_basis().shape[1], 4))
    c = form.rest_basis() @ z
    q, qd, qdd = form.evaluate(c, [0.0, 10.0])
    np.testing.assert_allclose(qd, 0.0, atol=1e-12)
    np.testing.assert_allclose(qdd, 0.0, atol=1e-12)
    np.testing.assert_allclose(q[0], q[1], atol=1e-12)
    n_mat = form.rest_basis()
    np.testing.assert_allclose(n_mat.T @ n_mat, np.eye(n_mat.shape[1]), atol=1e-12)


def test_fourier_refuses_bad_input():
    with pytest.raises(ValueError, match="harmonics"):
        FourierSeries(10.0, 1)
    with pytest.raises(ValueError, match="duration"):
        FourierSeries(-1.0, 3)


def test_via_points_rest_to_rest_and_interpolate():
    form = ViaPointSpline.uniform(6.0, 7)
    rng = np.random.default_rng(3)
    p = form.rest_basis() @ rng.standard_normal((6, 2))
    q, qd, qdd = form.evaluate(p, np.asarray(form.times))
    np.testing.assert_allclose(q, p, atol=1e-12)  # passes through every via point
    np.testing.assert_allclose(qd[[0, -1]], 0.0, atol=1e-10)
    np.testing.assert_allclose(qdd[[0, -1]], 0.0, atol=1e-9)
    np.testing.assert_allclose(q[0], q[-1], atol=1e-12)  # closed
    t = np.linspace(0.0, 6.0, 601)
    q, qd, _ = form.evaluate(p, t)
    np.testing.assert_allclose(np.gradient(q, t, axis=0)[5:-5], qd[5:-5], atol=2e-3)


# --------------------------------------------------------------------------- criterion
def test_condition_number_matches_numpy_and_sign_columns():
    reg = toy_regressor()
    form = FourierSeries(5.0, 3)
    c = form.rest_basis() @ np.random.default_rng(4).standard_normal((5, 2))
    t = np.arange(500) / 100.0
    q, qd, qdd = form.evaluate(c, t)
    w = np.vstack([np.asarray(reg(q[k], qd[k], qdd[k])) for k in range(t.size)])
    assert excitation.condition_number(reg, t, q, qd, qdd) == pytest.approx(np.linalg.cond(w), rel=1e-9)
    with pytest.raises(ValueError):
        excitation.condition_number(reg, t[:-1], q, qd, qdd)


def test_smooth_friction_replaces_only_coulomb_columns():
    reg = toy_regressor()
    smooth = smooth_friction_regressor(reg, NAMES, eps=0.1)
    q, qd, qdd = np.array([0.3, -0.2]), np.array([0.05, -2.0]), np.array([1.0, 2.0])
    exact, soft = np.asarray(reg(q, qd, qdd)), np.asarray(smooth(q, qd, qdd))
    fs = [NAMES.index("FS1"), NAMES.index("FS2")]
    others = [i for i in range(11) if i not in fs]
    np.testing.assert_allclose(soft[:, others], exact[:, others])
    assert soft[0, fs[0]] == pytest.approx(np.tanh(0.5))
    assert soft[1, fs[1]] == pytest.approx(np.tanh(-20.0))


def test_surrogate_brackets_true_condition_number():
    rng = np.random.default_rng(5)
    a = rng.standard_normal((200, 11)) * np.logspace(0, 1.5, 11)
    g = a.T @ a
    kappa = np.sqrt(np.linalg.cond(g))
    for p in (1, 4, 16):
        f = float(log_cond_surrogate(ca.DM(g), p))
        assert 2 * np.log(kappa) - 1e-9 <= f <= 2 * np.log(kappa) + 2 / p * np.log(11) + 1e-9


# --------------------------------------------------------------------------- constraints
def test_check_limits_reports_usage_and_violations():
    model = toy_model()
    q = np.zeros((11, 2))
    qd = np.zeros((11, 2))
    qd[3, 1] = 5.0  # joint 2 limit is 4 rad/s
    report = check_limits(model, q, qd, np.zeros((11, 2)), 10.0)
    assert not report.feasible
    assert report.velocity[1] == pytest.approx(1.25)
    assert "velocity limit of joint 2" in report.violations[0]
    # torque at rest = gravity: MX1R g + MX2 g at q = 0
    assert report.torque[0] == pytest.approx((1.5 + 0.6) * G / 80.0)


# --------------------------------------------------------------------------- optimiser
def _toy_optimise(seed=0, **kwargs):
    form = FourierSeries(4.0, 3)
    return optimise_model(toy_model(z_min=kwargs.pop("z_min", None)), form, seed=seed,
                          starts=kwargs.pop("starts", 2), time_budget=60.0,
                          options=kwargs.pop("options", FAST), progress=kwargs.pop("progress", False))


def test_optimised_trajectory_holds_limits_on_fine_grid_and_beats_random():
    traj = _toy_optimise(z_min=-0.6)
    t, q, qd, qdd = traj.sample(rate=2000.0, closed=True)  # finer than the optimiser's own check
    model = toy_model(z_min=-0.6)
    report = check_limits(model, q, qd, qdd, 2000.0)
    assert report.feasible, report.violations
    assert traj.usage.feasible
    np.testing.assert_allclose(qd[[0, -1]], 0.0, atol=1e-12)
    np.testing.assert_allclose(qdd[[0, -1]], 0.0, atol=1e-10)
    baseline = excitation.random_feasible(toy_model(z_min=-0.6), FourierSeries(4.0, 3), seed=0, options=FAST)
    assert baseline.usage.feasible
    assert traj.cond < 0.7 * baseline.cond
    t, q, qd, qdd = traj.sample(rate=100.0)
    assert traj.cond == pytest.approx(excitation.condition_number(toy_regressor(), t, q, qd, qdd))


def test_optimiser_is_deterministic_for_a_seed():
    a, b = _toy_optimise(seed=3, starts=1), _toy_optimise(seed=3, starts=1)
    np.testing.assert_array_equal(a.coefficients, b.coefficients)
    assert a.cond == b.cond


def test_progress_line_per_start():
    stream = io.StringIO()
    _toy_optimise(starts=2, progress=stream)
    lines = stream.getvalue().strip().splitlines()
    assert len(lines) == 2 and lines[0].startswith("[excitation] start 1/2")
    assert "iterations" in lines[0] and "cond" in lines[0] and "feasible" in lines[0]


def test_time_budget_is_optional_and_reports_every_skipped_start():
    stream = io.StringIO()
    traj = optimise_model(toy_model(), FourierSeries(4.0, 3), seed=0, starts=50, time_budget=1.0,
                          options=FAST, progress=stream)
    assert 1 <= traj.info.starts < 50 and traj.info.time_s < 5.0
    skipped = [line for line in stream.getvalue().splitlines() if "skipped" in line]
    assert len(skipped) == len(traj.info.skipped_starts) == 50 - traj.info.starts
    assert "time budget" in skipped[0]
    assert traj.summary()["optimiser"]["skipped_starts"] == list(traj.info.skipped_starts)


def test_starts_stop_on_their_count_by_default_and_each_has_its_own_seed():
    # no time budget: every start runs; start k draws from default_rng([seed, k]), so running
    # start 3 alone gives start 3 of the full run
    full = optimise_model(toy_model(), FourierSeries(4.0, 3), seed=4, starts=3, options=FAST, progress=False)
    assert full.info.starts == 3 and full.info.skipped_starts == ()
    from excitation.optimiser import run_starts

    alone = run_starts(toy_model(), FourierSeries(4.0, 3), FAST, 4, [full.info.best_start])[0]
    np.testing.assert_array_equal(alone.coefficients, full.coefficients)


def test_via_point_form_optimises():
    form = ViaPointSpline.uniform(4.0, 6)
    traj = optimise_model(toy_model(), form, seed=0, starts=1, options=FAST, progress=False)
    assert traj.usage.feasible and traj.harmonics is None and np.isfinite(traj.cond)


@pytest.mark.parametrize("duration, harmonics, options, match", [
    (2.0, 5, FAST, "max_frequency"),                                   # 2.5 Hz > 2 Hz
    (4.0, 3, OptimiserOptions(grid_rate=1.5, verify_rate=400.0), "Nyquist"),
    (0.25, 2, OptimiserOptions(grid_rate=20.0, max_frequency=10.0), "base parameters"),
])
def test_infeasible_requests_raise(duration, harmonics, options, match):
    with pytest.raises(ValueError, match=match):
        optimise_model(toy_model(), FourierSeries(duration, harmonics), options=options, progress=False)


def test_active_torque_limits_are_added_where_violated_and_hold():
    # torque limits are imposed lazily: the first solve ignores them, the fine-grid check finds
    # violations and the repair re-solves with them; the result uses most of the torque range
    traj = optimise_model(toy_model(tau_max=(30.0, 8.0)), FourierSeries(4.0, 3), seed=0, starts=1,
                          options=FAST, progress=False)
    assert "repair" in traj.info.status
    assert traj.usage.feasible and 0.9 < np.max(traj.usage.torque) <= 1.0
    t, q, qd, qdd = traj.sample(rate=2000.0, closed=True)
    assert check_limits(toy_model(tau_max=(30.0, 8.0)), q, qd, qdd, 2000.0).feasible


def test_impossible_torque_limits_raise():
    # 0.5 N m on joint 1: below the Coulomb friction (3 N m) and the static gravity torque almost
    # everywhere (up to 20.6 N m): joint 1 cannot move, so its parameters cannot be identified
    with pytest.raises(ValueError, match="no start"):
        optimise_model(toy_model(tau_max=(0.5, 30.0)), FourierSeries(4.0, 3), starts=1,
                       options=FAST, progress=False)
    with pytest.raises(ValueError, match="random trajectory"):
        excitation.random_feasible(toy_model(tau_max=(0.5, 30.0)), FourierSeries(4.0, 3), options=FAST)


def test_robot_level_api_on_duck_typed_robot():
    robot = toy_robot()
    traj = excitation.optimise(robot, duration=4.0, harmonics=3, seed=1, starts=1, chi_nominal=BETA,
                               base=TOY_BASE, options=FAST, progress=False, envelope=None)
    assert traj.usage.feasible and traj.harmonics == 3
    assert traj.base_frequency == pytest.approx(2 * np.pi / 4.0)
    assert np.all(np.isfinite(traj.usage.torque))
    rand = excitation.random_trajectory(robot, 4.0, 3, seed=1, base=TOY_BASE, options=FAST)
    assert rand.usage.feasible and np.all(np.isnan(rand.usage.torque))  # no chi: no torque limit


# --------------------------------------------------------------------------- files
def _any_trajectory():
    return excitation.random_feasible(toy_model(), FourierSeries(4.0, 3), seed=0, options=FAST)


def test_save_round_trip_in_staubli_angles(tmp_path):
    traj = _any_trajectory()
    path = tmp_path / "traj.csv"
    traj.save(path)
    with open(path) as handle:
        header = handle.readline().strip().split(",")
    assert header == ["t", "q1", "q2", "dq1", "dq2", "ddq1", "ddq2"]
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    assert data.shape == (4 * 250 + 1, 7)
    t, q, qd, qdd = traj.sample(250.0, closed=True)
    np.testing.assert_allclose(data[:, 0], t, atol=1e-9)
    np.testing.assert_allclose(data[:, 1:3] - traj.controller_offsets, q, atol=1e-8)
    np.testing.assert_allclose(data[:, 2] - data[0, 2] + q[0, 1], q[:, 1], atol=1e-8)
    np.testing.assert_allclose(data[:, 3:5], qd, atol=1e-8)
    np.testing.assert_allclose(data[:, 5:7], qdd, atol=1e-8)
    assert [p.name for p in tmp_path.iterdir()] == ["traj.csv"]


def test_former_staubli_offsets_spelling_warns_and_means_controller_offsets():
    """The RX90 word is kept one release, as for rx90sym.Robot: keyword and attribute both warn."""
    model = toy_model()
    with pytest.warns(DeprecationWarning, match="controller_offsets"):
        former = ExcitationModel(regressor=model.regressor, limits=model.limits, names=NAMES,
                                 staubli_offsets=np.array([0.0, np.pi / 2]), name="toy")
    np.testing.assert_array_equal(former.controller_offsets, model.controller_offsets)
    with pytest.warns(DeprecationWarning, match="ExcitationModel.staubli_offsets"):
        np.testing.assert_array_equal(model.staubli_offsets, [0.0, np.pi / 2])
    traj = _any_trajectory()
    with pytest.warns(DeprecationWarning, match="Trajectory.staubli_offsets"):
        np.testing.assert_array_equal(traj.staubli_offsets, traj.controller_offsets)
    again = dataclasses.replace(traj)  # the new keyword: no warning (warnings are errors here)
    with pytest.warns(DeprecationWarning, match="Trajectory\\(staubli_offsets"):
        excitation.Trajectory(traj.form, traj.coefficients, traj.cond, traj.criterion, usage=traj.usage,
                              info=traj.info, staubli_offsets=traj.controller_offsets)
    np.testing.assert_array_equal(again.controller_offsets, traj.controller_offsets)


def test_save_json_summary(tmp_path):
    traj = _any_trajectory()
    traj.save_json(tmp_path / "traj.json")
    content = json.loads((tmp_path / "traj.json").read_text())
    assert content["form"] == "fourier" and content["harmonics"] == 3
    assert np.array(content["coefficients"]["a_rad_s"]).shape == (2, 3)
    assert content["cond"] == pytest.approx(traj.cond)
    assert len(content["limits_usage"]["velocity"]) == 2
    assert content["limits_usage"]["feasible"] is True


def test_no_partial_file_on_error(tmp_path, monkeypatch):
    traj = _any_trajectory()
    path = tmp_path / "traj.csv"
    path.write_text("old content\n")

    def broken_savetxt(handle, rows, **kwargs):
        handle.write("0.0,1.0\n")  # part of the data, then a failure
        raise OSError("disk full")

    monkeypatch.setattr(np, "savetxt", broken_savetxt)
    with pytest.raises(OSError, match="disk full"):
        traj.save(path)
    assert path.read_text() == "old content\n"  # untouched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["traj.csv"]  # no temporary left
    with pytest.raises(ValueError, match="does not exist"):
        traj.save(tmp_path / "missing" / "traj.csv")


def test_plots_build(tmp_path):
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    traj = _any_trajectory()
    assert traj.plot() is not None
    assert excitation.plot_limit_usage(traj) is not None


# --------------------------------------------------------------------------- RX90 (acceptance)
@pytest.mark.slow
def test_rx90_optimised_trajectory_acceptance(tmp_path):
    """20 s, 5 harmonics, one start: cond <= 30 at 250 Hz, every limit held on a 2 kHz grid."""
    rx90sym = pytest.importorskip("rx90sym")
    robot = rx90sym.load_robot("rx90")
    bp = rx90sym.base_parameters(robot)
    chi = robot.parameter_vector(rx90sym.default_parameters(robot))
    traj = excitation.optimise(robot, 20.0, 5, seed=0, starts=1, chi_nominal=chi, base=bp,
                               criterion="cond", progress=False, envelope=None)
    assert bp.nb == 54
    t, q, qd, qdd = traj.sample(250.0)
    assert t.size == 5000
    w = excitation.stacked_regressor(bp.regressor_batch, q, qd, qdd)
    assert w.shape == (6 * 5000, 54)
    assert traj.cond == pytest.approx(np.linalg.cond(w), rel=1e-6)
    assert traj.cond <= 30.0
    model = excitation.model_from_robot(robot, chi, bp)
    t2, q2, qd2, qdd2 = traj.sample(2000.0, closed=True)
    report = check_limits(model, q2, qd2, qdd2, 2000.0)
    assert report.feasible, report.violations
    np.testing.assert_allclose(qd2[[0, -1]], 0.0, atol=1e-12)
    traj.save(tmp_path / "rx90.csv")
    data = np.loadtxt(tmp_path / "rx90.csv", delimiter=",", skiprows=1)
    assert data.shape == (5001, 19)
    np.testing.assert_allclose(robot.to_model(data[:-1, 1:7]), q, atol=1e-8)
    rand = excitation.random_trajectory(robot, 20.0, 5, seed=0, chi_nominal=chi, base=bp)
    assert rand.usage.feasible and traj.cond < 0.5 * rand.cond
