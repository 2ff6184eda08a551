"""Predictions scored against the raw measured torques, at the recording's own time stamps.

A fit predicts at its own (decimated) samples, from filtered positions; the torques it is judged
against are the ones the log holds, unfiltered, at every recorded time stamp: the prediction is
interpolated linearly onto those stamps (after the torque lag it compensates) and only the samples
inside both (the prediction's span, measured, not bridged) are scored. Two fits with different
filters, or the toolkit and the plain baseline (:mod:`identify.fitting.baseline`), are so compared
on the same samples of the same signal.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.signal.interpolate import onto

__all__ = ["RawScores", "SegmentPrediction", "raw_scores", "SCORE_TRIM_S"]

#: Seconds left out at both ends of every segment when scoring: the plain baseline's trim
#: (identify.fitting.baseline.BASELINE_TRIM_S). A fit predicts from its filter's edges on (3 periods
#: of its cut-off: within 0.5 s from 6 Hz on), so that fits of 6 Hz and more and the baseline are
#: scored on the same samples; a lower cut-off scores fewer (the baseline then on those).
SCORE_TRIM_S = 0.5


@dataclass(frozen=True, eq=False)
class RawScores:
    """The scored samples of a recording: t (S,) [s]; measured (S, n) raw torques [N m]; predicted
    (S, n) the fit's prediction there; moving (S, n) the fit's moving mask at the nearest predicted
    sample; baseline (S, n) the plain baseline's prediction (None: no baseline)."""

    t: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    moving: np.ndarray
    baseline: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class SegmentPrediction:
    """A fit's prediction of one segment: t (S,) the predicted samples [s] (before the torque lag);
    torque (S, n) [N m] (spring taken off); moving (S, n) the fit's moving mask there."""

    t: np.ndarray
    torque: np.ndarray
    moving: np.ndarray


def raw_scores(robot: rx90sym.Robot, predictions: Sequence[SegmentPrediction], segments: Sequence[Any],
               delay: float, baseline: Any = None) -> RawScores:
    """The fit's prediction of each segment (``predictions``) at the raw samples of the segments
    (``segments``: recordings of each segment whole), beside their measured torques.
    delay [s]: the torque lag the fit compensates (a prediction at t is the torque recorded at
    t + delay); baseline: a :class:`identify.fitting.baseline.PlainBaseline` scored on the same
    samples, or None. The samples scored: inside the prediction, measured, :data:`SCORE_TRIM_S` from each
    segment's ends (where the baseline predicts too)."""
    parts = []
    for m, piece in zip(predictions, segments):
        t_pred = np.asarray(m.t, dtype=float) + delay
        t = np.asarray(piece.t, dtype=float)
        tol = 1e-9 * max(1.0, float(np.max(np.abs(t))))
        inside = ((t >= t_pred[0] - tol) & (t <= t_pred[-1] + tol) & piece.measured_mask
                  & (t >= t[0] + SCORE_TRIM_S - tol) & (t <= t[-1] - SCORE_TRIM_S + tol))
        b = None
        if baseline is not None:
            bp = baseline.predict(robot, piece)
            inside &= bp.scored
            b = bp.predicted[inside]
        tt = t[inside]
        nearest = np.clip(np.searchsorted(t_pred, tt - 0.5 * _step(t_pred)), 0, t_pred.size - 1)
        parts.append((tt, np.asarray(piece.torques, dtype=float)[inside], onto(tt, t_pred, m.torque),
                      np.asarray(m.moving)[nearest], b))
    if not any(p[0].size for p in parts):
        raise ValueError(f"{segments[0].source}: no recorded sample lies inside the prediction"
                         + (" and 0.5 s from the segments' ends (the plain baseline's trim)" if baseline else ""))
    t, meas, pred, mov = (np.concatenate([p[k] for p in parts]) for k in range(4))
    base = None if baseline is None else np.concatenate([p[4] for p in parts])
    return RawScores(t, meas, pred, mov, base)


def _step(t: np.ndarray) -> float:
    return float(np.median(np.diff(t))) if t.size > 1 else 0.0
