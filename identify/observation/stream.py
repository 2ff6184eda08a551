"""The observation matrix of a long log, block by block (eqs. 6-8 and 20 without the whole log in memory).

Two passes over each recording (:class:`identify.io.blocks.BlockSource`):

1. :func:`scan` — read in blocks, checked like a whole file; count the samples, take the rate, and
   stream the Welch spectrum of the raw accelerations so that the automatic cut-off
   (:func:`identify.observation.matrix.automatic_cutoff`) is the whole log's;
2. :func:`pieces` — the blocks of :func:`identify.signal.blocks.motion_windows` (core plus margins
   from the filters' impulse responses), each through :func:`filtered_motion` exactly as a whole
   recording, cut back to its core: a :class:`Piece` of decimated rows.

Peak memory is that of one block: the full-rate regressor of a block with its margins,
(block + 2·margin) × n × c doubles, and its parallel-filtered copies (about three such arrays).
Every quantity downstream (incremental QR, bootstrap, validation) consumes pieces.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Callable, Iterator, Sequence

import numpy as np

import rx90sym

from identify.io.blocks import DEFAULT_BLOCK, BlockSource
from identify.observation.matrix import DECIMATION_PASSBAND, automatic_cutoff, filtered_motion, shifted_torques
from identify.observation.processing import RestPolicy
from identify.signal.blocks import WelchAccumulator, decimation_margin, lowpass_margin, motion_windows
from identify.signal.filtering import EDGE_PERIODS, cutoff_from_spectrum, decimate, decimation_plan

__all__ = ["DEFAULT_BLOCK", "Piece", "Scan", "StreamSettings", "pieces", "plan_windows", "scan", "scan_all"]



@dataclass(frozen=True)
class StreamSettings:
    """The processing of a streamed fit: cut-off [Hz] (None: chosen), decimate_to [Hz] (None: none),
    min_velocity [rad/s] (None: no rest mask), rest policy, torque delay [s], spring, block [raw samples]."""

    cutoff: float | None = None
    decimate_to: float | None = 50.0
    min_velocity: float | None = None
    rest: RestPolicy = "drop"
    delay: float = 0.0
    spring: bool = True
    block: int = DEFAULT_BLOCK


@dataclass(frozen=True)
class Scan:
    """What the first pass learnt of one recording: samples, rate [Hz] (first block's median step),
    and either the Welch spectrum of its raw accelerations or, for a recording of one block, the recording."""

    source: str
    samples: int
    rate: float
    spectrum: tuple[np.ndarray, np.ndarray] | None
    whole: Any = None
    q_range: np.ndarray | None = None  # (2, n) smallest and largest position of each joint [rad]


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


def scan(src: BlockSource, block: int, need_spectrum: bool) -> Scan:
    """First pass over one recording (checks every block; see the module docstring)."""
    welch, rate, first = None, float("nan"), None
    lo = hi = None
    steps = StepCounts()  # the rate is the whole log's, 1 / median step
    for k, rec in enumerate(src.scan(block)):
        lo = rec.q.min(axis=0) if lo is None else np.minimum(lo, rec.q.min(axis=0))
        hi = rec.q.max(axis=0) if hi is None else np.maximum(hi, rec.q.max(axis=0))
        steps.add(np.diff(rec.t[max(0, int(rec.meta.get("new_from", 0)) - 1):]))
        if k == 0:
            rate = 1.0 / float(np.median(np.diff(rec.t)))  # for the spectrum; the same to rounding
            first = rec
            if need_spectrum:
                welch = WelchAccumulator(rate, max(16, int(round(4.0 * rate))), rec.q.shape[1])
        elif k == 1:
            first = None
        if welch is not None:
            new = int(rec.meta.get("new_from", 0))
            q = rec.q[max(0, new - 2):]
            welch.feed((q[2:] - 2.0 * q[1:-1] + q[:-2]) * rate**2)
    n = int(src.n_samples)
    rate = 1.0 / steps.median()
    q_range = np.vstack([lo, hi])
    if first is not None:  # one block: the whole-recording rule, exactly
        return Scan(src.source, n, rate, None, first, q_range)
    return Scan(src.source, n, rate, welch.result() if welch is not None else None, None, q_range)


def scan_all(sources: Sequence[BlockSource], settings: StreamSettings) -> tuple[list[Scan], float]:
    """Scan every recording; the cut-off [Hz] given, or chosen as on the whole recordings."""
    need = settings.cutoff is None
    scans = [scan(src, settings.block, need) for src in sources]
    if not need:
        return scans, float(settings.cutoff)
    floor = max(2.0, DECIMATION_PASSBAND * settings.decimate_to) if settings.decimate_to else 2.0
    cuts = [automatic_cutoff([s.whole], settings.decimate_to) if s.whole is not None
            else cutoff_from_spectrum(*s.spectrum, s.rate, min_cutoff=floor) for s in scans]
    return scans, float(max(cuts))


@dataclass(frozen=True)
class Plan:
    """How one recording is cut: its scan, the filter's edge and the decimation, the windows."""

    scan: Scan
    edge: int
    factor: int
    rate: float
    note: str
    windows: tuple
    samples: int  # decimated samples of the whole motion

    @property
    def spans(self) -> list[tuple[int, int]]:
        return [w.raw for w in self.windows]


def plan_windows(s: Scan, cutoff: float, settings: StreamSettings) -> Plan:
    """The windows of one recording for :func:`pieces` (margins from the filters' impulse responses)."""
    edge = max(2, math.ceil(EDGE_PERIODS * s.rate / cutoff))
    dplan = decimation_plan(s.rate, settings.decimate_to)
    k = dplan.factor
    delay_samples = int(math.ceil(abs(settings.delay) * s.rate)) + 1 if settings.delay else 0
    lp = lowpass_margin(s.rate, cutoff) + delay_samples + DELAY_MARGIN
    windows = motion_windows(s.samples, edge, k, settings.block, lp, decimation_margin(k))
    # The plan travels with every block (Dask tasks): without the recording a short log's scan keeps.
    return Plan(replace(s, whole=None, spectrum=None, q_range=None), edge, k, dplan.rate, dplan.note, tuple(windows),
                windows[-1].core[1])


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
    m = filtered_motion(robot, rec, cutoff, settings.decimate_to, settings.spring, regressor, names,
                        settings.min_velocity, settings.rest, settings.delay, kept=slice(d0 - r0, d1 - r0))
    j0 = (d0 - plan.edge) // plan.factor
    core = slice(window.core[0] - j0, window.core[1] - j0)
    extra = []
    for lag in lags:  # the delay search: only Y moves (identify.signal.delay)
        Y = shifted_torques(rec, lag)[m.kept] + m.extra
        extra.append((decimate(Y, m.factor) if m.factor > 1 else Y)[core])
    cut = type(m)(m.t[core], m.q[core], m.dq[core], m.ddq[core], m.Y[core], m.Phi[core], m.cutoff, m.rate,
                  m.source, m.moving[core], m.usable[core], m.factor, m.kept, 0.0, m.note)
    return Piece(cut, first + window.core[0], tuple(extra))


def pieces(robot: rx90sym.Robot, sources: Sequence[BlockSource], plans: Sequence[Plan], cutoff: float,
           settings: StreamSettings, regressor: Callable[..., np.ndarray], names: Sequence[str],
           lags: Sequence[float] = (), submit: Callable[..., Any] | None = None) -> Iterator[Any]:
    """Second pass: the pieces of every recording in order (``submit(fn, *args)`` runs them elsewhere,
    e.g. ``dask.distributed.Client.submit``; futures are then yielded in order)."""
    offset = 0
    for src, plan in zip(sources, plans):
        for window, rec in zip(plan.windows, src.windows(plan.spans)):
            args = (robot, rec, window, plan, cutoff, settings, regressor, names, offset, tuple(lags))
            yield piece(*args) if submit is None else submit(piece, *args)
        offset += plan.samples
