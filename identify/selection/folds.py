"""The folds of the blocked cross-validations (:mod:`identify.selection.cross_validation`, the friction
choice): the folds by time, the per-(block, joint) compressed rows, the fold fits (WLS, eq. 11's weights)
and the scores from the held-back squared errors. A candidate processing's held-back error against the
raw measured torques is :mod:`identify.selection.raw_torque_scores`'."""
from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ["time_folds", "time_blocks", "block_factors", "block_scores", "fold_wls"]


def time_folds(t: np.ndarray, start: float, span: float, blocks: int) -> np.ndarray:
    """The contiguous block (0 .. blocks-1) of each time ``t`` [s] in ``[start, start + span)``."""
    return np.minimum((blocks * (t - start) / span).astype(int), blocks - 1)


def time_blocks(times: Sequence[np.ndarray], blocks: int) -> list[np.ndarray]:
    """The fold of every sample: per array of sample times [s] (one per motion or segment), the
    block 0..blocks-1 it falls in when the common span (earliest to latest time of all) is cut into
    ``blocks`` contiguous blocks of equal duration (:func:`time_folds`). The one fold assignment of the
    processing and the friction choices (by time, not by sample index: recordings and segments of other
    lengths or rates fall in the same blocks for both)."""
    start = min(float(np.min(t)) for t in times)
    span = max(float(np.max(t)) for t in times) - start + 1e-9
    return [time_folds(np.asarray(t), start, span, blocks) for t in times]


def block_factors(W: np.ndarray, Y: np.ndarray, joint: np.ndarray, ids: np.ndarray, blocks: Sequence[int],
                  n: int) -> dict[tuple[int, int], tuple[np.ndarray, int]]:
    """(block, joint) -> (the triangular factor of [W | Y] over the rows of that block (``ids``) and
    joint, their number), for the ``blocks`` listed: what :func:`fold_wls` solves from."""
    # The rows grouped by (block, joint) with one stable sort (each group keeps its order), not a mask per group.
    key = np.asarray(ids) * n + joint
    order = np.argsort(key, kind="stable")
    edges = np.searchsorted(key[order], [[b * n + j, b * n + j + 1] for b in blocks for j in range(n)])
    out = {}
    for bj, (lo, hi) in zip([(b, j) for b in blocks for j in range(n)], edges):
        if hi > lo:
            rows = order[lo:hi]
            out[bj] = (np.linalg.qr(np.column_stack([W[rows], Y[rows]]), mode="r"), int(hi - lo))
    return out


def block_scores(err2: np.ndarray, ref2: np.ndarray) -> tuple[float, tuple[float, ...], tuple[tuple[float, ...], ...]]:
    """(score, per joint, per held-back block and joint), relative errors 100 sqrt(err2 / ref2) in %,
    from the squared errors and references (blocks, n) of the held-back blocks."""
    total = ref2.sum(axis=0)
    per_joint = 100.0 * np.sqrt(err2.sum(axis=0) / np.where(total > 0, total, np.nan))
    per_block = 100.0 * np.sqrt(err2 / np.where(ref2 > 0, ref2, np.nan))
    return (float(np.nanmean(per_joint)), tuple(float(v) for v in per_joint),
            tuple(tuple(float(v) for v in row) for row in per_block))


def fold_wls(factors: dict[tuple[int, int], tuple[np.ndarray, int]], held: int, n: int) -> np.ndarray | None:
    """WLS (each joint weighted by 1 / its residual standard deviation, as the fit does) on every
    block but ``held``, from the compressed blocks; None when a joint has too few rows. A joint without
    rows in any block (its torque left out of the fit) is not fitted."""
    systems = []
    fitted = {jj for (_, jj) in factors}
    for j in range(n):
        if j not in fitted:
            continue
        parts = [f for (b, jj), f in factors.items() if jj == j and b != held]
        if not parts:
            return None
        stacked = np.vstack([R for R, _ in parts])  # the same norms as the rows it compresses
        rows = sum(count for _, count in parts)
        c = stacked.shape[1] - 1
        # The joint's own columns only (its rows hold no parameter of the links before it): the same
        # residual, and rank threshold (rows > columns), from a smaller SVD.
        live = np.flatnonzero(np.any(stacked[:, :c] != 0.0, axis=0))
        x, *_ = np.linalg.lstsq(stacked[:, live], stacked[:, c], rcond=None)
        resid = np.linalg.norm(stacked[:, live] @ x - stacked[:, c])
        if rows <= c or resid == 0:
            return None
        systems.append(stacked / (resid / np.sqrt(rows - c)))  # sigma_j as in eq. 12, per joint
    R = np.vstack(systems)
    c = R.shape[1] - 1
    beta, *_ = np.linalg.lstsq(R[:, :c], R[:, c], rcond=None)
    return beta
