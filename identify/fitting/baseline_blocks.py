"""The yardsticks of long logs: their windows read block by block from a log's source.

:mod:`identify.fitting.baseline` filters each segment in blocks with margins (one block: the whole
segment in memory); here the blocks come from a :class:`identify.io.blocks.BlockSource` after the
first pass over it (:func:`identify.observation.scan.scan`: each segment's start, samples, rate and
first and last times), so a log of any length gets the yardsticks (the plain OLS baseline, the model
the user had: :mod:`identify.fitting.yardsticks`) of the same recording held whole (to ~1e-12 relative)
with memory bounded by the block.
"""
from __future__ import annotations

from typing import Any, Iterator, Sequence

import numpy as np

import rx90sym

from identify.fitting.baseline import BaselinePrediction, BaselineSegment, yardstick_predictions

__all__ = ["baseline_at", "source_windows", "log_predictions"]


def _segments(scan: Any, index: int) -> list[tuple[int, BaselineSegment]]:
    """(first raw sample in the recording, segment) of every segment of a scan (checked as in memory) of the
    recording ``index`` (the segments' ``key``)."""
    out = []
    for k, g in enumerate(scan.segments):
        name = f"{scan.source}#{k + 1}" if len(scan.segments) > 1 else scan.source
        segment = BaselineSegment(1.0 / g.rate if g.samples > 1 else float("nan"), g.first_t, g.last_t, g.samples,
                                  name, (index, g.start))
        segment.check()
        out.append((g.start, segment))
    return out


def source_windows(sources: Sequence[Any], scans: Sequence[Any], block: int) -> Iterator[tuple]:
    """(segment, window, its raw samples) of every segment of every source, in blocks of at most ``block``
    samples (``scans``: the sources' first pass, :func:`identify.observation.scan.scan`)."""
    for index, (src, scan) in enumerate(zip(sources, scans)):
        planned = [(start, segment, w) for start, segment in _segments(scan, index) for w in segment.windows(block)]
        spans = [(start + w.raw[0], start + w.raw[1]) for start, _, w in planned]
        for (_, segment, w), rec in zip(planned, src.windows(spans)):
            yield segment, w, rec


def log_predictions(robot: rx90sym.Robot, models: Sequence[Any], source: Any, scan: Any,
                         block: int) -> list[BaselinePrediction]:
    """The predictions of the yardsticks ``models`` of one log read block by block, in one pass
    (:meth:`identify.fitting.baseline.LinearYardstick.predict` of it held whole, to ~1e-12)."""
    return yardstick_predictions(robot, models, source_windows([source], [scan], block))


def baseline_at(prediction: BaselinePrediction, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(scored (S,), predicted (S, n)) of a yardstick at the raw time stamps ``t`` (S,) of the same log."""
    idx = np.clip(np.searchsorted(prediction.t, t), 0, prediction.t.size - 1)
    same = prediction.t[idx] == t
    return same & prediction.scored[idx], prediction.predicted[idx]
