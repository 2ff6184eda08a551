"""The default processing (cut-off, decimation and per-joint rest policy cross-validated inside the
fitted rows) against a plain least squares with a fixed 10 Hz filter, judged on the noise-free
torques of twin runs the fit never sees; the per-joint rest choice on a twin whose friction at rest
differs per joint; the fit file's round trip of a per-joint policy."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import rx90sym
from conftest import benchmark_module
from identify import Processing, fit, load_fit, predict, split
from identify.selection.processing_choice import choose_processing
from motions import multisine
from rx90sym.recording import Recording
from test_presliding import dahl, stop_and_go


def _relative(pred: np.ndarray, truth: np.ndarray) -> np.ndarray:
    return 100 * np.linalg.norm(pred - truth, axis=0) / np.linalg.norm(truth, axis=0)


def _defaults_and_plain(robot, base, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Held-out error per joint (%) of the defaults and of the plain 10 Hz LS, vs noise-free torques."""
    plain = benchmark_module("plain_ls")
    profile = replace(rx90sym.twin.profiles()["quantised"], torque_noise=0.05)
    motion = multisine(robot, seed)
    rec = rx90sym.twin.simulate(robot, motion, duration=20.0, noise=profile, seed=seed)
    clean = rx90sym.twin.simulate(robot, motion, duration=20.0, noise=replace(profile, torque_noise=0.0), seed=seed)
    fit_part, _ = split(rec, 2 / 3)
    _, test = split(clean, 2 / 3)
    f = fit(robot, [fit_part], Processing(estimate_delay=False), base=base)
    assert f.choice is not None  # no cut-off given: cross-validated
    val = predict(robot, f.result, test, base=base, cutoff=f.cutoff, decimate_to=None,
                  min_velocity=f.min_velocity, rest=f.rest)
    baseline = plain.plain_ls(robot, fit_part)
    pred, kept = plain.plain_prediction(robot, baseline, test)
    return _relative(val.predicted, val.measured), _relative(pred, np.asarray(test.tau)[kept])


@pytest.mark.slow
def test_the_defaults_beat_a_plain_10_hz_least_squares_on_every_joint(rx90, rx90_base):
    ratios = []
    for seed in (0, 1, 2):
        ours, plain = _defaults_and_plain(rx90, rx90_base, seed)
        ratios.append(ours / plain)
    ratios = np.array(ratios)
    # Measured (5 % torque noise), ours / plain per joint: medians over seeds 0-2 0.62 0.37 0.67 0.37
    # 0.23 0.20 (over seeds 0-4: at most 0.63); single runs up to 1.21 (seed 4, joint 1).
    assert np.all(np.median(ratios, axis=0) < 0.85), ratios
    assert np.all(ratios < 1.5), ratios


def test_the_rest_policy_is_chosen_per_joint_from_the_twins_friction(rx90, rx90_base):
    """Joints 1-3 held at rest by a Dahl state (presliding friction), joints 4-6 with Coulomb
    friction on the speed only (0 at rest): presliding on 1-3, mostly not on 4-6."""
    chi = rx90.parameter_vector(rx90sym.twin.default_parameters(rx90))
    t, q, qd, qdd = stop_and_go(rx90, 0)
    fs = chi[rx90.parameter_index([f"FS{j}" for j in range(1, rx90.n + 1)])]
    no_coulomb = np.array([0.0 if name.startswith("FS") else 1.0 for name in rx90.parameter_names])
    state = np.where(np.arange(rx90.n) < 3, dahl(q, 0.005), np.sign(qd))
    tau = rx90.regressor_batch(q, qd, qdd) @ (chi * no_coulomb) + fs * state - rx90.spring_torque_batch(q)[:, :, 0]
    tau += 0.01 * np.sqrt(np.mean(tau**2, axis=0)) * np.random.default_rng(100).normal(size=tau.shape)
    fit_part, _ = split(Recording(t=t, q=q, tau=tau, dq=qd, robot=rx90.name), 2 / 3)
    # presliding is scored on request only (not by the defaults: SCORED_REST says why)
    choice = choose_processing(rx90, [fit_part], base=rx90_base, policies=("zero-coulomb", "presliding", "crossing"))
    rest = choice.chosen.rest
    assert rest[:3] == ("presliding",) * 3, choice.reason()
    # Joints 4-6: no hold torque; below the threshold at the end of each move the friction still
    # follows the motion, which crossing keeps (measured, seed 0: crossing on joints 5, 6; presliding
    # on joint 4, 8.8 % against 9.7 % for zero-coulomb, its FP4 fitting that tail).
    assert sum(r != "presliding" for r in rest[3:]) >= 2, choice.reason()
    f = fit(rx90, [fit_part], Processing(estimate_delay=False), base=rx90_base)  # the defaults: no presliding
    assert "presliding" not in f.rest and f.choice["rest_scores_pct"] and "rest per joint" in f.choice["reason"]


def test_a_per_joint_rest_policy_round_trips_through_the_fit_file(rx90, rx90_base, tmp_path):
    rec = rx90sym.twin.simulate(rx90, multisine(rx90, 3, duration=6.0), duration=6.0, noise="ideal", seed=3)
    rest = ("crossing", "zero-coulomb", "presliding", "none", "drop", "zero-coulomb")
    f = fit(rx90, [rec], Processing(cutoff=5.0, rest=rest, estimate_delay=False), base=rx90_base)
    assert f.rest == rest and f.choice is None
    f.save(tmp_path / "fit.json")
    back = load_fit(tmp_path / "fit.json", rx90)
    assert back.rest == rest and back.processing == f.processing
    # predict follows it: the same torques as the fit's own prediction
    np.testing.assert_allclose(back.predict(rec).predicted, f.predict(rec).predicted, rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="rest must be one of"):
        Processing(rest=("zero-coulomb", "sometimes"))


def test_crossing_keeps_short_or_travelling_passes_and_zeroes_still_rests():
    from identify.observation.rest import crossing_passes

    mask = np.array([0, 1, 1, 0, 1, 1, 1, 1, 1, 0, 1, 1, 1, 1, 1], dtype=bool)
    q = np.r_[np.zeros(10), 0.0, 0.001, 0.002, 0.003, 0.004]  # still rest, then a slow motion
    # the run of 2 is short (< 3 samples); the still run of 5 is a rest; the last run travels
    expected = np.array([0, 1, 1, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1], dtype=bool)
    np.testing.assert_array_equal(crossing_passes(mask, q, 3, 5e-4), expected)
