"""Segment-bootstrap standard deviations of a least-squares fit.

Eq. 13's covariance σρ²·(WᵀW)⁻¹ assumes white residuals; on real logs the residual is coloured
(unmodelled dynamics, friction hysteresis) and that σ is optimistic. The segment (moving-block)
bootstrap keeps the correlation inside contiguous blocks of samples: draw blocks with replacement,
refit with the same joint weights, and take the spread of the estimates.
"""
from __future__ import annotations

import numpy as np

__all__ = ["segment_bootstrap_std", "bootstrap_std", "BLOCK_S", "DRAWS"]

#: Block length, s: longer than the residual's correlation (filtered at 20-30 Hz, decimated to
#: 50 Hz: a few samples), short enough for ~100 blocks in a 50 s run.
BLOCK_S = 0.5
#: Number of bootstrap refits (the sigma of a sigma estimate from 200 draws is ~5 %).
DRAWS = 200


def segment_bootstrap_std(W: np.ndarray, Y: np.ndarray, joint: np.ndarray, samples: np.ndarray,
                          weights: np.ndarray, block: int, draws: int = 200, seed: int = 0,
                          instruments: np.ndarray | None = None) -> np.ndarray:
    """Standard deviation of each estimate over ``draws`` segment-bootstrap refits.

    Args:
        W: (r, c) observation matrix; Y: (r,) torques; joint: (r,) joint of each row;
        samples: (r,) sample index of each row (rows of one sample go together).
        weights: (n,) joint weights of the fit (1 for OLS); block: samples per block (≥ 1).
        draws: number of bootstrap refits; seed: seeds the draws.
        instruments: (r, c) instruments Z of an instrumental-variable fit (the estimate solves
            ZᵀW x = ZᵀY, e.g. the drive gains' IDIM-IV); None: least squares (Z = W).

    Returns:
        (c,) standard deviations, units of the parameters (NaN where a draw was rank deficient).
    """
    if block < 1 or draws < 2:
        raise ValueError(f"block must be >= 1 sample and draws >= 2, got {block} and {draws}")
    w = np.asarray(weights, dtype=float)[np.asarray(joint)]
    Ww, Yw = W * w[:, None], Y * w
    Zw = Ww if instruments is None else np.asarray(instruments) * w[:, None]
    ids = np.asarray(samples) // block
    blocks = np.unique(ids)
    c = W.shape[1]
    # Per-block normal (or instrumental) equations: a draw is then a weighted sum, not a new QR.
    A = np.zeros((blocks.size, c, c))
    g = np.zeros((blocks.size, c))
    for k, b in enumerate(blocks):
        rows = ids == b
        A[k] = Zw[rows].T @ Ww[rows]
        g[k] = Zw[rows].T @ Yw[rows]
    rng = np.random.default_rng(seed)
    estimates = np.full((draws, c), np.nan)
    for i in range(draws):
        counts = np.bincount(rng.integers(0, blocks.size, blocks.size), minlength=blocks.size)
        M = np.tensordot(counts, A, axes=1)
        if np.linalg.matrix_rank(M) == c:
            estimates[i] = np.linalg.solve(M, counts @ g)
    return np.nanstd(estimates, axis=0, ddof=1)


def bootstrap_std(W: np.ndarray, Y: np.ndarray, joint: np.ndarray, samples: np.ndarray, weights: np.ndarray,
                  rate: float, seed: int = 0, instruments: np.ndarray | None = None) -> np.ndarray:
    """:func:`segment_bootstrap_std` with the toolkit's blocks of BLOCK_S seconds (``rate``: the
    rows' sample rate, Hz) and DRAWS refits; the one bootstrap of identification, payload, drive
    gains and the consistent fit."""
    block = max(1, int(round(BLOCK_S * rate)))
    return segment_bootstrap_std(W, Y, joint, samples, weights, block, DRAWS, seed, instruments)
