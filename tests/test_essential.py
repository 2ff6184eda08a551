"""Tests of identify.estimation.essential: backward elimination with the σ_pe ≥ 1.02·σρ0 stop (paper §II-B).

Truth: simulated systems where some parameters are exactly zero, and direct weighted least
squares on the raw columns kept. Every draw is seeded.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from identify.estimation.essential import essential_parameters
from identify.estimation.least_squares import weighted_least_squares
from identify.estimation.results import IdentificationResult

IRRELEVANT = (1, 8, 13, 17)


def simulate(seed: int, rows: int = 500) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str], np.ndarray]:
    """3 joints, 18 parameters, joint i exciting parameters 6i..17; β = 0 on IRRELEVANT."""
    rng = np.random.default_rng(seed)
    n, k = 3, 6
    c = n * k
    W = np.zeros((n * rows, c))
    for i in range(n):
        W[i * rows:(i + 1) * rows, i * k:] = rng.standard_normal((rows, c - i * k)) * rng.uniform(0.2, 5.0, c - i * k)
    joint = np.repeat(np.arange(n), rows)
    beta = rng.uniform(1.0, 3.0, c) * rng.choice([-1.0, 1.0], c)
    beta[list(IRRELEVANT)] = 0.0
    noise = np.array([0.2, 0.5, 0.1])
    Y = W @ beta + rng.standard_normal(n * rows) * noise[joint]
    return W, Y, joint, [f"p{j}" for j in range(c)], beta


def direct_fit(W, Y, joint, weights, keep):
    """Weighted LS on the raw kept columns: solution and σ_pe (eq. 12 with r − c_k)."""
    w = np.asarray(weights)[joint]
    Ww, Yw = W[:, keep] * w[:, None], Y * w
    x = np.linalg.lstsq(Ww, Yw, rcond=None)[0]
    rho = Yw - Ww @ x
    return x, float(np.sqrt(rho @ rho / (W.shape[0] - len(keep))))


@pytest.mark.parametrize("seed", range(5))
def test_removes_exactly_the_irrelevant_parameters_then_stops(seed):
    W, Y, joint, names, _ = simulate(seed)
    wls = weighted_least_squares(W, Y, joint, names)
    ess = essential_parameters(wls)
    removed = [s.removed for s in ess.history if s.accepted]
    assert sorted(removed) == sorted(names[j] for j in IRRELEVANT)
    assert ess.names == tuple(n for j, n in enumerate(names) if j not in IRRELEVANT)
    assert ess.method == "essential"
    stop = ess.history[-1]
    assert not stop.accepted and stop.ratio >= 1.02  # the refused trial
    assert all(s.ratio < 1.02 for s in ess.history[:-1])
    assert ess.sigma_rho < 1.02 * wls.sigma_rho
    assert ess.sigma_rho == pytest.approx(ess.history[-2].sigma_pe, rel=1e-9)


def test_first_removal_is_the_largest_relative_std():
    W, Y, joint, names, _ = simulate(10)
    wls = weighted_least_squares(W, Y, joint, names)
    ess = essential_parameters(wls)
    assert ess.history[0].removed == names[int(np.argmax(wls.rel_std_pct))]


def test_every_trial_matches_a_direct_solve_on_raw_data():
    W, Y, joint, names, _ = simulate(11)
    wls = weighted_least_squares(W, Y, joint, names)
    ess = essential_parameters(wls)
    keep = list(range(len(names)))
    for step in ess.history:
        keep = [j for j in keep if names[j] != step.removed]
        _, sigma_pe = direct_fit(W, Y, joint, wls.weights, keep)
        assert step.sigma_pe == pytest.approx(sigma_pe, rel=1e-9)
        assert step.ratio == pytest.approx(sigma_pe / wls.sigma_rho, rel=1e-9)
        assert step.parameters_left == len(keep)
    kept = [names.index(n) for n in ess.names]
    x, sigma_pe = direct_fit(W, Y, joint, wls.weights, kept)
    assert np.allclose(ess.values, x, rtol=1e-9)
    assert ess.sigma_rho == pytest.approx(sigma_pe, rel=1e-9)
    assert np.array_equal(ess.weights, wls.weights)
    raw = Y - W[:, kept] @ x
    assert np.allclose(ess.residual_rms, [np.sqrt(np.mean(raw[joint == i] ** 2)) for i in range(3)], rtol=1e-9)


def test_essential_three_sigma_intervals_cover_the_truth():
    t = []
    for seed in range(20):
        W, Y, joint, names, beta = simulate(100 + seed)
        ess = essential_parameters(weighted_least_squares(W, Y, joint, names))
        truth = np.array([beta[names.index(n)] for n in ess.names])
        t.append(np.abs(ess.values - truth) / ess.std)
    t = np.concatenate(t)
    assert np.mean(t <= 3.0) >= 0.97
    assert 0.55 <= np.mean(t <= 1.0) <= 0.80  # normal: 0.683


def test_threshold_below_one_keeps_every_parameter():
    W, Y, joint, names, _ = simulate(13)
    wls = weighted_least_squares(W, Y, joint, names)
    ess = essential_parameters(wls, threshold=0.5)
    assert ess.names == wls.names
    assert len(ess.history) == 1 and not ess.history[0].accepted
    assert np.allclose(ess.values, wls.values, rtol=1e-10)


def test_huge_threshold_stops_at_min_parameters():
    W, Y, joint, names, _ = simulate(14)
    ess = essential_parameters(weighted_least_squares(W, Y, joint, names), threshold=1e9, min_parameters=3)
    assert len(ess.names) == 3
    assert all(s.accepted for s in ess.history) and len(ess.history) == len(names) - 3


def test_works_on_ols_results_too():
    W, Y, joint, names, _ = simulate(15)
    ess = essential_parameters(weighted_least_squares(W, Y, joint, names, weighted=False))
    assert sorted(s.removed for s in ess.history if s.accepted) == sorted(names[j] for j in IRRELEVANT)


def test_history_is_in_json(tmp_path):
    W, Y, joint, names, _ = simulate(16)
    ess = essential_parameters(weighted_least_squares(W, Y, joint, names))
    data = json.loads(ess.to_json(tmp_path / "ess.json").read_text())
    assert data["method"] == "essential"
    assert [h["removed"] for h in data["history"]] == [s.removed for s in ess.history]
    assert data["history"][-1]["accepted"] is False


def test_refuses_results_without_compressed_system(tmp_path):
    W, Y, joint, names, _ = simulate(17)
    path = weighted_least_squares(W, Y, joint, names).to_json(tmp_path / "r.json")
    with pytest.raises(ValueError, match="result.system"):
        essential_parameters(IdentificationResult.from_json(path))


@pytest.mark.parametrize("threshold", [0.0, -1.0, float("inf"), float("nan")])
def test_refuses_bad_threshold(threshold):
    W, Y, joint, names, _ = simulate(18, rows=50)
    with pytest.raises(ValueError, match="threshold"):
        essential_parameters(weighted_least_squares(W, Y, joint, names), threshold=threshold)
