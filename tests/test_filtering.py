"""Filtering: zero-phase low-pass, cut-off rule, derivatives (eq. 20), parallel decimation."""

from __future__ import annotations

import numpy as np
import pytest

from identify.signal.filtering import (
    EDGE_PERIODS,
    choose_cutoff,
    crossover_frequencies,
    decimate,
    decimation_factor,
    derivatives,
    lowpass,
)

RATE = 250.0                     # Hz, the paper's sampling rate (§III-A)
ENCODER_STEP = 2 * np.pi / 2**20  # rad, a 20-bit encoder


def multisine(t: np.ndarray, n: int, base: float, harmonics: int, seed: int):
    """Finite Fourier series per joint (like an excitation trajectory) and its exact derivatives."""
    rng = np.random.default_rng(seed)
    k = np.arange(1, harmonics + 1)
    w = 2 * np.pi * base * k
    a = rng.normal(0.0, 0.5, (n, harmonics)) / k  # amplitudes decay like a smooth trajectory
    b = rng.normal(0.0, 0.5, (n, harmonics)) / k
    s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))  # (N, H)
    q = s @ a.T + c @ b.T
    dq = (c * w) @ a.T - (s * w) @ b.T
    ddq = -(s * w**2) @ a.T - (c * w**2) @ b.T
    return q, dq, ddq


def measured(q: np.ndarray, noise: float, seed: int) -> np.ndarray:
    """Encoder reading: white noise, then quantisation to the encoder step."""
    rng = np.random.default_rng(seed)
    return np.round((q + rng.normal(0.0, noise, q.shape)) / ENCODER_STEP) * ENCODER_STEP


def rel_rms(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean((estimate - truth) ** 2, axis=0) / np.mean(truth**2, axis=0))


# ---------------------------------------------------------------------------------------------
# lowpass
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("ratio", [0.2, 0.5, 1.0, 2.0])
def test_lowpass_gain_is_squared_butterworth_without_phase(ratio):
    # forward-backward digital Butterworth of order 4 (bilinear transform, frequency prewarped):
    # |H|^2 = 1 / (1 + (tan(pi f/rate) / tan(pi fc/rate))^8), zero phase
    fc = 10.0
    t = np.arange(5000) / RATE
    x = np.sin(2 * np.pi * ratio * fc * t)
    y = lowpass(x, RATE, fc)
    gain = 1.0 / (1.0 + (np.tan(np.pi * ratio * fc / RATE) / np.tan(np.pi * fc / RATE)) ** 8)
    middle = slice(1000, 4000)  # away from the edges
    np.testing.assert_allclose(y[middle], gain * x[middle], atol=2e-4)


def test_lowpass_rejects_bad_cutoff():
    x = np.zeros((100, 2))
    for bad in (0.0, -1.0, RATE / 2, 200.0):
        with pytest.raises(ValueError, match="cutoff"):
            lowpass(x, RATE, bad)


# ---------------------------------------------------------------------------------------------
# derivatives against the analytic truth
# ---------------------------------------------------------------------------------------------

# Bounds, for 250 Hz, harmonics up to 0.5 Hz, noise 1e-5 rad + 20-bit quantisation (6e-6 rad):
# * bias: the filter changes a 0.5 Hz component by (0.5/fc)^8 < 1e-6 for fc >= 2 Hz; eq. 20 has a
#   truncation error (ωT)²/6 = 2.6e-5 for q̇, about twice that for q̈ (applied twice);
# * noise: white noise σ filtered at fc then differentiated has an RMS of
#   σ·2π·sqrt(2·fc³/(3·rate)) for q̇ and σ·(2π)²·sqrt(2·fc⁵/(5·rate)) for q̈, i.e. 2.5e-5 rad/s and
#   4.5e-4 rad/s² at fc ≈ 4 Hz, against RMS of 0.35–0.83 rad/s and 0.77–2.2 rad/s² for this
#   trajectory: at most 7e-5 and 6e-4 relative (measured: 3–7e-5 and 2–6e-4).
# The bounds keep > 8x margin on these figures; barely filtered (cut-off at 40 % of Nyquist)
# the q̈ error is 8–23 %, so the test does fail when the filtering is wrong.
DQ_BOUND = 1e-3
DDQ_BOUND = 5e-3


def test_derivatives_match_analytic_multisine():
    t = np.arange(int(20 * RATE)) / RATE
    q, dq, ddq = multisine(t, n=6, base=0.1, harmonics=5, seed=1)
    d = derivatives(t, measured(q, noise=1e-5, seed=2))
    k = d.kept
    err_dq = rel_rms(d.dq, dq[k])
    err_ddq = rel_rms(d.ddq, ddq[k])
    print(f"\ncut-off chosen: {d.cutoff:.2f} Hz, kept samples {k.start}..{k.stop} of {t.size}")
    print("relative RMS error dq :", np.array2string(err_dq, formatter={"float": "{:.2e}".format}))
    print("relative RMS error ddq:", np.array2string(err_ddq, formatter={"float": "{:.2e}".format}))
    assert np.all(err_dq < DQ_BOUND)
    assert np.all(err_ddq < DDQ_BOUND)
    assert np.array_equal(d.t, t[k])
    # the same data, barely filtered: the bound is violated (the test can fail)
    raw = derivatives(t, measured(q, noise=1e-5, seed=2), cutoff=0.4 * RATE / 2, edge=k.start)
    assert np.max(rel_rms(raw.ddq, ddq[k])) > 10 * DDQ_BOUND


def test_derivatives_edges_and_shapes():
    t = np.arange(1000) / RATE
    q, _, _ = multisine(t, n=1, base=0.5, harmonics=3, seed=4)
    d = derivatives(t, q[:, 0], cutoff=10.0)  # 1-D input stays 1-D
    edge = int(np.ceil(EDGE_PERIODS * RATE / 10.0))
    assert d.kept == slice(edge, 1000 - edge)
    assert d.q.shape == d.dq.shape == d.ddq.shape == d.t.shape == (1000 - 2 * edge,)
    assert np.all(np.isfinite(d.ddq)) and d.cutoff == 10.0 and d.rate == pytest.approx(RATE)
    d2 = derivatives(t, q, cutoff=10.0, edge=2)
    assert d2.kept == slice(2, 998) and np.all(np.isfinite(d2.ddq))
    with pytest.raises(ValueError, match="edge"):
        derivatives(t, q, cutoff=10.0, edge=1)
    t_bad = t.copy()
    t_bad[500:] += 0.5 / RATE
    with pytest.raises(ValueError, match="irregular time step at sample 501"):
        derivatives(t_bad, q, cutoff=10.0)


# ---------------------------------------------------------------------------------------------
# choose_cutoff
# ---------------------------------------------------------------------------------------------


def test_cutoff_above_signal_band_and_well_below_nyquist():
    t = np.arange(int(30 * RATE)) / RATE
    f_max = 2.0  # harmonics of 0.2 Hz up to 2 Hz
    q, _, _ = multisine(t, n=3, base=0.2, harmonics=10, seed=5)
    still = np.zeros((t.size, 1))  # a joint at rest: only noise, it must not vote
    q = measured(np.hstack([q, still]), noise=1e-4, seed=6)
    per_joint = crossover_frequencies(q, RATE)
    cutoff = choose_cutoff(q, RATE)
    print(f"\nband up to {f_max} Hz, crossovers {np.array2string(per_joint, precision=2)} Hz, cut-off {cutoff:.2f} Hz")
    assert np.isnan(per_joint[3])
    assert f_max < cutoff < 0.1 * RATE / 2  # above the band, at most 10 % of Nyquist


def test_cutoff_falls_as_noise_rises():
    t = np.arange(int(30 * RATE)) / RATE
    q, _, _ = multisine(t, n=2, base=0.2, harmonics=5, seed=7)
    cutoffs = [choose_cutoff(measured(q, noise, seed=8), RATE, min_cutoff=0.1) for noise in (1e-6, 1e-5, 1e-4, 1e-3)]
    print("\ncut-offs for noise 1e-6..1e-3 rad:", np.round(cutoffs, 2))
    assert all(a >= b for a, b in zip(cutoffs, cutoffs[1:]))
    assert cutoffs[0] > 2 * cutoffs[-1]
    assert cutoffs[-1] > 1.0  # still above the 1 Hz band


def test_cutoff_bounds():
    t = np.arange(2000) / RATE
    rest = measured(np.zeros((t.size, 2)), noise=1e-5, seed=9)
    assert choose_cutoff(rest, RATE) == 2.0  # nothing moves: the floor
    slow, _, _ = multisine(t, n=1, base=0.05, harmonics=1, seed=10)
    assert choose_cutoff(measured(slow, 1e-3, seed=11), RATE) >= 2.0
    assert choose_cutoff(slow, 8.0) == pytest.approx(0.4 * 4.0)  # the ceiling wins at low rates
    with pytest.raises(ValueError, match="at least 64 samples"):
        choose_cutoff(slow[:10], RATE)


# ---------------------------------------------------------------------------------------------
# decimation
# ---------------------------------------------------------------------------------------------


def test_decimation_factor():
    assert decimation_factor(5000.0, 250.0) == 20
    assert decimation_factor(250.0, 250.0) == 1
    with pytest.raises(ValueError, match="2.5 is not an integer"):
        decimation_factor(250.0, 100.0)
    with pytest.raises(ValueError, match="above the sampling rate"):
        decimation_factor(100.0, 250.0)


@pytest.mark.parametrize(
    ("ftype", "atol"),
    # iir: Chebyshev I with 0.05 dB ripple, passed forward and backward in each of the 2 stages
    # (20 = 10 x 2): gain within 0.2 dB, i.e. 2.3 %; fir: flat passband.
    [("iir", 0.023), ("fir", 1e-3)],
)
def test_decimate_removes_what_the_new_rate_cannot_hold(ftype, atol):
    rate, factor = 5000.0, 20  # -> 250 Hz, new Nyquist 125 Hz
    t = np.arange(20000) / rate
    slow = np.sin(2 * np.pi * 3.0 * t)
    fast = 0.5 * np.sin(2 * np.pi * 1210.0 * t)  # would alias to 10 Hz if merely sub-sampled
    y = decimate(slow + fast, factor, ftype=ftype)
    assert y.shape == (1000,)
    middle = slice(100, 900)
    np.testing.assert_allclose(y[middle], slow[::factor][middle], atol=atol)
    assert np.max(np.abs((slow + fast)[::factor][middle] - slow[::factor][middle])) > 0.4  # aliasing without it


def test_parallel_decimation_keeps_y_equal_w_chi():
    # Y = W chi sample by sample; filtering Y and every column of W alike keeps the relation.
    rng = np.random.default_rng(12)
    n_samples, n_joints, n_params = 3000, 3, 5
    t = np.arange(n_samples) / 1000.0
    W = np.sin(np.outer(t, rng.uniform(1, 40, n_joints * n_params))).reshape(n_samples, n_joints, n_params)
    W += 0.1 * rng.normal(size=W.shape)
    chi = rng.normal(size=n_params)
    Y = W @ chi
    Wd, Yd = decimate(W, 4), decimate(Y, 4)
    assert Wd.shape == (750, n_joints, n_params) and Yd.shape == (750, n_joints)
    np.testing.assert_allclose(Wd @ chi, Yd, rtol=0, atol=1e-10)
    assert not np.allclose(decimate(Y, 4), Y[::4], atol=1e-2)  # it did filter
    with pytest.raises(ValueError, match="factor"):
        decimate(Y, 0)
