"""Segment-bootstrap standard deviations of a least-squares fit.

Eq. 13's covariance σρ²·(WᵀW)⁻¹ assumes white residuals; on real logs the residual is coloured
(unmodelled dynamics, friction hysteresis) and that σ is optimistic. The segment (moving-block)
bootstrap keeps the correlation inside contiguous blocks of samples: draw blocks with replacement,
refit with the same joint weights, and take the spread of the estimates.
"""
from __future__ import annotations

import warnings

from typing import Sequence

import numpy as np

__all__ = ["SegmentBootstrap", "segment_bootstrap_std", "bootstrap_std", "BLOCK_S", "DRAWS"]

#: Block length, s: longer than the residual's correlation (filtered at 20-30 Hz, decimated to
#: 50 Hz: a few samples), short enough for ~100 blocks in a 50 s run.
BLOCK_S = 0.5
#: Number of bootstrap refits (the sigma of a sigma estimate from 200 draws is ~5 %).
DRAWS = 200


def segment_bootstrap_std(W: np.ndarray, Y: np.ndarray, joint: np.ndarray, samples: np.ndarray,
                          weights: np.ndarray, block: int, draws: int = 200, seed: int = 0) -> np.ndarray:
    """Standard deviation of each estimate over ``draws`` segment-bootstrap refits.

    Args:
        W: (r, c) observation matrix; Y: (r,) torques; joint: (r,) joint of each row;
        samples: (r,) sample index of each row (rows of one sample go together).
        weights: (n,) joint weights of the fit (1 for OLS); block: samples per block (≥ 1).
        draws: number of bootstrap refits; seed: seeds the draws.

    Returns:
        (c,) standard deviations, units of the parameters (NaN where a draw was rank deficient).
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
    counts = _draw_counts(blocks.size, draws, seed)
    return np.nanstd(_estimates(np.tensordot(counts, A, axes=1), counts @ g), axis=0, ddof=1)


def _draw_counts(blocks: int, draws: int, seed: int) -> np.ndarray:
    """(draws, blocks) how often each block is drawn in each refit (blocks drawn with replacement)."""
    rng = np.random.default_rng(seed)
    return np.stack([np.bincount(rng.integers(0, blocks, blocks), minlength=blocks) for _ in range(draws)])


def _estimates(M: np.ndarray, g: np.ndarray) -> np.ndarray:
    """The refits ``M_d⁻¹·g_d``, (draws, c) (a NaN row for a rank-deficient draw)."""
    c = M.shape[-1]
    estimates = np.full((M.shape[0], c), np.nan)
    for i in range(M.shape[0]):
        if np.linalg.matrix_rank(M[i]) == c:
            estimates[i] = np.linalg.solve(M[i], g[i])
    return estimates


def _spread(M: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Standard deviation of the refits ``M_d⁻¹·g_d`` (NaN where every draw was rank deficient, said by the NaN,
    not by numpy's warning)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanstd(_estimates(M, g), axis=0, ddof=1)


class SegmentBootstrap:
    """:func:`segment_bootstrap_std` fed block by block (a long log's W is never held).

    Every draw's normal equations are sums over the bootstrap blocks weighted by how often the
    draw picks them, so each piece of rows adds its share to every draw at once, per joint (the
    joint weights are known only at the end). The draws are those of :func:`segment_bootstrap_std`
    for the same seed when every block has rows (no rest sample dropped from a whole block).
    Memory: draws × n × c² doubles (200 × 7 × 78² ≈ 68 MB).

    Args:
        samples: decimated samples of all the recordings together; block, draws, seed: as
            :func:`segment_bootstrap_std`; joints n, columns c.
    """

    def __init__(self, samples: int, block: int, joints: int, columns: int, draws: int = 200, seed: int = 0) -> None:
        if block < 1 or draws < 2:
            raise ValueError(f"block must be >= 1 sample and draws >= 2, got {block} and {draws}")
        self.block = int(block)
        self.counts = _draw_counts(-(-int(samples) // self.block), draws, seed).astype(np.int32)  # 4 B a block
        self.M = np.zeros((draws, joints, columns, columns))
        self.g = np.zeros((draws, joints, columns))

    def add(self, joint: int, samples: np.ndarray, W: np.ndarray, Y: np.ndarray,
            instruments: np.ndarray | None = None) -> None:
        """Rows of joint ``joint``: their decimated sample index (increasing), W (m, c), Y (m,);
        ``instruments``: (m, c) Z of an instrumental-variable fit (its draws solve ZᵀW x = ZᵀY)."""
        if samples.size == 0:
            return
        Z = W if instruments is None else instruments
        ids = np.asarray(samples) // self.block
        starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
        stops = np.r_[starts[1:], ids.size]
        A = np.stack([Z[a:b].T @ W[a:b] for a, b in zip(starts, stops)])
        g = np.stack([Z[a:b].T @ Y[a:b] for a, b in zip(starts, stops)])
        picked = self.counts[:, ids[starts]].astype(float)
        self.M[:, joint] += (picked @ A.reshape(A.shape[0], -1)).reshape(self.M.shape[0], *A.shape[1:])
        self.g[:, joint] += picked @ g

    def estimates(self, weights: np.ndarray, columns: Sequence[int] | None = None) -> np.ndarray:
        """The refits themselves, (draws, c) (a NaN row where a draw was rank deficient), for the joint
        weights of the fit (1 for OLS); ``columns``: those of the parameters fitted only (None: all)."""
        w2 = np.asarray(weights, dtype=float) ** 2
        M, g = np.tensordot(self.M, w2, axes=([1], [0])), np.tensordot(self.g, w2, axes=([1], [0]))
        if columns is not None:
            keep = np.asarray(columns, dtype=int)
            M, g = M[:, keep][:, :, keep], g[:, keep]
        return _estimates(M, g)

    def std(self, weights: np.ndarray, columns: Sequence[int] | None = None) -> np.ndarray:
        """(c,) standard deviations of :meth:`estimates` (NaN where every draw was rank deficient)."""
        return np.nanstd(self.estimates(weights, columns), axis=0, ddof=1)


def bootstrap_std(W: np.ndarray, Y: np.ndarray, joint: np.ndarray, samples: np.ndarray, weights: np.ndarray,
                  rate: float, seed: int = 0) -> np.ndarray:
    """:func:`segment_bootstrap_std` with the toolkit's blocks of BLOCK_S seconds (``rate``: the
    rows' sample rate, Hz) and DRAWS refits, for rows held in memory (the consistent fit's
    covariance); logs read block by block fold theirs into :class:`SegmentBootstrap`."""
    block = max(1, int(round(BLOCK_S * rate)))
    return segment_bootstrap_std(W, Y, joint, samples, weights, block, DRAWS, seed)
