"""The first pass over a log read block by block: its samples, rate and segments, the automatic cut-off.

:func:`scan` reads a recording (:class:`identify.io.blocks.BlockSource`) in blocks, each checked like a
whole file; it counts the samples, takes the rate, and streams the Welch spectrum of the raw
accelerations so that the automatic cut-off (:func:`identify.observation.matrix.automatic_cutoff`) is
the whole log's. Segments (a recording cut at gaps too long to bridge, ``Recording.segment`` or a
``segment`` column) are scanned one by one, as :func:`identify.observation.matrix.filtered_motions`
filters them. The second pass, the rows of each block, is :mod:`identify.observation.block_rows`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from identify.io.blocks import BlockSource
from identify.io.log_fields import layout_fields
from identify.io.steps import StepCounts
from identify.io.unlogged import ColumnRange, constant_channels
from identify.observation.matrix import DECIMATION_PASSBAND, SPECTRUM_SAMPLES
from identify.observation.processing import Processing
from identify.signal.blocks import WelchAccumulator
from identify.signal.cutoff import choose_cutoff
from identify.signal.filtering import cutoff_from_spectrum

__all__ = ["Scan", "SegmentScan", "scan", "scan_all", "scanned_cutoff", "torque_left_out"]


@dataclass(frozen=True)
class SegmentScan:
    """One segment of a recording (the samples between two gaps too long to bridge): its first raw
    sample ``start`` in the recording, ``samples``, ``rate`` [Hz] (1 / its median step, as
    :func:`filtered_motions` takes it), its automatic cut-off [Hz] (None when a cut-off is given) and,
    when the scan was asked to keep them, the times [s] of its first and last samples (``head``,
    ``tail``: where the filters' edges end, for the time blocks of a cross-validation) and whether each
    was measured (``head_measured``, ``tail_measured``: not bridged over lost packets)."""

    start: int
    samples: int
    rate: float
    cutoff: float | None
    head: np.ndarray = field(default_factory=lambda: np.empty(0), compare=False, repr=False)
    tail: np.ndarray = field(default_factory=lambda: np.empty(0), compare=False, repr=False)
    head_measured: np.ndarray = field(default_factory=lambda: np.empty(0, bool), compare=False, repr=False)
    tail_measured: np.ndarray = field(default_factory=lambda: np.empty(0, bool), compare=False, repr=False)
    first_t: float = field(default=float("nan"), compare=False)  # times [s] of its first and last samples
    last_t: float = field(default=float("nan"), compare=False)

    def time_at(self, index: int) -> float:
        """The time [s] of the segment's sample ``index`` (0 .. samples-1), from its head or tail kept."""
        if 0 <= index < self.head.size:
            return float(self.head[index])
        back = self.samples - index
        if 0 < back <= self.tail.size:
            return float(self.tail[-back])
        raise ValueError(f"sample {index} of a segment of {self.samples} is not among the times the scan kept "
                         f"({self.head.size} first, {self.tail.size} last)")


@dataclass(frozen=True)
class Scan:
    """What the first pass learnt of one recording: samples, rate [Hz] (1 / median step), its segments,
    the smallest and largest position of each joint ``q_range`` (2, n) [rad], the samples bridged over
    lost packets and what the file keeps of its log (``log``: stale rows, gaps that split it;
    :mod:`identify.io.log_fields`; None: nothing), the smallest and largest torque of each joint
    ``tau_range`` (2, n) [N·m] (None: no torques)."""

    source: str
    samples: int
    rate: float
    segments: tuple[SegmentScan, ...]
    q_range: np.ndarray | None = None
    bridged: int = 0
    log: dict | None = None
    tau_range: np.ndarray | None = None

    def layout(self) -> dict[str, Any]:
        """As :func:`identify.io.recordings.layout_summary` for a recording in memory."""
        return {"source": self.source, "samples": self.samples, "bridged_samples": self.bridged,
                "segments": len(self.segments), **layout_fields(self.log)}


#: Length of a Welch segment of the automatic cut-off [s] (:func:`identify.choose_cutoff`'s default).
WELCH_SECONDS = 4.0


class _SegmentPass:
    """One segment fed in consecutive pieces: its steps, and the automatic cut-off's spectrum.

    While the segment is at most one block (or one Welch segment) long its samples are held and its
    cut-off is :func:`identify.choose_cutoff` on them, exactly the whole-recording rule; beyond, the
    Welch spectrum of its raw accelerations is streamed (:class:`WelchAccumulator`, equal to scipy's).
    """

    def __init__(self, start: int, hold: int, floor: float | None, keep_s: float = 0.0) -> None:
        self.start, self.hold, self.floor, self.keep_s = start, hold, floor, keep_s
        self.head, self.tail = np.empty(0), np.empty(0)
        self.head_measured, self.tail_measured = np.empty(0, bool), np.empty(0, bool)
        self.samples, self.steps = 0, StepCounts()
        self.t: list[np.ndarray] = []
        self.q: list[np.ndarray] = []
        self.tail_t: np.ndarray | None = None
        self.first_t = float("nan")
        self.tail_q = np.empty((0, 0))
        self.welch: WelchAccumulator | None = None
        self.rate = float("nan")

    def feed(self, t: np.ndarray, q: np.ndarray, measured: np.ndarray) -> None:
        if self.keep_s > 0:  # the times within keep_s of either end, and whether they were measured
            first = self.head[0] if self.head.size else t[0]
            if self.head.size == self.samples:
                near = t <= first + self.keep_s
                self.head = np.concatenate([self.head, t[near]])
                self.head_measured = np.concatenate([self.head_measured, measured[near]])
            tail, tail_measured = np.concatenate([self.tail, t]), np.concatenate([self.tail_measured, measured])
            near = tail >= t[-1] - self.keep_s
            self.tail, self.tail_measured = tail[near], tail_measured[near]
        if self.tail_t is not None:
            self.steps.add(np.diff(np.r_[self.tail_t, t]))
        else:
            self.steps.add(np.diff(t))
            self.first_t = float(t[0])
        self.tail_t = t[-1:]
        self.samples += t.size
        if self.floor is None:
            return
        if self.welch is None:
            self.t.append(t)
            self.q.append(q)
            t_all = np.concatenate(self.t)
            rate = 1.0 / float(np.median(np.diff(t_all))) if t_all.size > 1 else np.inf
            if self.samples > max(self.hold, WELCH_SECONDS * rate):  # long: stream the spectrum from here on
                q_all = np.concatenate(self.q)
                self.t, self.q = [], []
                self.rate = rate
                self.welch = WelchAccumulator(self.rate, max(16, int(round(WELCH_SECONDS * self.rate))), q.shape[1])
                self._accelerations(q_all)
            return
        self._accelerations(q)

    def _accelerations(self, q: np.ndarray) -> None:
        x = q if not self.tail_q.size else np.concatenate([self.tail_q, q])
        self.welch.feed((x[2:] - 2.0 * x[1:-1] + x[:-2]) * self.rate**2)
        self.tail_q = x[-2:]

    def result(self) -> SegmentScan:
        rate = 1.0 / self.steps.median() if self.samples > 1 else float("nan")
        cut = None
        if self.floor is not None and self.welch is not None:
            cut = cutoff_from_spectrum(*self.welch.result(), self.rate, min_cutoff=self.floor)
        elif self.floor is not None and self.samples > 2:
            t_all, q_all = np.concatenate(self.t), np.concatenate(self.q)
            cut = choose_cutoff(q_all, 1.0 / float(np.median(np.diff(t_all))), min_cutoff=self.floor)
        return SegmentScan(self.start, self.samples, rate, cut, self.head, self.tail, self.head_measured,
                           self.tail_measured, self.first_t,
                           float(self.tail_t[0]) if self.tail_t is not None else float("nan"))


def scan(src: BlockSource, block: int, floor: float | None, keep_s: float = 0.0) -> Scan:
    """First pass over one recording (checks every block; see the module docstring); ``floor``: the
    lowest automatic cut-off [Hz] (None: the cut-off is given, no spectrum); ``keep_s`` [s]: keep the
    times of each segment's first and last ``keep_s`` seconds (:meth:`SegmentScan.time_at`)."""
    lo = hi = None
    torques = ColumnRange()
    steps = StepCounts()  # the rate is the whole log's, 1 / median step
    done: list[SegmentScan] = []
    current: _SegmentPass | None = None
    bridged, at, last_t = 0, 0, None
    for rec in src.scan(block):
        new = int(rec.meta.get("new_from", 0))
        lo = rec.q.min(axis=0) if lo is None else np.minimum(lo, rec.q.min(axis=0))
        hi = rec.q.max(axis=0) if hi is None else np.maximum(hi, rec.q.max(axis=0))
        t, q, measured = rec.t[new:], rec.q[new:], rec.measured_mask[new:]
        torques.add(None if rec.tau is None else rec.tau[new:])
        steps.add(np.diff(t if last_t is None else np.r_[last_t, t]))
        last_t = t[-1:]
        bridged += int(np.sum(~measured))
        seg = int(rec.meta.get("segment0", 0)) + (rec.segment[new:] if rec.segment is not None
                                                  else np.zeros(t.size, np.int64))
        for number in np.unique(seg):
            rows = np.flatnonzero(seg == number)
            if current is None or number != len(done):
                if current is not None:
                    done.append(current.result())
                current = _SegmentPass(at + int(rows[0]), block, floor, keep_s)
            current.feed(t[rows], q[rows], measured[rows])
        at += t.size
    done.append(current.result())
    return Scan(src.source, int(src.n_samples), 1.0 / steps.median(), tuple(done), np.vstack([lo, hi]), bridged,
                src.log, torques.value())


def torque_left_out(scans: Sequence[Scan], joints: int | None = None) -> tuple[int, ...]:
    """The joints (0-based) whose torque is constant over a whole recording (:mod:`identify.io.unlogged`: a
    channel not logged) in any of ``scans``: left out of a fit (their rows out of W, not scored); with the
    robot's count of ``joints``, a ValueError when every joint is left out."""
    out: set[int] = set()
    for s in scans:
        if s.tau_range is not None:
            out.update(constant_channels(s.tau_range[0], s.tau_range[1]))
    if joints is not None and len(out) == joints:
        raise ValueError(f"{', '.join(s.source for s in scans)}: every joint's torque holds one value on every sample "
                         f"(channels not logged): nothing to fit; log the joint torques, or the currents with gains")
    return tuple(sorted(out))


def scan_all(sources: Sequence[BlockSource], processing: Processing, block: int,
             keep_s: float = 0.0) -> tuple[list[Scan], Processing]:
    """Scan every recording in blocks of ``block`` samples; ``processing`` with its cut-off [Hz], the one
    given or the one chosen as on the whole recordings (:func:`identify.observation.matrix.automatic_cutoff`:
    the largest over the segments long enough for a spectrum); ``keep_s``: as :func:`scan`."""
    if processing.cutoff is not None:
        return [scan(src, block, None, keep_s) for src in sources], processing
    floor = max(2.0, DECIMATION_PASSBAND * processing.decimate_to) if processing.decimate_to else 2.0
    scans = [scan(src, block, floor, keep_s) for src in sources]
    return scans, processing.chosen(cutoff=scanned_cutoff(scans, floor))


def scanned_cutoff(scans: Sequence[Scan], floor: float) -> float:
    """:func:`identify.observation.matrix.automatic_cutoff` [Hz] from the segments' cut-offs of a scan made
    with a floor at most ``floor`` [Hz]: the largest over the segments long enough for a spectrum, each
    raised to ``floor`` and bounded by 40 % of its Nyquist frequency as :func:`choose_cutoff` bounds it."""
    segments = [g for s in scans for g in s.segments]
    longest = max(g.samples for g in segments)
    return float(max(g.cutoff if g.cutoff >= floor else min(floor, 0.2 * g.rate) for g in segments
                     if g.samples >= min(longest, SPECTRUM_SAMPLES)))
