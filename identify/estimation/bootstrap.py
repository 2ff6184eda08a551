"""Segment-bootstrap standard deviations of a least-squares fit.

Eq. 13's covariance σρ²·(WᵀW)⁻¹ assumes white residuals; on real logs the residual is coloured
(unmodelled dynamics, friction hysteresis) and that σ is optimistic. The segment (moving-block)
bootstrap keeps the correlation inside contiguous blocks of samples: draw blocks with replacement,
refit with the same joint weights, and take the spread of the estimates.
"""
from __future__ import annotations

import numpy as np

__all__ = ["segment_bootstrap_draws", "segment_bootstrap_std"]


def segment_bootstrap_std(W: np.ndarray, Y: np.ndarray, joint: np.ndarray, samples: np.ndarray,
                          weights: np.ndarray, block: int, draws: int = 200, seed: int = 0) -> np.ndarray:
    """Standard deviation of each estimate over ``draws`` segment-bootstrap refits
    (:func:`segment_bootstrap_draws`; NaN where a draw was rank deficient)."""
    return np.nanstd(segment_bootstrap_draws(W, Y, joint, samples, weights, block, draws, seed), axis=0, ddof=1)


def segment_bootstrap_draws(W: np.ndarray, Y: np.ndarray, joint: np.ndarray, samples: np.ndarray,
                            weights: np.ndarray, block: int, draws: int = 200, seed: int = 0) -> np.ndarray:
    """The ``draws`` segment-bootstrap least-squares estimates, (draws, c).

    Args:
        W: (r, c) observation matrix; Y: (r,) torques; joint: (r,) joint of each row;
        samples: (r,) sample index of each row (rows of one sample go together).
        weights: (n,) joint weights of the fit (1 for OLS); block: samples per block (≥ 1).
        draws: number of bootstrap refits; seed: seeds the draws.

    Returns:
        (draws, c) estimates, units of the parameters (a row of NaN where a draw was rank deficient).
    """
    if block < 1 or draws < 2:
        raise ValueError(f"block must be >= 1 sample and draws >= 2, got {block} and {draws}")
    w = np.asarray(weights, dtype=float)[np.asarray(joint)]
    Ww, Yw = W * w[:, None], Y * w
    ids = np.asarray(samples) // block
    blocks = np.unique(ids)
    c = W.shape[1]
    # Per-block normal equations: a draw is then a weighted sum, not a new QR.
    A = np.zeros((blocks.size, c, c))
    g = np.zeros((blocks.size, c))
    for k, b in enumerate(blocks):
        rows = ids == b
        A[k] = Ww[rows].T @ Ww[rows]
        g[k] = Ww[rows].T @ Yw[rows]
    rng = np.random.default_rng(seed)
    estimates = np.full((draws, c), np.nan)
    for i in range(draws):
        counts = np.bincount(rng.integers(0, blocks.size, blocks.size), minlength=blocks.size)
        M = np.tensordot(counts, A, axes=1)
        if np.linalg.matrix_rank(M) == c:
            estimates[i] = np.linalg.solve(M, counts @ g)
    return estimates
