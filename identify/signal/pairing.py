"""Pairing an empty and a loaded run of the same trajectory logged separately, segment by segment
(payload method 3, same-motion drive gains).

Two real runs of one trajectory start at different instants of the controller's clock and have
different lengths; a log cut at gaps too long to bridge is made of segments, each a run of the
motion. :func:`pair_runs` pairs segment k of the empty run with segment k of the loaded run (both
runs must have as many): it finds the time lag from the positions (cross-correlation of the
normalised positions, refined to a fraction of a sample by minimising the position gap), keeps the
common part and reports the lag and the largest position gap; beyond ``position_tol`` the runs are
refused (not the same motion). :meth:`PairedRuns.loaded_span` and :func:`on_empty_grid` then put the
loaded run's samples on the empty run's time stamps window by window, so that a pair of logs of any
length is compared block by block. Memory: one segment's positions, read ``block`` samples at a time;
a segment longer than ``block`` samples is paired on every k-th sample (positions are smooth), its
position gap measured on those samples.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Iterator, Sequence

import numpy as np

from rx90sym.recording import Recording

from identify.io.blocks import DEFAULT_BLOCK
from identify.io.resampling import interpolate
from identify.signal.defaults import POSITION_TOLERANCE

__all__ = ["PairedRuns", "pair_runs", "on_empty_grid", "POSITION_TOLERANCE", "accepting_tolerance",
           "recording_segments"]

# A lag below this fraction of a sample is taken as none: the samples are used as they are.
_NO_SHIFT = 1e-3
#: Samples between the time stamps a pair keeps of each run (and the last one): where a window of
#: the empty run finds the loaded samples it needs (:meth:`PairedRuns.loaded_span`).
CLOCK_STRIDE = 64
#: Loaded samples read beyond those a window needs, at each end: the interpolation's support (a cubic
#: spline's end effect decays by ~0.27 a sample: 40 samples leave it below 1e-22).
SPLINE_MARGIN = 40


@dataclass(frozen=True, eq=False)
class PairedRuns:
    """One segment of an empty run and the same segment of the loaded run, on the empty run's time stamps.

    empty, loaded: the sources (``NAME#k`` for segment k of a run of several); lag: loaded-run clock
    minus empty-run clock at the same point of the motion, s; gap: largest |q_empty − q_loaded| over
    the common part, rad, and ``gap_joint`` (1-based); dropped: samples of the empty segment outside
    the common part (start, end); span: the common part, raw samples [a, b) of the empty recording;
    segment: the loaded segment's raw samples [a, b) in its recording; shift: a lag of a whole number
    of samples, loaded raw sample = empty raw sample + shift (None: the loaded samples are
    interpolated); clocks: (sample, time) every :data:`CLOCK_STRIDE`-th sample of both segments.
    """

    empty: str
    loaded: str
    lag: float
    gap: float
    gap_joint: int
    dropped: tuple[int, int]
    span: tuple[int, int]
    segment: tuple[int, int]
    shift: int | None
    clocks: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]

    @property
    def samples(self) -> int:
        """Common samples (on the empty run's time stamps)."""
        return self.span[1] - self.span[0]

    def summary(self) -> str:
        return (f"paired {self.empty} with {self.loaded}: lag {self.lag:.6g} s, {self.samples} common samples "
                f"({self.dropped[0]} + {self.dropped[1]} dropped), largest position gap {self.gap:.3g} rad "
                f"(joint {self.gap_joint})")

    def to_dict(self) -> dict[str, Any]:
        """The pairing entry of a payload or gains JSON."""
        return {"empty": self.empty, "loaded": self.loaded, "lag_s": self.lag, "position_gap_rad": self.gap,
                "position_gap_joint": self.gap_joint, "common_samples": self.samples}

    def loaded_span(self, r0: int, r1: int) -> tuple[int, int]:
        """Raw samples [a, b) of the loaded recording that hold the motion of the empty recording's
        samples [r0, r1) (within :attr:`span`), with :data:`SPLINE_MARGIN` more at each end."""
        if self.shift is not None:
            return r0 + self.shift, r1 + self.shift
        ie, te, il, tl = self.clocks
        start = self.span[0] - self.dropped[0]  # the empty segment's first raw sample
        lo = te[np.searchsorted(ie, r0 - start, "right") - 1] + self.lag              # <= t_e[r0] + lag
        hi = te[min(int(np.searchsorted(ie, r1 - 1 - start, "left")), ie.size - 1)] + self.lag
        k0 = max(int(np.searchsorted(tl, lo, "right")) - 1, 0)
        k1 = min(int(np.searchsorted(tl, hi, "left")), il.size - 1)
        a, b = self.segment
        return a + max(int(il[k0]) - SPLINE_MARGIN, 0), a + min(int(il[k1]) + SPLINE_MARGIN + 1, b - a)

    def recordings(self, empty: Recording, loaded: Recording) -> tuple[Recording, Recording]:
        """The common part of two runs held in memory (those paired), the loaded one on the empty run's
        time stamps (one window: :func:`on_empty_grid`)."""
        e = empty.select(slice(*self.span))
        return e, on_empty_grid(self, e, loaded.select(slice(*self.loaded_span(*self.span))))


def on_empty_grid(pair: PairedRuns, empty: Recording, loaded: Recording) -> Recording:
    """The loaded run's samples at the empty window's time stamps + the lag (``loaded``: the samples of
    :meth:`PairedRuns.loaded_span` of the window), on the empty window's time stamps: taken as they are
    for a whole-sample lag, else interpolated (identify.io.resampling.interpolate)."""
    meta = {**loaded.meta, "paired_with": pair.empty, "lag_s": pair.lag}
    if pair.shift is not None:
        if loaded.n_samples != empty.n_samples:
            raise ValueError(f"{pair.loaded}: {loaded.n_samples} samples for {empty.n_samples} of {pair.empty}")
        return replace(loaded, t=empty.t, meta=meta, segment=None)
    r = interpolate(replace(loaded, segment=None), np.clip(empty.t + pair.lag, loaded.t[0], loaded.t[-1]))
    return replace(r, t=empty.t, meta=meta)


def recording_segments(rec: Recording) -> list[tuple[int, int]]:
    """(first raw sample, samples) of each segment of a recording in memory."""
    if rec.segment is None:
        return [(0, rec.n_samples)]
    edges = np.r_[0, np.flatnonzero(np.diff(rec.segment)) + 1, rec.n_samples]
    return [(int(a), int(b - a)) for a, b in zip(edges[:-1], edges[1:])]


@dataclass(frozen=True)
class _Held:
    """One segment's positions: every ``every``-th sample (t, q, dq) and all its time stamps ``clock``."""

    name: str
    start: int
    clock: np.ndarray
    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray | None
    every: int


def _held(run: Any, segments: Sequence[tuple[int, int]], block: int) -> Iterator[_Held]:
    """Each segment of ``run`` (a recording in memory or a :class:`~identify.io.blocks.BlockSource`) read
    ``block`` samples at a time, in order (one pass over a file)."""
    spans = [(a, min(a + block, start + n)) for start, n in segments for a in range(start, start + n, block)]
    windows = (run.select(slice(a, b)) for a, b in spans) if isinstance(run, Recording) else run.windows(spans)
    name = run.source
    for k, (start, n) in enumerate(segments):
        every = max(1, math.ceil(n / block))
        clock, t, q, dq = [], [], [], []
        for a in range(start, start + n, block):
            rec = next(windows)
            pick = np.flatnonzero((np.arange(a, a + rec.n_samples) - start) % every == 0)
            clock.append(np.asarray(rec.t, dtype=float))
            t.append(np.asarray(rec.t, dtype=float)[pick])
            q.append(np.asarray(rec.q, dtype=float)[pick])
            dq.append(None if rec.dq is None else np.asarray(rec.dq, dtype=float)[pick])
        yield _Held(f"{name}#{k + 1}" if len(segments) > 1 else name, start, np.concatenate(clock),
                    np.concatenate(t), np.concatenate(q), None if dq[0] is None else np.concatenate(dq), every)


def _uniform(t: np.ndarray, q: np.ndarray, step: float) -> np.ndarray:
    """Positions resampled on a grid of ``step`` s from the first sample."""
    t = t - t[0]
    grid = np.arange(0.0, t[-1] + 1e-12, step)
    return np.stack([np.interp(grid, t, q[:, j]) for j in range(q.shape[1])], axis=1)


def _coarse_lag(empty: _Held, loaded: _Held, step: float) -> float:
    """Lag (s), to the sample of ``step``, that minimises the mean squared gap of the normalised
    positions over the overlap (sums by FFT cross-correlation and cumulative sums)."""
    a, b = _uniform(empty.t, empty.q, step), _uniform(loaded.t, loaded.q, step)
    scale = a.std(axis=0)
    moving = scale > 1e-6  # a joint at rest carries no timing information
    if not np.any(moving):
        raise ValueError(f"{empty.name}: no joint moves; the runs cannot be paired in time")
    a, b = a[:, moving] / scale[moving], b[:, moving] / scale[moving]
    lags = np.arange(-(len(a) - 1), len(b))   # b[n + lag] against a[n]
    from scipy.signal import correlate  # SciPy when pairing runs, not when the command line starts

    cross = sum(correlate(b[:, j], a[:, j], mode="full", method="fft") for j in range(a.shape[1]))
    ca = np.concatenate([[0.0], np.cumsum(np.sum(a**2, axis=1))])
    cb = np.concatenate([[0.0], np.cumsum(np.sum(b**2, axis=1))])
    n0 = np.maximum(0, -lags)
    n1 = np.minimum(len(a), len(b) - lags)
    overlap = n1 - n0
    ssd = (ca[n1] - ca[n0]) + (cb[n1 + lags] - cb[n0 + lags]) - 2 * cross
    # Overlaps shorter than half the shorter run do not count: short ends match by chance.
    ssd = np.where(overlap >= 0.5 * min(len(a), len(b)), ssd / np.maximum(overlap, 1), np.inf)
    k = int(np.argmin(ssd))
    return float(lags[k] * step + loaded.t[0] - empty.t[0])


# [rad^2] mismatch of a lag with too little overlap: above any real mean squared gap, and finite
# (an infinite value makes Brent's parabolic step inf - inf).
_NO_OVERLAP = 1e6


def accepting_tolerance(gap: float) -> float:
    """A round position tolerance (2 significant digits, rad) that accepts a gap of ``gap`` rad."""
    scale = 10.0 ** (math.floor(math.log10(gap)) - 1)
    return math.ceil(gap / scale * (1 + 1e-12)) * scale


def _positions_at(held: _Held, t: np.ndarray) -> np.ndarray:
    """The held positions at times ``t`` (identify.io.resampling's rule: cubic Hermite with the recorded
    velocities, else a cubic spline)."""
    from scipy.interpolate import CubicHermiteSpline, CubicSpline

    if held.dq is not None:
        return CubicHermiteSpline(held.t, held.q, held.dq, axis=0)(t)
    return CubicSpline(held.t, held.q, axis=0)(t)


def _pair(empty: _Held, loaded: _Held, loaded_end: int, position_tol: float, max_lag: float | None,
          instead: str) -> PairedRuns:
    """The lag, common part and position gap of one segment of each run."""
    from scipy.interpolate import CubicSpline
    from scipy.optimize import minimize_scalar

    step = float(np.median(np.diff(empty.clock)))
    coarse_step = step * empty.every
    coarse = _coarse_lag(empty, loaded, coarse_step)
    spline = CubicSpline(loaded.t, loaded.q, axis=0)
    least = 0.5 * min(empty.t.size, loaded.t.size)

    def mismatch(lag: float) -> float:
        t = empty.t + lag
        inside = (t >= loaded.t[0]) & (t <= loaded.t[-1])
        if inside.sum() < least:
            return _NO_OVERLAP
        return float(np.mean((spline(t[inside]) - empty.q[inside]) ** 2))

    # Sub-sample refinement: the position gap is smooth in the lag near its minimum.
    lag = float(minimize_scalar(mismatch, bounds=(coarse - 1.5 * coarse_step, coarse + 1.5 * coarse_step),
                                method="bounded", options={"xatol": 1e-4 * step}).x)
    if max_lag is not None and abs(lag) > max_lag:
        raise ValueError(f"{loaded.name}: lag {lag:.6g} s to {empty.name} exceeds {max_lag:g} s")
    te, tl = empty.clock, loaded.clock
    shift = (lag - (tl[0] - te[0])) / step
    whole = round(shift)
    t_l = te + lag
    inside = np.flatnonzero((t_l >= tl[0] - 1e-9 * step) & (t_l <= tl[-1] + 1e-9 * step))
    if inside.size < 5:
        raise ValueError(f"{empty.name} and {loaded.name} have no common part at lag {lag:.6g} s")
    first, last = int(inside[0]), int(inside[-1])
    offset = None
    if abs(shift - whole) < _NO_SHIFT and np.allclose(np.diff(tl), step, rtol=1e-6, atol=0):
        offset = int(np.argmin(np.abs(tl - t_l[first]))) - first  # loaded segment sample - empty segment sample
    if empty.every == 1 and offset is not None:
        q_e, q_l = empty.q[first:last + 1], loaded.q[first + offset:last + 1 + offset]
    else:  # the held samples of the common part; the loaded positions at their times + the lag
        held = np.flatnonzero((empty.t >= te[first]) & (empty.t <= te[last]))
        q_e = empty.q[held]
        q_l = _positions_at(loaded, np.clip(empty.t[held] + lag, tl[0], tl[-1]))
    diff = np.abs(q_e - q_l)
    gap = float(diff.max())
    gap_joint = int(np.unravel_index(np.argmax(diff), diff.shape)[1]) + 1
    if gap > position_tol:
        raise ValueError(f"{empty.name} and {loaded.name}: after the lag {lag:.6g} s the positions still "
                         f"differ by up to {gap:.3g} rad on joint {gap_joint}, more than --position-tol "
                         f"{position_tol:g} rad: not the same motion, or one run drifted; --position-tol "
                         f"{accepting_tolerance(gap):g} accepts this pair (position_tol= in Python), {instead} "
                         f"needs no pairing")
    stride = [np.unique(np.r_[np.arange(0, c.size, CLOCK_STRIDE), c.size - 1]) for c in (te, tl)]
    shift_raw = None if offset is None else loaded.start + offset - empty.start
    return PairedRuns(empty.name, loaded.name, lag, gap, gap_joint, (first, te.size - 1 - last),
                      (empty.start + first, empty.start + last + 1), (loaded.start, loaded_end), shift_raw,
                      (stride[0], te[stride[0]], stride[1], tl[stride[1]]))


def pair_runs(empty: Any, loaded: Any, position_tol: float = POSITION_TOLERANCE, max_lag: float | None = None,
              instead: str = "--method 4", block: int = DEFAULT_BLOCK,
              segments: tuple[Sequence[tuple[int, int]], Sequence[tuple[int, int]]] | None = None
              ) -> tuple[PairedRuns, ...]:
    """Pair two runs of one trajectory segment by segment (eq. 28 needs both at the same instants).

    Args:
        empty, loaded: two runs of the same trajectory (recordings in memory, or block sources of
            files: :class:`identify.io.blocks.BlockSource`), uniform time steps, any clocks and lengths.
        position_tol: largest position gap accepted over each common part, rad.
        max_lag: refuse a lag larger than this, s (None: any).
        instead: the method that needs no pairing, named by the refusal of a position gap.
        block: raw samples read at a time; a longer segment is paired on every k-th sample.
        segments: ((first raw sample, samples) of each segment of the empty run, the same of the loaded
            run); None: those of the recordings in memory (:func:`recording_segments`).

    Returns:
        One :class:`PairedRuns` per segment; the loaded samples are interpolated at t_empty + lag (not
        at all when the lag is a whole number of samples to within 1e-3 of a sample).

    Raises:
        ValueError: different joints, different numbers of segments (both counts named), no common
            part, lag beyond ``max_lag``, or a position gap beyond ``position_tol`` (the message gives
            the lag and the gap).
    """
    seg_e, seg_l = segments if segments is not None else (recording_segments(empty), recording_segments(loaded))
    if len(seg_e) != len(seg_l):
        raise ValueError(f"{empty.source} has {len(seg_e)} segment{'s' * (len(seg_e) != 1)} and {loaded.source} "
                         f"{len(seg_l)} (gaps too long to bridge): paired runs are compared segment by segment, "
                         f"each segment of one run with the same segment of the other; {instead} needs no pairing")
    pairs = []
    for (e, l), (a, n) in zip(zip(_held(empty, seg_e, block), _held(loaded, seg_l, block)), seg_l):
        if e.q.shape[1] != l.q.shape[1]:
            raise ValueError(f"{empty.source} has {e.q.shape[1]} joints and {loaded.source} {l.q.shape[1]}")
        pairs.append(_pair(e, l, a + n, position_tol, max_lag, instead))
    return tuple(pairs)
