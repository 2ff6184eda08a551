"""Sequential design (--complement) and payload excitation (--for payload), issue 15."""
from __future__ import annotations

import numpy as np
import pytest

import excitation
from excitation.complement import prior_information
from excitation.criterion import regressor_samples
from excitation.fourier import FourierSeries
from excitation.multistart import optimise_model
from excitation.objective import Objective, numeric_information
from test_excitation import BETA, FAST, NAMES, toy_model, toy_regressor

NOISE = np.array([0.8, 0.3])


def _info(traj, objective):
    t, q, qd, qdd = traj.sample(objective.rate)
    return numeric_information(regressor_samples(toy_regressor(), q, qd, qdd), objective, traj.duration)


def test_prior_information_counts_a_recording_like_seconds_of_trajectory():
    traj = excitation.random_feasible(toy_model(), FourierSeries(4.0, 3), seed=2, options=FAST)
    objective = Objective("logdet", NOISE, rate=FAST.cond_rate)
    # the same motion recorded at 4x the rate carries the same information (counted per second);
    # the Coulomb sign columns make the sums differ a little between rates
    prior = prior_information(toy_regressor(), [traj.sample(4 * FAST.cond_rate)], objective)
    info = _info(traj, objective)
    assert np.linalg.norm(prior - info) < 0.01 * np.linalg.norm(info)
    twice = prior_information(toy_regressor(), [traj.sample(FAST.cond_rate)] * 2, objective)
    np.testing.assert_allclose(twice, 2 * _info(traj, objective), rtol=1e-9)


def test_complementing_trajectory_fills_what_the_recording_missed():
    # the recording moves joint 2 only a little; the complement, optimised with the recording's
    # information added, does better on the combined criterion than a trajectory optimised alone
    weak = excitation.random_feasible(toy_model(), FourierSeries(4.0, 3), seed=5, options=FAST)
    t, q, qd, qdd = weak.sample(FAST.cond_rate)
    centre = q[:, 1].mean()
    recording = (t, np.c_[q[:, 0], centre + 0.05 * (q[:, 1] - centre)], np.c_[qd[:, 0], 0.05 * qd[:, 1]],
                 np.c_[qdd[:, 0], 0.05 * qdd[:, 1]])
    reference = excitation.reference_magnitudes(BETA, NAMES)
    alone = Objective("sigma", NOISE, reference, rate=FAST.cond_rate)
    combined = Objective("sigma", NOISE, reference, prior=prior_information(toy_regressor(), [recording], alone),
                         rate=FAST.cond_rate)
    gains = []
    for seed in range(2):
        plain = optimise_model(toy_model(), FourierSeries(4.0, 3), seed=seed, starts=1, progress=False,
                               options=excitation.OptimiserOptions(**{**vars(FAST), "criterion": alone}))
        comp = optimise_model(toy_model(), FourierSeries(4.0, 3), seed=seed, starts=1, progress=False,
                              options=excitation.OptimiserOptions(**{**vars(FAST), "criterion": combined}))
        assert comp.info.criterion_value == pytest.approx(combined.value(_info(comp, combined)), rel=1e-9)
        gains.append(combined.value(_info(plain, combined)) - comp.info.criterion_value)
    assert min(gains) > 0.0, gains


@pytest.fixture(scope="module")
def rx90():
    rx90sym = pytest.importorskip("rx90sym")
    robot = rx90sym.load_robot("rx90")
    return robot, rx90sym.base_parameters(robot), robot.parameter_vector(rx90sym.default_parameters(robot))


def test_payload_regressor_is_the_torque_the_payload_adds(rx90):
    # independent route: inverse dynamics with and without the payload merged into link 6
    from excitation.payload_design import payload_regressor
    from rx90sym.parameters import PAYLOAD_NAMES
    from rx90sym.payloads import add_payload, as_payload

    robot, _, chi = rx90
    rng = np.random.default_rng(0)
    values = as_payload("tables_4")
    chi_c = np.array([values[n] for n in PAYLOAD_NAMES])
    for _ in range(3):
        q, qd, qdd = (rng.uniform(-1.5, 1.5, 6) for _ in range(3))
        added = np.asarray(robot.inverse_dynamics(q, qd, qdd, add_payload(robot, chi, "tables_4"))
                           - robot.inverse_dynamics(q, qd, qdd, chi)).ravel()
        np.testing.assert_allclose(np.asarray(payload_regressor(robot)(q, qd, qdd)) @ chi_c, added,
                                   rtol=1e-9, atol=1e-9)


def test_payload_sigma_methods_3_and_4_agree_on_one_motion_and_4_matches_the_stacked_system(rx90):
    from excitation.api import default_noise
    from excitation.payload_design import payload_sigma

    robot, bp, chi = rx90
    a = excitation.random_trajectory(robot, 6.0, 2, seed=1, chi_nominal=chi, base=bp)
    b = excitation.random_trajectory(robot, 6.0, 2, seed=2, chi_nominal=chi, base=bp)
    noise = default_noise(robot.limits)
    same = payload_sigma(robot, bp.regressor, a, noise, rate=100.0)
    # Wc = Wb Kc lies in the range of Wb: the global system (eq. 29) on one motion is method 3
    np.testing.assert_allclose(list(same["method_4"].values()), list(same["method_3"].values()), rtol=1e-6)
    other = payload_sigma(robot, bp.regressor, a, noise, empty=b, rate=100.0)
    # eq. 29 by another route: the stacked system [[Wb_empty, 0], [Wb_loaded, Wc]] (rows / noise)
    # and the covariance from its pseudo-inverse
    from excitation.payload_design import payload_regressor

    def rows(traj, f):
        t, q, qd, qdd = traj.sample(100.0)
        phi = regressor_samples(f, q, qd, qdd) / noise[None, :, None]
        return phi.reshape(-1, phi.shape[2])

    wb_e, wb_l, wc = rows(b, bp.regressor), rows(a, bp.regressor), rows(a, payload_regressor(robot))
    stacked = np.block([[wb_e, np.zeros((wb_e.shape[0], 10))], [wb_l, wc]])
    pinv = np.linalg.pinv(stacked)
    sigma = np.sqrt(np.sum(pinv ** 2, axis=1))[-10:]
    np.testing.assert_allclose(list(other["method_4"].values()), sigma, rtol=1e-6)


@pytest.mark.slow
def test_payload_motion_beats_a_random_one_on_its_criterion(rx90):
    from excitation.api import default_noise, optimise_payload
    from excitation.payload_design import payload_model, payload_objective, payload_regressor

    robot, bp, chi = rx90
    objective = payload_objective("tables_4", default_noise(robot.limits))
    traj = optimise_payload(robot, 6.0, None, harmonics=2, chi_nominal=chi, base=bp, starts=1, progress=False)
    assert traj.usage.feasible and np.all(np.isfinite(traj.usage.torque))
    rnd = excitation.random_feasible(payload_model(robot, bp, chi, "tables_4"), FourierSeries(6.0, 2), seed=0)
    t, q, qd, qdd = rnd.sample(250.0)
    value_random = objective.value(numeric_information(regressor_samples(payload_regressor(robot), q, qd, qdd),
                                                       objective, 6.0))
    # measured: -9.6 optimised vs -6.0 random (log variance: sigmas 6x smaller); margin 1.0
    assert traj.info.criterion_value < value_random - 1.0, (traj.info.criterion_value, value_random)


def test_controller_export_with_approach_move_holds_limits_by_finite_differences(tmp_path):
    from excitation.controller_export import Controller, export_for_controller
    from test_excitation import toy_limits

    traj = excitation.random_feasible(toy_model(), FourierSeries(4.0, 3), seed=0, options=FAST)
    start = traj.start_position() + traj.controller_offsets + np.array([1.0, -0.8])
    limits = toy_limits()
    path = export_for_controller(traj, tmp_path / "ur.csv", "ur", limits, start)
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    t, q = data[:, 0], data[:, 1:3]
    np.testing.assert_allclose(np.diff(t), 1 / 500.0, rtol=1e-9)            # UR servoj period
    np.testing.assert_allclose(q[0], start, atol=1e-12)
    np.testing.assert_allclose(q[-1], start, atol=1e-12)  # the return: back to the start pose
    qd = np.diff(q, axis=0) * 500.0                                          # independent of the file's dq
    qdd = np.diff(qd, axis=0) * 500.0
    assert np.all(np.abs(qd) <= limits.qd_max * 1.001)
    assert np.all(np.abs(qdd) <= limits.qdd_max * 1.01)
    n_traj = int(round(4.0 * 500)) + 1
    approach = (t.size - n_traj) // 2  # the same move there and back
    assert approach > 0 and t[approach] == pytest.approx(approach / 500.0)
    for k in (approach, approach + n_traj - 1):  # the trajectory's first and last rows: its start
        np.testing.assert_allclose(q[k], traj.start_position() + traj.controller_offsets, atol=1e-9)
    with pytest.raises(ValueError, match=r"joint \d jerk .* at t = .* exceeds the limit 1 rad/s\^3"):
        export_for_controller(traj, tmp_path / "f.csv", Controller("strict", 1000.0, (1.0, 1.0)), limits, start)
    assert not (tmp_path / "f.csv").exists()
