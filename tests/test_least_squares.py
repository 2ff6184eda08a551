"""Tests of identify.estimation.least_squares and identify.estimation.results on simulated joint-grouped systems.

Truth is independent of the code under test: known parameters and noise levels, and textbook
formulas evaluated with numpy on the raw (uncompressed) matrices. Every draw is seeded.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from identify.estimation.least_squares import (
    IdentificationError,
    compress,
    stack_systems,
    weighted_least_squares,
)
from identify.estimation.results import EliminationStep, IdentificationResult


def make_w(seed: int, n: int, k: int, rows: int) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Joint-grouped W like a serial arm: joint i rows excite only the parameter groups g >= i.

    So the last joint's block has rank k only (rank-deficient blocks), while the stacked W has
    full rank n·k. Column scales differ by two decades, as parameter units do.
    """
    rng = np.random.default_rng(seed)
    c = n * k
    scale = rng.uniform(0.1, 10.0, c)
    W = np.zeros((n * rows, c))
    for i in range(n):
        W[i * rows:(i + 1) * rows, i * k:] = rng.standard_normal((rows, c - i * k)) * scale[i * k:]
    joint = np.repeat(np.arange(n), rows)
    return W, joint, [f"p{j}" for j in range(c)]


def make_y(W: np.ndarray, joint: np.ndarray, beta: np.ndarray, noise: np.ndarray, seed: int) -> np.ndarray:
    """Torques W·β plus white noise of standard deviation noise[joint] (N·m)."""
    rng = np.random.default_rng(seed)
    return W @ beta + rng.standard_normal(W.shape[0]) * np.asarray(noise)[joint]


def make_beta(seed: int, c: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform(0.5, 2.0, c) * rng.choice([-1.0, 1.0], c)


def block_noise_std(W: np.ndarray, Y: np.ndarray) -> float:
    """Textbook σ of one block's own minimum-norm LS fit with rank-aware dof (raw data)."""
    x = np.linalg.lstsq(W, Y, rcond=None)[0]
    res = Y - W @ x
    return float(np.sqrt(res @ res / (W.shape[0] - np.linalg.matrix_rank(W))))


# --------------------------------------------------------------------------- compress


def test_compress_matches_lstsq_on_raw_data():
    rng = np.random.default_rng(1)
    W = rng.standard_normal((5000, 20)) * rng.uniform(0.1, 10.0, 20)
    y = W @ rng.standard_normal(20) + rng.standard_normal(5000)
    x_ref, rss_ref = np.linalg.lstsq(W, y, rcond=None)[:2]
    for chunk in (700, 5000):  # several chunks, then a single QR
        s = compress(W, y, chunk_rows=chunk)
        x = np.linalg.solve(s.R, s.z)
        assert np.linalg.norm(x - x_ref) <= 1e-10 * np.linalg.norm(x_ref)
        assert s.rss_outside == pytest.approx(rss_ref[0], rel=1e-10)
        assert s.rows == 5000
        assert np.allclose(s.R, np.triu(s.R))
        for x_any in (rng.standard_normal(20), x_ref + 0.1):
            r = W @ x_any - y
            assert s.rss(x_any) == pytest.approx(r @ r, rel=1e-10)


def test_compress_with_fewer_rows_than_columns_keeps_the_identity():
    rng = np.random.default_rng(2)
    W, y = rng.standard_normal((3, 5)), rng.standard_normal(3)
    s = compress(W, y)
    assert s.R.shape == (5, 5)
    x = rng.standard_normal(5)
    assert s.rss(x) == pytest.approx(np.sum((W @ x - y) ** 2), rel=1e-12)


def test_stack_and_select_match_raw_weighted_subsets():
    rng = np.random.default_rng(3)
    W1, W2 = rng.standard_normal((300, 6)), rng.standard_normal((200, 6))
    y1, y2 = rng.standard_normal(300), rng.standard_normal(200)
    s = stack_systems([compress(W1, y1), compress(W2, y2)], weights=[2.0, 0.5]).select([0, 2, 5])
    Wr = np.vstack([2.0 * W1, 0.5 * W2])[:, [0, 2, 5]]
    yr = np.concatenate([2.0 * y1, 0.5 * y2])
    x_ref, rss_ref = np.linalg.lstsq(Wr, yr, rcond=None)[:2]
    assert np.allclose(np.linalg.solve(s.R, s.z), x_ref, rtol=1e-10, atol=1e-12)
    assert s.rss_outside == pytest.approx(rss_ref[0], rel=1e-10)
    assert s.rows == 500


def test_compressed_arrays_are_read_only():
    s = compress(np.eye(4)[:, :2], np.ones(4))
    with pytest.raises(ValueError):
        s.R[0, 0] = 1.0


# --------------------------------------------------------------------------- exact algebra


def test_ols_matches_textbook_formulas():
    W, joint, names = make_w(4, n=3, k=3, rows=60)
    Y = make_y(W, joint, make_beta(4, 9), [0.3, 1.0, 0.5], seed=40)
    res = weighted_least_squares(W, Y, joint, names, weighted=False)
    x = np.linalg.lstsq(W, Y, rcond=None)[0]
    rho = Y - W @ x
    sigma2 = rho @ rho / (W.shape[0] - W.shape[1])  # eq. 12
    std = np.sqrt(np.diag(sigma2 * np.linalg.inv(W.T @ W)))  # eqs. 13-14, raw normal matrix
    assert res.method == "ols"
    assert np.allclose(res.values, x, rtol=1e-9, atol=1e-12)
    assert np.allclose(res.std, std, rtol=1e-8)
    assert np.allclose(res.rel_std_pct, 100 * std / np.abs(x), rtol=1e-8)
    assert res.sigma_rho == pytest.approx(np.sqrt(sigma2), rel=1e-9)
    assert res.cond == pytest.approx(np.linalg.cond(W), rel=1e-9)
    assert res.cond_unweighted == pytest.approx(np.linalg.cond(W), rel=1e-9)
    rms = [np.sqrt(np.mean(rho[joint == i] ** 2)) for i in range(3)]
    assert np.allclose(res.residual_rms, rms, rtol=1e-9)
    assert np.array_equal(res.weights, np.ones(3))
    assert res.rows == W.shape[0]


def test_wls_matches_direct_weighted_solve_on_raw_data():
    W, joint, names = make_w(5, n=3, k=3, rows=80)
    Y = make_y(W, joint, make_beta(5, 9), [0.2, 2.0, 0.7], seed=50)
    res = weighted_least_squares(W, Y, joint, names)
    sigma = np.array([block_noise_std(W[joint == i], Y[joint == i]) for i in range(3)])
    w = (1.0 / sigma)[joint]
    Ww, Yw = W * w[:, None], Y * w
    x = np.linalg.lstsq(Ww, Yw, rcond=None)[0]
    rho = Yw - Ww @ x
    sigma2 = rho @ rho / (W.shape[0] - W.shape[1])
    std = np.sqrt(np.diag(sigma2 * np.linalg.inv(Ww.T @ Ww)))
    assert res.method == "wls"
    assert np.allclose(res.weights, 1.0 / sigma, rtol=1e-9)
    assert np.allclose(res.values, x, rtol=1e-9, atol=1e-12)
    assert np.allclose(res.std, std, rtol=1e-8)
    assert res.sigma_rho == pytest.approx(np.sqrt(sigma2), rel=1e-9)
    assert res.cond == pytest.approx(np.linalg.cond(Ww), rel=1e-9)
    assert res.cond_unweighted == pytest.approx(np.linalg.cond(W), rel=1e-9)
    raw = Y - W @ x
    assert np.allclose(res.residual_rms, [np.sqrt(np.mean(raw[joint == i] ** 2)) for i in range(3)], rtol=1e-9)
    assert np.allclose(res.covariance, sigma2 * np.linalg.inv(Ww.T @ Ww), rtol=1e-7, atol=1e-14)


def test_row_order_and_chunking_do_not_change_the_result():
    W, joint, names = make_w(6, n=3, k=2, rows=150)
    Y = make_y(W, joint, make_beta(6, 6), [1.0, 0.5, 0.2], seed=60)
    ref = weighted_least_squares(W, Y, joint, names)
    perm = np.random.default_rng(61).permutation(W.shape[0])  # interleaved joints
    other = weighted_least_squares(W[perm], Y[perm], joint[perm], names, chunk_rows=37)
    assert np.allclose(other.values, ref.values, rtol=1e-10)
    assert np.allclose(other.std, ref.std, rtol=1e-9)
    assert np.allclose(other.weights, ref.weights, rtol=1e-9)


# --------------------------------------------------------------------------- statistics


def test_wls_weights_recover_injected_noise_per_joint():
    noise = np.array([0.5, 2.0, 1.0, 0.1, 4.0, 0.3])
    W, joint, names = make_w(7, n=6, k=3, rows=2000)
    Y = make_y(W, joint, make_beta(7, 18), noise, seed=70)
    res = weighted_least_squares(W, Y, joint, names)
    assert np.allclose(1.0 / res.weights, noise, rtol=0.10)
    assert res.sigma_rho == pytest.approx(1.0, rel=0.05)  # weighted residual ≈ unit variance
    assert np.allclose(res.residual_rms, noise, rtol=0.10)


def test_joint_noise_uses_the_rank_of_its_own_block():
    """Block 1 sees only 10 of 20 parameters: with 30 rows its dof is 20 (not 30 − 20 = 10)."""
    W, joint, names = make_w(8, n=2, k=10, rows=30)
    beta, noise = make_beta(8, 20), np.array([1.0, 3.0])
    est = np.array([1.0 / weighted_least_squares(W, make_y(W, joint, beta, noise, seed=800 + d), joint, names).weights
                    for d in range(200)])
    mean_var = np.mean(est**2, axis=0)  # σ̂² is unbiased with the right dof
    assert np.allclose(mean_var, noise**2, rtol=0.10)


def test_three_sigma_intervals_cover_the_truth():
    errors, stds = [], []
    for seed in range(10):
        W, joint, names = make_w(100 + seed, n=4, k=6, rows=300)
        beta = make_beta(200 + seed, 24)
        Y = make_y(W, joint, beta, [0.2, 1.0, 3.0, 0.5], seed=300 + seed)
        res = weighted_least_squares(W, Y, joint, names)
        errors.append(np.abs(res.values - beta))
        stds.append(res.std)
    t = np.concatenate(errors) / np.concatenate(stds)
    assert np.mean(t <= 3.0) >= 0.97
    assert 0.55 <= np.mean(t <= 1.0) <= 0.80  # σ is not merely inflated (normal: 0.683)


@pytest.mark.parametrize(
    "weighted, noise",
    # eq. 13 assumes equal noise on every row (eq. 11): OLS only with homoscedastic noise,
    # WLS restores that assumption by weighting.
    [(False, [1.0, 1.0, 1.0]), (True, [0.5, 2.0, 1.0])],
)
def test_eq13_std_matches_monte_carlo_spread(weighted, noise):
    W, joint, names = make_w(9, n=3, k=2, rows=100)
    beta = make_beta(9, 6)
    runs = [weighted_least_squares(W, make_y(W, joint, beta, noise, seed=900 + d), joint, names, weighted=weighted)
            for d in range(200)]
    empirical = np.std([r.values for r in runs], axis=0, ddof=1)
    predicted = np.mean([r.std for r in runs], axis=0)
    assert np.allclose(predicted, empirical, rtol=0.15)


def test_weighting_beats_ols_on_heteroscedastic_noise():
    W, joint, names = make_w(10, n=3, k=2, rows=200)
    beta, noise = make_beta(10, 6), np.array([0.05, 5.0, 0.05])
    wls = [weighted_least_squares(W, make_y(W, joint, beta, noise, seed=1000 + d), joint, names) for d in range(50)]
    ols = [weighted_least_squares(W, make_y(W, joint, beta, noise, seed=1000 + d), joint, names, weighted=False)
           for d in range(50)]
    err = lambda rs: np.sqrt(np.mean([(r.values - beta) ** 2 for r in rs], axis=0))  # noqa: E731
    assert np.all(err(wls) < err(ols))


# --------------------------------------------------------------------------- rank deficiency


@pytest.mark.parametrize("weighted", [False, True])
def test_zero_column_is_named(weighted):
    W, joint, names = make_w(11, n=2, k=3, rows=50)
    W[:, 4] = 0.0
    Y = make_y(W, joint, make_beta(11, 6), [1.0, 1.0], seed=110)
    with pytest.raises(IdentificationError, match="p4") as info:
        weighted_least_squares(W, Y, joint, names, weighted=weighted)
    assert isinstance(info.value, ValueError)
    assert info.value.names == ("p4",)
    assert info.value.rank == 5


def test_proportional_columns_are_both_named():
    W, joint, names = make_w(12, n=2, k=4, rows=50)
    W[:, 6] = 3.0 * W[:, 5]
    Y = make_y(W, joint, make_beta(12, 8), [1.0, 1.0], seed=120)
    with pytest.raises(IdentificationError) as info:
        weighted_least_squares(W, Y, joint, names)
    assert set(info.value.names) == {"p5", "p6"}


def test_combination_of_three_columns_names_the_three():
    W, joint, names = make_w(13, n=2, k=4, rows=50)
    W[:, 7] = W[:, 1] - 2.0 * W[:, 4]
    Y = make_y(W, joint, make_beta(13, 8), [1.0, 1.0], seed=130)
    with pytest.raises(IdentificationError) as info:
        weighted_least_squares(W, Y, joint, names)
    assert set(info.value.names) == {"p1", "p4", "p7"}


# --------------------------------------------------------------------------- input checks


def _small():
    W, joint, names = make_w(14, n=2, k=2, rows=20)
    return W, make_y(W, joint, make_beta(14, 4), [1.0, 1.0], seed=140), joint, names


def test_non_finite_w_is_refused_with_row_and_column():
    W, Y, joint, names = _small()
    W[7, 2] = np.nan
    with pytest.raises(ValueError, match="row 7, column 2"):
        weighted_least_squares(W, Y, joint, names)


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda W, Y, j, n: (W, Y[:-1], j, n), "Y must have shape"),
        (lambda W, Y, j, n: (W, Y, j[:-1], n), "joint must have shape"),
        (lambda W, Y, j, n: (W, Y, np.where(j == 1, 2, j), n), r"joint 2 \(index 1\) has no rows"),
        (lambda W, Y, j, n: (W, Y, j - 1, n), "must be >= 0"),
        (lambda W, Y, j, n: (W, Y, j + 0.5, n), "integer"),
        (lambda W, Y, j, n: (W, Y, j, n[:-1]), "3 names for 4 columns"),
        (lambda W, Y, j, n: (W, Y, j, [n[0]] * 4), "duplicate parameter name"),
    ],
)
def test_bad_inputs_are_refused(mutate, message):
    with pytest.raises(ValueError, match=message):
        weighted_least_squares(*mutate(*_small()))


# --------------------------------------------------------------------------- result object


def test_json_round_trip(tmp_path):
    W, Y, joint, names = _small()
    res = weighted_least_squares(W, Y, joint, names)
    path = res.to_json(tmp_path / "result.json")
    data = json.loads(path.read_text())
    assert data == res.to_dict()
    assert data["method"] == "wls"
    assert [p["name"] for p in data["parameters"]] == names
    assert set(data["parameters"][0]) == {"name", "value", "std", "rel_std_pct"}
    assert len(data["residual_rms"]) == 2 and "sigma_rho" in data and "cond" in data
    back = IdentificationResult.from_json(path)
    assert back.to_dict() == res.to_dict()
    assert back.system is None and back["p0"] == res["p0"]


def test_json_writes_inf_as_null(tmp_path):
    res = IdentificationResult(
        names=("A", "B"), values=[0.0, 2.0], std=[0.1, 0.2], rel_std_pct=[np.inf, 10.0],
        sigma_rho=1.0, cond=3.0, cond_unweighted=np.nan, residual_rms=[0.5], weights=[2.0], rows=10,
        method="wls", history=(EliminationStep("C", 1.01, 1.01, 2, True),),
    )
    text = res.to_json(tmp_path / "r.json").read_text()
    assert "Infinity" not in text and "NaN" not in text
    data = json.loads(text)
    assert data["parameters"][0]["rel_std_pct"] is None and data["cond_unweighted"] is None
    back = IdentificationResult.from_json(tmp_path / "r.json")
    assert np.isinf(back.rel_std_pct[0]) and back.history == res.history


def test_from_json_refuses_missing_field(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps({"method": "wls"}))
    with pytest.raises(ValueError, match="bad.json.*parameters"):
        IdentificationResult.from_json(path)


def test_table_lists_every_parameter():
    W, Y, joint, names = _small()
    res = weighted_least_squares(W, Y, joint, names)
    text = res.table()
    head = text.splitlines()[0].split()
    assert head == ["Parameter", "Estimate", "2σ", "σr", "%"]
    for name in names:
        assert any(line.split()[0] == name for line in text.splitlines()[1:])
    assert "residual RMS per joint" in text


def test_lookup_by_name_and_read_only_arrays():
    W, Y, joint, names = _small()
    res = weighted_least_squares(W, Y, joint, names)
    assert res["p2"] == res.values[2]
    assert res.as_dict() == {n: float(v) for n, v in zip(names, res.values)}
    with pytest.raises(KeyError, match="ZZ1R"):
        res["ZZ1R"]
    with pytest.raises(ValueError):
        res.values[0] = 0.0
