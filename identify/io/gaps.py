"""Lost packets and stale samples of a real-time stream: found on the raw rows, before resampling.

A host PC that logs a robot's real-time stream loses packets (a time step of several periods)
and repeats the last packet when a new one is late (a *stale* row: every signal identical to the
previous row, the time stamp advancing). Both are facts about the data, not corruption:

* a stale row is dropped (it is not a sample of the motion: the motion seems to stop and restart);
  its time becomes a lost packet like any other;
* a time step longer than :data:`LOST_STEPS` median steps has lost packets. Up to ``max_gap``
  seconds (:data:`DEFAULT_MAX_GAP`), the gap is bridged when resampling (cubic Hermite with the
  recorded velocities, :mod:`identify.io.resampling`) and the bridged samples are marked as
  not measured (``Recording.measured``): they keep the filters continuous but never enter the
  observation matrix; a longer gap starts a new segment (``Recording.segment``), filtered and
  differentiated on its own.

Why 50 ms: splitting costs every segment end the filter's start-up, ``EDGE_PERIODS / cut-off``
(0.3 s at 10 Hz, :func:`identify.signal.filtering.derivatives`), six times a 50 ms bridge; the
Hermite error with recorded velocities is at most h^4/384 max|q''''| (h the gap): for h = 50 ms
and a 1 rad sine at 2 Hz, 4e-4 rad on samples that are not used as measurements anyway.
"""
from __future__ import annotations

import warnings

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from rx90sym.recording import RecordingError

from identify.io.defaults import DEFAULT_MAX_GAP

__all__ = ["RETIME_SPEED", "RETIME_TOLERANCE", "sample_periods", "EDGE_PERIODS", "DEFAULT_MAX_GAP", "LOST_STEPS", "MIN_SEGMENT_ROWS", "SPLITS_LISTED", "Gap", "LogGaps", "stale_rows", "find_gaps",
           "all_segments_short"]

#: Samples dropped at each end by :func:`identify.signal.filtering.derivatives`, in periods of the cut-off frequency.
#: The impulse response of the order-4 Butterworth filter has decayed to 1e-3 of its peak after
#: 3 periods of the cut-off (1e-4 after 4), so the start-up transients left by the forward–backward
#: pass (already reduced by sosfiltfilt's odd-extension padding) are gone after 3 periods.
EDGE_PERIODS = 3.0
#: A time step longer than this many median steps has lost at least one packet (host-clock jitter
#: of a fraction of a period stays below it; one lost packet makes a step of 2 periods).
LOST_STEPS = 1.5
#: Fewest rows of a segment kept when a log has several: the fewest samples the fit's filters can
#: use at any cut-off below Nyquist (two edges of more than 2·EDGE_PERIODS samples each, plus 5;
#: identify.observation.matrix.filtered_motions). A shorter segment (e.g. one row between two
#: gaps) holds no row of W at any cut-off, and cannot even be resampled with one row.
MIN_SEGMENT_ROWS = 2 * (2 * int(EDGE_PERIODS) + 1) + 5
#: How many gaps that split a log (and dropped segments) the summary lists by lines; the counts cover all.
SPLITS_LISTED = 10


@dataclass(frozen=True)
class Gap:
    """Lost packets between two rows: ``lines`` (the rows before and after, file line numbers),
    ``duration`` (s), ``periods`` (duration / median step) and ``bridged`` (False: a new segment)."""

    lines: tuple[int, int]
    duration: float
    periods: float
    bridged: bool

    def to_dict(self) -> dict:
        return {"lines": list(self.lines), "duration_s": self.duration, "periods": self.periods,
                "bridged": self.bridged}


@dataclass(frozen=True)
class LogGaps:
    """Every gap of a log (time order), the segment of each row (0, 1, ...) and the segments
    dropped as too short to filter (``dropped``: first and last line of each, rows)."""

    gaps: tuple[Gap, ...]
    segment: np.ndarray
    max_gap: float
    dropped: tuple[tuple[int, int, int], ...] = ()

    @property
    def bridged(self) -> tuple[Gap, ...]:
        return tuple(g for g in self.gaps if g.bridged)

    @property
    def splits(self) -> tuple[Gap, ...]:
        return tuple(g for g in self.gaps if not g.bridged)

    def summary(self) -> dict:
        """Counts and the gaps themselves, for the JSON and the printed report; ``splits``: the first
        SPLITS_LISTED gaps that split the log (``splits_total`` of them)."""
        return {"max_gap_s": self.max_gap, "bridged_gaps": len(self.bridged),
                "bridged_lost_periods": float(sum(g.periods - 1.0 for g in self.bridged)),
                "segments": int(self.segment[-1]) + 1 if self.segment.size else 0,
                "gaps": [g.to_dict() for g in self.gaps], "splits_total": len(self.splits),
                "splits": [g.to_dict() for g in self.splits[:SPLITS_LISTED]], "dropped_segments": len(self.dropped),
                "dropped_rows": int(sum(rows for _, _, rows in self.dropped)),
                "dropped_lines": [[a, b] for a, b, _ in self.dropped[:SPLITS_LISTED]]}


def stale_rows(values: np.ndarray, t_col: int, used: Sequence[int]) -> np.ndarray:
    """(N,) bool: rows equal to the previous row in every used column but the time ``t_col``.

    A row is compared with the row just before it in the file (a run of repeats is stale from its
    second row on). Exact equality: a real sample of a moving or noisy signal never repeats every
    column to the last digit; a robot at rest with quantised signals can, and losing such a row
    costs nothing (the gap is bridged with the same values).
    """
    cols = [c for c in used if c != t_col]
    same = np.all(values[1:, cols] == values[:-1, cols], axis=1)
    return np.r_[False, same]


#: Re-timing a clock that counts samples: a joint's speed must be at least this [rad/s] (over both rows)
#: for its position step to time the row, and the steps of the joints that time it must agree on a whole
#: number of periods within this share of a period.
RETIME_SPEED, RETIME_TOLERANCE = 0.05, 0.3


def sample_periods(q: np.ndarray, dq: np.ndarray, period: float) -> np.ndarray:
    """(N - 1,) the whole number of periods [s] between consecutive rows of a log whose clock counts samples,
    from the positions (N, n) [rad] and the recorded velocities (N, n) [rad/s]: each joint moving at
    least RETIME_SPEED over both rows times the step by its position change over its mean recorded speed,
    the median of those rounded when it is a whole number within RETIME_TOLERANCE (0: the same cycle
    logged again; 2 and more: cycles the logger lost), else 1 (no joint moving: the clock as it counts)."""
    v = 0.5 * (dq[1:] + dq[:-1])
    moving = (np.abs(dq[1:]) >= RETIME_SPEED) & (np.abs(dq[:-1]) >= RETIME_SPEED) & (np.sign(dq[1:]) == np.sign(dq[:-1]))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(moving, np.diff(q, axis=0) / (v * period), np.nan)
    out = np.ones(ratio.shape[0], dtype=int)
    timed = moving.any(axis=1)
    if timed.any():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # rows with no joint moving: NaN, kept at 1
            k = np.nanmedian(ratio[timed], axis=1)
        whole = np.round(k)
        sure = (np.abs(k - whole) <= RETIME_TOLERANCE) & (whole >= 0)
        out[np.flatnonzero(timed)[sure]] = whole[sure].astype(int)
    return out


def find_gaps(t: np.ndarray, numbers: Sequence[int], max_gap: float = DEFAULT_MAX_GAP) -> LogGaps:
    """The gaps of increasing time stamps ``t`` (s) whose rows are lines ``numbers`` of the file.

    A step longer than :data:`LOST_STEPS` median steps is a gap; one longer than ``max_gap`` (s)
    starts a new segment.
    """
    if not (np.isfinite(max_gap) and max_gap > 0):
        raise ValueError(f"max_gap must be a positive time in s, got {max_gap!r}")
    dt = np.diff(t)
    step = float(np.median(dt))
    found = []
    for k in np.flatnonzero(dt > LOST_STEPS * step):
        found.append(Gap((int(numbers[k]), int(numbers[k + 1])), float(dt[k]), float(dt[k] / step),
                         bool(dt[k] <= max_gap)))
    split = dt > max(max_gap, LOST_STEPS * step)
    segment = np.r_[0, np.cumsum(split)].astype(np.int64)
    return LogGaps(tuple(found), segment, float(max_gap))




def all_segments_short(source: str, max_gap: float, first: tuple[int, int]) -> RecordingError:
    """The error of a log whose segments are all too short to filter (``first``: the first one's lines)."""
    return RecordingError(f"{source}: every segment between gaps longer than {max_gap:g} s has fewer than "
                          f"{MIN_SEGMENT_ROWS} rows (lines {first[0]}..{first[1]} the first): none is long "
                          f"enough to filter")
