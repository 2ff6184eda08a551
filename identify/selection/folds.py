"""The folds of the blocked cross-validations (:mod:`identify.selection.cross_validation`, the friction
choice): the folds by time and the scores from the held-back squared errors (the per-(block, joint)
compressed rows and the fold fits on them: :mod:`identify.estimation.compression`,
:mod:`identify.estimation.least_squares`). A candidate processing's held-back error against the
raw measured torques is :mod:`identify.selection.raw_torque_scores`'."""
from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ["time_folds", "time_blocks", "block_scores"]


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


def block_scores(err2: np.ndarray, ref2: np.ndarray) -> tuple[float, tuple[float, ...], tuple[tuple[float, ...], ...]]:
    """(score, per joint, per held-back block and joint), relative errors 100 sqrt(err2 / ref2) in %,
    from the squared errors and references (blocks, n) of the held-back blocks."""
    total = ref2.sum(axis=0)
    per_joint = 100.0 * np.sqrt(err2.sum(axis=0) / np.where(total > 0, total, np.nan))
    per_block = 100.0 * np.sqrt(err2 / np.where(ref2 > 0, ref2, np.nan))
    return (float(np.nanmean(per_joint)), tuple(float(v) for v in per_joint),
            tuple(tuple(float(v) for v in row) for row in per_block))
