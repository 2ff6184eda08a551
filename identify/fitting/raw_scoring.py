"""Predictions scored against the raw measured torques, at the recording's own time stamps
(:func:`identify.predict` does it block by block).

A fit predicts at its own (decimated) samples, from filtered positions; the torques it is judged
against are the ones the log holds, unfiltered, at every recorded time stamp: the prediction is
interpolated linearly onto those stamps (after the torque lag it compensates) and only the samples
inside both (the prediction's span, measured, not bridged) are scored. Two fits with different
filters, or the toolkit and the yardsticks (:mod:`identify.fitting.yardsticks`), are so compared
on the same samples of the same signal.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


__all__ = ["RawScores", "SCORE_TRIM_S"]

#: Seconds left out at both ends of every segment when scoring: the plain baseline's trim
#: (identify.fitting.baseline.BASELINE_TRIM_S). A fit predicts from its filter's edges on (3 periods
#: of its cut-off: within 0.5 s from 6 Hz on), so that fits of 6 Hz and more and the baseline are
#: scored on the same samples; a lower cut-off scores fewer (the baseline then on those).
SCORE_TRIM_S = 0.5


@dataclass(frozen=True, eq=False)
class RawScores:
    """The scored samples of a recording: t (S,) [s]; measured (S, n) raw torques [N m]; predicted
    (S, n) the fit's prediction there; moving (S, n) the fit's moving mask at the nearest predicted
    sample; baseline (S, n) the plain baseline's prediction (None: no baseline); user (S, n) the model the
    user had's (identify.fitting.user_model; None: none)."""

    t: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    moving: np.ndarray
    baseline: np.ndarray | None = None
    user: np.ndarray | None = None


