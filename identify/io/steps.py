"""The time steps of a log: their distinct values and counts, and the figures a log's report gives.

:class:`StepCounts` holds the distinct steps of a log and how often each occurs, so that the median
of all the steps is known while the log is read block by block (a regular clock has a few hundred
distinct steps whatever the log's length). :func:`step_figures` gives the report's figures from
them, the same for a log read whole (:func:`identify.read_log`) and block by block
(:mod:`identify.io.log_blocks`): both feed the same steps, rounded to :data:`STEP_RESOLUTION`
(which bounds the distinct values of a jittered host clock: at most 6e5 between 0.7 and 1.3 ms).
"""
from __future__ import annotations

import numpy as np

from identify.io.gaps import LOST_STEPS

__all__ = ["STEP_RESOLUTION", "StepCounts", "log_steps", "step_figures"]

#: Resolution of the steps the report counts, s (1 ns: finer than any controller's or ROS clock).
STEP_RESOLUTION = 1e-9


class StepCounts:
    """The distinct time steps of a log and how often each occurs (a regular log has a few hundred
    distinct values whatever its length): their median is ``np.median`` of all the steps."""

    def __init__(self) -> None:
        self.values, self.counts = np.empty(0), np.empty(0, dtype=np.int64)

    def add(self, steps: np.ndarray) -> None:
        values, where = np.unique(np.concatenate([self.values, steps]), return_inverse=True)
        weights = np.concatenate([self.counts, np.ones(steps.size, dtype=np.int64)])
        self.values, self.counts = values, np.bincount(where, weights=weights).astype(np.int64)

    def median(self) -> float:
        total = int(self.counts.sum())
        cum = np.cumsum(self.counts)
        lo = self.values[np.searchsorted(cum, (total - 1) // 2, side="right")]
        hi = self.values[np.searchsorted(cum, total // 2, side="right")]
        return float((lo + hi) / 2.0) if lo != hi else float(lo)


def log_steps(dt: np.ndarray) -> np.ndarray:
    """Steps (s) as the report counts them: rounded to :data:`STEP_RESOLUTION`."""
    return np.round(np.asarray(dt, dtype=float) / STEP_RESOLUTION) * STEP_RESOLUTION


def step_figures(steps: StepCounts, rtol: float) -> dict[str, float | int]:
    """The clock of a log from its steps (:func:`log_steps`): ``median_step_s``; ``irregular_steps``,
    the steps more than ``rtol`` x the median from the median (identify.io.checks.TIME_RTOL); ``rate_hz``, 1 / the mean step of the steps up to
    LOST_STEPS median steps (the stream's own rate: a lost packet, a dropped stale row or a gap that
    splits the log is left out, so the rate does not depend on how the gaps are bridged or split)."""
    if not steps.counts.size:
        return {"median_step_s": float("nan"), "irregular_steps": 0, "rate_hz": float("nan")}
    median = steps.median()
    off = np.abs(steps.values - median) > rtol * median
    stream = steps.values <= LOST_STEPS * median
    mean = float(np.sum(steps.values[stream] * steps.counts[stream]) / np.sum(steps.counts[stream]))
    return {"median_step_s": median, "irregular_steps": int(steps.counts[off].sum()), "rate_hz": 1.0 / mean}
