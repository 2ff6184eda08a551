"""The filtered figures of a prediction: its RMS error against the torques filtered like the fit's rows.

A validation gives, beside the errors on the raw torques, the RMS error against the torques filtered
like the fit's rows (``rms_error_filtered``, all samples and while moving, measured samples only). The
rows come block by block (:func:`identify.observation.block_rows.piece`): the per-joint sums of squared
errors and counts are accumulated, so the figures are the whole log's without holding its rows.
"""
from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np

import rx90sym

from identify.observation.block_rows import piece, plan_windows, windows_in_order
from identify.observation.processing import Processing

__all__ = ["FilteredSums", "filtered_rms"]


class FilteredSums:
    """Per joint, the sums of squared errors of a prediction ``beta`` on filtered rows, and their counts
    (all measured rows, and those while moving), fed one block's motion at a time."""

    def __init__(self, beta: np.ndarray, joints: int) -> None:
        self.beta = beta
        self.sums = {"all": np.zeros(joints), "moving": np.zeros(joints)}
        self.counts = {"all": np.zeros(joints), "moving": np.zeros(joints)}

    def add(self, m: Any) -> None:
        """The rows of one block (a FilteredMotion cut to its core)."""
        rows = m.measured if m.measured is not None else np.ones(m.Y.shape[0], bool)
        err2 = (m.Y - m.Phi @ self.beta)[rows] ** 2
        moving = np.asarray(m.moving, dtype=bool)[rows]
        self.sums["all"] += err2.sum(axis=0)
        self.counts["all"] += err2.shape[0]
        self.sums["moving"] += np.where(moving, err2, 0.0).sum(axis=0)
        self.counts["moving"] += moving.sum(axis=0)

    def result(self) -> dict[str, np.ndarray]:
        """``rms_error_filtered`` and ``rms_error_filtered_moving`` (n,) [N m]; nan on a joint without rows."""
        rms = {k: np.where(self.counts[k] > 0, np.sqrt(self.sums[k] / np.maximum(self.counts[k], 1)), np.nan)
               for k in self.sums}
        return {"rms_error_filtered": rms["all"], "rms_error_filtered_moving": rms["moving"]}


def filtered_rms(robot: rx90sym.Robot, src: Any, scan: Any, processing: Processing, block: int,
                 regressor: Callable[..., np.ndarray], names: Sequence[str], beta: np.ndarray) -> dict[str, np.ndarray]:
    """:meth:`FilteredSums.result` of the prediction ``beta`` on the rows of one log (``src``, its first pass
    ``scan``) made with ``processing`` (its cut-off chosen; its ``decimate_to``: the rows' rate) in blocks of
    ``block`` samples, a pass of its own."""
    plans, _ = plan_windows(scan, processing, block)
    sums = FilteredSums(beta, robot.n)
    for plan, window, rec, _ in windows_in_order([src], [plans]):
        sums.add(piece(robot, rec, window, plan, processing, regressor, names).motion)
    return sums.result()
