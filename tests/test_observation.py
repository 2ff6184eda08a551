"""The observation matrix (eqs. 6-8) on twin recordings whose truth and noise are known."""
from __future__ import annotations

import numpy as np
import pytest

import identify
import rx90sym

from motions import multisine


@pytest.fixture(scope="module")
def quantised(rx90):
    # No model mismatch: encoder quantisation and Gaussian torque noise only.
    return rx90sym.twin.simulate(rx90, multisine(rx90, 21), duration=20.0, noise="quantised", seed=5)


def test_true_parameters_reproduce_the_torques_to_the_injected_noise(rx90, rx90_base, rx90_truth, quantised):
    beta = np.array([rx90_truth[n] for n in rx90_base.names])
    obs = identify.observation_matrix(rx90, [quantised], base=rx90_base, decimate_to=None)
    sigma = np.asarray(quantised.meta["torque_noise_sigma"])
    for j in range(6):
        rows = obs.joint == j
        rms = np.sqrt(np.mean((obs.Y[rows] - obs.W[rows] @ beta) ** 2))
        # Residual = injected noise (+ a little from the derivatives of quantised positions).
        assert 0.95 * sigma[j] < rms < 1.25 * sigma[j], (j, rms, sigma[j])


def test_parallel_filtering_keeps_y_equal_to_w_beta_and_lowers_the_noise(rx90, rx90_base, rx90_truth, quantised):
    beta = np.array([rx90_truth[n] for n in rx90_base.names])
    # One cut-off for both (the automatic one depends on the decimation: automatic_cutoff).
    full = identify.observation_matrix(rx90, [quantised], base=rx90_base, decimate_to=None, cutoff=10.0)
    dec = identify.observation_matrix(rx90, [quantised], base=rx90_base, decimate_to=25.0, cutoff=10.0)
    assert dec.rate == pytest.approx(25.0) and dec.rows * 10 <= full.rows + 60
    res_full = np.std(full.Y - full.W @ beta)
    res_dec = np.std(dec.Y - dec.W @ beta)
    # The decimation filter passes 0.8 of the new Nyquist: white noise drops by ~sqrt(10 / 0.8).
    assert res_dec < 0.5 * res_full


def test_rows_are_grouped_per_joint_and_the_spring_is_added(rx90, rx90_base, quantised):
    obs = identify.observation_matrix(rx90, [quantised, quantised], base=rx90_base, decimate_to=50.0)
    assert np.all(np.diff(obs.joint) >= 0) and set(obs.joint) == set(range(6))   # eq. 7
    no_spring = identify.observation_matrix(rx90, [quantised, quantised], base=rx90_base,
                                            decimate_to=50.0, spring=False)
    gap = obs.Y - no_spring.Y
    assert np.allclose(gap[obs.joint != 1], 0) and np.abs(gap[obs.joint == 1]).max() > 10


def test_rest_samples_are_dropped_per_joint(rx90, rx90_base, quantised):
    full = identify.observation_matrix(rx90, [quantised], base=rx90_base)
    fewer = identify.observation_matrix(rx90, [quantised], base=rx90_base, min_velocity=0.2)
    assert fewer.rows < full.rows
    assert "50 Hz" in full.summary() and "cut-off" in full.summary()
