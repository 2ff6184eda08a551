"""The observation matrix of a long log, block by block (eqs. 6-8 and 20 without the whole log in memory).

Two passes over each recording (:class:`identify.io.blocks.BlockSource`):

1. :func:`scan` — read in blocks, checked like a whole file; count the samples, take the rate, and
   stream the Welch spectrum of the raw accelerations so that the automatic cut-off
   (:func:`identify.observation.matrix.automatic_cutoff`) is the whole log's;
2. :func:`pieces` — the blocks of :func:`identify.signal.blocks.motion_windows` (core plus margins
   from the filters' impulse responses), each through :func:`filtered_motion` exactly as a whole
   recording, cut back to its core: a :class:`Piece` of decimated rows.

Segments (a recording cut at gaps too long to bridge, ``Recording.segment`` or a ``segment`` column)
are scanned, planned and filtered one by one, as :func:`identify.observation.matrix.filtered_motions`
does on a whole recording: the filters restart at each segment and no window spans two; a sample
bridged over lost packets (``measured`` 0) runs through the filters but its row is left out
(:meth:`FilteredMotion.rows`).

Peak memory is that of one block: the full-rate regressor of a block with its margins,
(block + 2·margin) × n × c doubles, and its parallel-filtered copies (about three such arrays).
Every quantity downstream (incremental QR, bootstrap, validation) consumes pieces.
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Iterator, Sequence

import numpy as np

import rx90sym

from identify.io.blocks import DEFAULT_BLOCK, BlockSource
from identify.io.log_fields import layout_fields
from identify.io.unlogged import ColumnRange, constant_channels
from identify.observation.matrix import DECIMATION_PASSBAND, SPECTRUM_SAMPLES, filtered_motion, shifted_torques
from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.observation.processing import CROSSING_SECONDS, RestPolicy, has_policy
from identify.signal.blocks import WelchAccumulator, decimation_margin, lowpass_margin, motion_windows
from identify.signal.cutoff import choose_cutoff
from identify.signal.filtering import EDGE_PERIODS, cutoff_from_spectrum, decimate, decimation_plan
from identify.io.steps import StepCounts

__all__ = ["DEFAULT_BLOCK", "Piece", "Plan", "Scan", "SegmentScan", "StreamSettings", "in_order", "pieces",
           "plan_windows", "scan", "scan_all", "scanned_cutoff", "torque_left_out"]



@dataclass(frozen=True)
class StreamSettings:
    """The processing of a streamed fit: cut-off [Hz] (None: chosen), decimate_to [Hz] (None: none),
    min_velocity [rad/s] (None: no rest mask), rest policy, torque delay [s], spring, block [raw samples],
    the joints (0-based) whose torque is left out (their rows out of W: :func:`torque_left_out`)."""

    cutoff: float | None = None
    decimate_to: float | None = DEFAULT_DECIMATE_TO
    min_velocity: float | None = None
    rest: RestPolicy = "drop"
    delay: float = 0.0
    spring: bool = True
    block: int = DEFAULT_BLOCK
    left_out: tuple[int, ...] = ()


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


def torque_left_out(scans: Sequence[Scan]) -> tuple[int, ...]:
    """The joints (0-based) whose torque is constant over a whole recording (:mod:`identify.io.unlogged`: a
    channel not logged) in any of ``scans``: left out of a fit (their rows out of W, not scored)."""
    out: set[int] = set()
    for s in scans:
        if s.tau_range is not None:
            out.update(constant_channels(s.tau_range[0], s.tau_range[1]))
    return tuple(sorted(out))


def scan_all(sources: Sequence[BlockSource], settings: StreamSettings,
             keep_s: float = 0.0) -> tuple[list[Scan], float]:
    """Scan every recording; the cut-off [Hz] given, or chosen as on the whole recordings
    (:func:`identify.observation.matrix.automatic_cutoff`: the largest over the segments long enough
    for a spectrum); ``keep_s``: as :func:`scan`."""
    need = settings.cutoff is None
    floor = (max(2.0, DECIMATION_PASSBAND * settings.decimate_to) if settings.decimate_to else 2.0) if need else None
    scans = [scan(src, settings.block, floor, keep_s) for src in sources]
    return scans, scanned_cutoff(scans, floor) if need else float(settings.cutoff)


def scanned_cutoff(scans: Sequence[Scan], floor: float) -> float:
    """:func:`identify.observation.matrix.automatic_cutoff` [Hz] from the segments' cut-offs of a scan made
    with a floor at most ``floor`` [Hz]: the largest over the segments long enough for a spectrum, each
    raised to ``floor`` and bounded by 40 % of its Nyquist frequency as :func:`choose_cutoff` bounds it."""
    segments = [g for s in scans for g in s.segments]
    longest = max(g.samples for g in segments)
    return float(max(g.cutoff if g.cutoff >= floor else min(floor, 0.2 * g.rate) for g in segments
                     if g.samples >= min(longest, SPECTRUM_SAMPLES)))


@dataclass(frozen=True)
class Plan:
    """How one segment of a recording is cut: its first raw sample ``start`` in the recording, the
    filter's edge and the decimation, the windows (in the segment's samples)."""

    source: str
    start: int
    edge: int
    factor: int
    rate: float
    note: str
    windows: tuple
    samples: int  # decimated samples of the segment's motion
    length: int = 0  # raw samples of the segment

    @property
    def spans(self) -> list[tuple[int, int]]:
        """The raw samples of each window, counted in the recording."""
        return [(self.start + w.raw[0], self.start + w.raw[1]) for w in self.windows]


def plan_windows(s: Scan, cutoff: float, settings: StreamSettings) -> tuple[list[Plan], list[str]]:
    """The windows of every segment of one recording for :func:`pieces` (margins from the filters'
    impulse responses), and notes naming the segments too short for the filters' edges (left out, as
    :func:`identify.observation.matrix.filtered_motions` does)."""
    plans, notes = [], []
    for k, g in enumerate(s.segments):
        edge = max(2, math.ceil(EDGE_PERIODS * g.rate / cutoff)) if g.samples > 1 else 2
        name = f"{s.source}#{k + 1}" if len(s.segments) > 1 else s.source
        if len(s.segments) > 1 and g.samples < 2 * edge + 5:
            notes.append(f"{name}: segment of {g.samples} samples left out (shorter than the {2 * edge + 5} the "
                         f"filter's edges need at {cutoff:.3g} Hz)")
            continue
        dplan = decimation_plan(g.rate, settings.decimate_to)
        factor = dplan.factor
        delay_samples = int(math.ceil(abs(settings.delay) * g.rate)) + 1 if settings.delay else 0
        lp = lowpass_margin(g.rate, cutoff) + delay_samples + DELAY_MARGIN
        if settings.min_velocity is not None and has_policy(settings.rest, "crossing"):
            # A rest run is a crossing when shorter than CROSSING_SECONDS: a run cut by a window's edge is then at
            # least that long inside it, and judged as the whole run is.
            lp += int(math.ceil(CROSSING_SECONDS * g.rate)) + 1
        windows = motion_windows(g.samples, edge, factor, settings.block, lp, decimation_margin(factor))
        plans.append(Plan(name, g.start, edge, factor, dplan.rate, dplan.note, tuple(windows), windows[-1].core[1],
                          g.samples))
    if not plans:
        raise ValueError("no segment is long enough to filter: " + "; ".join(notes))
    return plans, notes


#: Extra raw samples of margin for the torque shifts of the delay search (±20 ms at up to 2.5 kHz).
DELAY_MARGIN = 50


@dataclass(frozen=True, eq=False)
class Piece:
    """The decimated rows of one block's core: ``motion`` (a FilteredMotion cut to the core),
    ``first`` the index of its first sample in the motion of all recordings, ``extra_Y`` the torques
    shifted by each lag asked (delay search), each (S, n)."""

    motion: Any
    first: int
    extra_Y: tuple[np.ndarray, ...] = ()


def piece(robot: rx90sym.Robot, rec: Any, window: Any, plan: Plan, cutoff: float, settings: StreamSettings,
          regressor: Callable[..., np.ndarray], names: Sequence[str], first: int,
          lags: Sequence[float] = ()) -> Piece:
    """One window through :func:`filtered_motion`, cut back to its core (a Dask task when distributed)."""
    r0 = window.raw[0]
    d0, d1 = window.span
    # The plan's factor for every window of a segment (its achieved rate: a window's own median step could round a
    # ratio of 12.5 the other way, and its rows would then not tile the segment's).
    rest_span = None
    if settings.min_velocity is not None and has_policy(settings.rest, "crossing"):
        # The rest runs of "crossing" measured beyond the window's core, up to the segment's own filter edges,
        # as in one window (plan_windows gave the margin room for them).
        context = int(math.ceil(CROSSING_SECONDS * rec.rate)) + 1 if rec.n_samples > 1 else 0
        rest_span = slice(max(plan.edge, d0 - context) - r0, min(plan.length - plan.edge, d1 + context) - r0)
    m = filtered_motion(robot, rec, cutoff, plan.rate if plan.factor > 1 else None, settings.spring, regressor, names,
                        settings.min_velocity, settings.rest, settings.delay, kept=slice(d0 - r0, d1 - r0),
                        rest_span=rest_span)
    j0 = (d0 - plan.edge) // plan.factor
    core = slice(window.core[0] - j0, window.core[1] - j0)
    extra = []
    for lag in lags:  # the delay search: only Y moves (identify.estimation.delay)
        Y = shifted_torques(rec, lag)[m.kept] + m.extra
        extra.append((decimate(Y, m.factor) if m.factor > 1 else Y)[core])
    kept = None
    if settings.left_out:  # joints whose torque is left out: none of their rows enters W
        kept = np.ones(m.Phi.shape[1], dtype=bool)
        kept[list(settings.left_out)] = False
    cut = type(m)(m.t[core], m.q[core], m.dq[core], m.ddq[core], m.Y[core], m.Phi[core], m.cutoff, m.rate,
                  m.source, m.moving[core], m.usable[core], m.factor, m.kept, 0.0, m.note,
                  None if m.measured is None else m.measured[core], kept)
    return Piece(cut, first + window.core[0], tuple(extra))


def windows_in_order(sources: Sequence[BlockSource], plans: Sequence[Sequence[Plan]]) -> Iterator[tuple]:
    """(plan, window, raw samples, first) for every window of every segment of every recording, in
    order; ``first``: the index of the segment's first decimated sample among all segments."""
    offset = 0
    for src, src_plans in zip(sources, plans):
        pairs = [(plan, window) for plan in src_plans for window in plan.windows]
        spans = [span for plan in src_plans for span in plan.spans]
        starts = {}
        for plan in src_plans:
            starts[id(plan)] = offset
            offset += plan.samples
        for (plan, window), rec in zip(pairs, src.windows(spans)):
            yield plan, window, rec, starts[id(plan)]


def pieces(robot: rx90sym.Robot, sources: Sequence[BlockSource], plans: Sequence[Sequence[Plan]], cutoff: float,
           settings: StreamSettings, regressor: Callable[..., np.ndarray], names: Sequence[str],
           lags: Sequence[float] = (), submit: Callable[..., Any] | None = None) -> Iterator[Any]:
    """Second pass: the pieces of every segment of every recording in order (``plans``: per recording,
    from :func:`plan_windows`; ``submit(fn, *args)`` runs them elsewhere, e.g.
    ``dask.distributed.Client.submit``; futures are then yielded in order)."""
    for plan, window, rec, first in windows_in_order(sources, plans):
        args = (robot, rec, window, plan, cutoff, settings, regressor, names, first, tuple(lags))
        yield piece(*args) if submit is None else submit(piece, *args)


def in_order(task: Callable[..., Any], arguments: Iterable[tuple], client: Any = None,
             in_flight: int = 2) -> Iterator[Any]:
    """``task(*args)`` for every tuple of ``arguments``, here, or on a ``dask.distributed.Client`` with at
    most ``in_flight`` tasks submitted; the results in order (the fold that follows is the serial one)."""
    if client is None:
        for args in arguments:
            yield task(*args)
        return
    queue: deque = deque()
    for args in arguments:
        queue.append(client.submit(task, *args, pure=False))
        if len(queue) >= in_flight:
            yield queue.popleft().result()
    while queue:
        yield queue.popleft().result()
