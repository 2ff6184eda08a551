"""The plain OLS baseline of long logs: its windows read block by block from a log's source.

:mod:`identify.fitting.baseline` filters each segment in blocks with margins (one block: the whole
segment in memory); here the blocks come from a :class:`identify.io.blocks.BlockSource` after the
first pass over it (:func:`identify.observation.stream.scan`: each segment's start, samples, rate and
first and last times), so a log of any length gets the baseline of the same recording held whole
(to ~1e-12 relative) with memory bounded by the block.
"""
from __future__ import annotations

from typing import Any, Iterator, Sequence

import numpy as np

import rx90sym

from identify.fitting.baseline import BaselinePrediction, BaselineSegment, PlainBaseline, fit_baseline_windows

__all__ = ["baseline_at", "source_windows", "streamed_baseline", "streamed_baseline_prediction"]


def _segments(scan: Any) -> list[tuple[int, BaselineSegment]]:
    """(first raw sample in the recording, segment) of every segment of a scan (checked as in memory)."""
    out = []
    for k, g in enumerate(scan.segments):
        name = f"{scan.source}#{k + 1}" if len(scan.segments) > 1 else scan.source
        segment = BaselineSegment(1.0 / g.rate if g.samples > 1 else float("nan"), g.first_t, g.last_t, g.samples,
                                  name)
        segment.check()
        out.append((g.start, segment))
    return out


def source_windows(sources: Sequence[Any], scans: Sequence[Any], block: int) -> Iterator[tuple]:
    """(segment, window, its raw samples) of every segment of every source, in blocks of at most ``block``
    samples (``scans``: the sources' first pass, :func:`identify.observation.stream.scan`)."""
    for src, scan in zip(sources, scans):
        planned = [(start, segment, w) for start, segment in _segments(scan) for w in segment.windows(block)]
        spans = [(start + w.raw[0], start + w.raw[1]) for start, _, w in planned]
        for (_, segment, w), rec in zip(planned, src.windows(spans)):
            yield segment, w, rec


def streamed_baseline(robot: rx90sym.Robot, sources: Sequence[Any], scans: Sequence[Any], spring: bool,
                      block: int, client: Any = None) -> PlainBaseline | None:
    """:func:`identify.fitting.baseline.plain_baseline` of logs read block by block (None where it cannot be
    fitted: a rate of 20 Hz or less, every segment shorter than 1 s); client: a ``dask.distributed.Client``
    running the windows (read here, filtered and compressed on the workers, folded here in order)."""
    runner = None
    if client is not None:
        from identify.observation.stream import in_order

        shared = client.scatter(robot, broadcast=True, hash=False)  # sent once to each worker

        def on_dask(task: Any, arguments: Any) -> Any:
            return in_order(task, ((shared, *a[1:]) for a in arguments), client, 4)
        runner = on_dask
    try:
        return fit_baseline_windows(robot, source_windows(sources, scans, block), spring, runner)
    except ValueError:
        return None


def streamed_baseline_prediction(robot: rx90sym.Robot, baseline: PlainBaseline, source: Any, scan: Any,
                                 block: int) -> BaselinePrediction:
    """The baseline's prediction of one log read block by block (:meth:`PlainBaseline.predict` of it held
    whole, to ~1e-12)."""
    return baseline.predict_windows(robot, source_windows([source], [scan], block))


def baseline_at(prediction: BaselinePrediction, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(scored (S,), predicted (S, n)) of the baseline at the raw time stamps ``t`` (S,) of the same log."""
    idx = np.clip(np.searchsorted(prediction.t, t), 0, prediction.t.size - 1)
    same = prediction.t[idx] == t
    return same & prediction.scored[idx], prediction.predicted[idx]
