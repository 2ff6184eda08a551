"""Controller logs: the column map and the checks of their rows (read by :func:`identify.read_log`,
:mod:`identify.io.log_blocks`, with the rules of :mod:`identify.io.log_rules`).

A log is what a robot controller writes: no header (or one this reader does not trust), one row
per sample, time stamps of the controller's own clock, the controller's joint angles, often
motor currents instead of torques, an irregular period, and sometimes corrupt rows. The user
names every column with a *column map* (``columns=``, ``rx90 convert --columns``)::

    t,q1..q6,qd1..qd6,i1..i6,x:i_target1..x:i_target6,x:tau_target1..x:tau_target6

Names (n = the robot's number of joints):

====================  ==================================================================
``t``                 time stamp, s (the log's own clock; the recording starts at 0 s, its first sample)
``q1``..``qn``        joint positions, rad, controller angles (all n required)
``qd1``..``qdn``      recorded joint velocities, rad/s (all or none) -> ``Recording.dq``
``tau1``..``taun``    joint torques, N·m, joint side (all or none)
``i1``..``in``        motor currents, A (all or none) -> ``Recording.current``
``_``                 a column to ignore
``x:NAME``            an auxiliary column kept in ``Recording.aux[NAME]``, never a torque
====================  ==================================================================

Shorthands: ``q1..q6`` (same prefix, increasing numbers; also ``x:i_target1..x:i_target6``) and
``_*3`` (three ignored columns). Either torques or currents (or both) must be present.

Rules (one time tolerance everywhere, as in :mod:`identify.io.recordings`):

* A row is corrupt when it has the wrong number of cells, a cell that is not a number, a value
  that is not finite or larger than :data:`ABSURD` in magnitude, a position more than
  :data:`POSITION_MARGIN` beyond the robot's limits, or a time that does not increase (a gap is
  not corrupt: stale rows, lost packets and segments in :mod:`identify.io.gaps`). Corrupt rows
  inside the window raise :class:`RecordingError` naming the first bad rows by line number of the file.
* ``rows=(FIRST, LAST)`` (1-based line numbers, inclusive) or ``t_from``/``t_to`` (seconds of
  the log's clock: from the first row at or after ``t_from`` to the last row at or before
  ``t_to``) select a clean window; only the window is checked. When the time stamps of a
  corrupt head jump forward and back, select by ``rows``.
* Time steps within 1 % of the median step are regular (rate = 1 / mean step). Beyond that the
  log is refused with the figures unless ``resample=HZ`` puts every signal on a uniform grid
  ``t0 + k/HZ`` (:func:`identify.io.resampling.resample`: positions by cubic Hermite interpolation
  with the recorded velocities when there are some, the rest linearly), before any filtering.
* A recorded-velocity column that is 0 on every row while its joint moves is refused (it holds
  no velocities); a window where no joint moves more than :data:`STILL` gives a
  :class:`~identify.io.recordings.RecordingWarning`.
* Currents become joint torques only with drive gains (:func:`identify.io.gains.apply_gains`);
  without gains the recording keeps its currents and ``tau`` is None.
"""
from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Sequence

import numpy as np

import rx90sym
from rx90sym.recording import RecordingError

from identify.io.columns import ColumnMap, parse_columns
from identify.io.log_rows import ABSURD, WINDOW_ADVICE, bad_rows
from identify.io.gains import DriveGains, read_gains, warn_negative
from identify.io.gaps import DEFAULT_MAX_GAP, LOST_STEPS, LogGaps
from identify.io.recordings import JUMP_ATOL, JUMP_SAFETY, TIME_RTOL, _normalise_convention

__all__ = ["ColumnMap", "parse_columns", "ABSURD", "POSITION_MARGIN", "DEFAULT_MAX_GAP",
           "STILL", "MOVING_SPAN", "VELOCITY_MISMATCH", "LISTED_ROWS", "gains_label", "log_drive",
           "log_options", "check_increasing", "refuse_splits", "check_positions", "check_velocities",
           "irregular_refusal"]

#: A position further than this beyond the robot's joint limits (rad) marks its row as corrupt.
POSITION_MARGIN = 1.0
#: A joint whose position spans less than this (rad) in the window does not move (the UR10e logs
#: print 4 decimals: 1e-4 rad of quantisation).
STILL = 1e-3
#: Recorded velocities are compared with the derivative of the positions on joints that move at
#: least this much (rad) in the window (below, quantisation dominates the derivative).
MOVING_SPAN = 0.05
#: Largest RMS difference between a recorded velocity and the derivative of its positions, as a
#: fraction of the derivative's RMS (measured on the UR10e logs: see docs/real-logs.md).
VELOCITY_MISMATCH = 0.5

def check_increasing(t: np.ndarray, numbers: Sequence[int], source: str, window: bool = True) -> None:
    """Time increases (a gap is not an error: :func:`identify.io.gaps.find_gaps`). A log's
    rule; a recording's regular clock is checked by :func:`identify.io.checks._check_time`.
    ``window``: the input form can select a window of lines (a CSV log; a bag cannot)."""
    if t.size < 2:
        raise RecordingError(f"{source}: line {numbers[0]}: a log needs at least 2 rows")
    dt = np.diff(t)
    problems = [(numbers[k + 1], f"time {t[k + 1]:g} s does not increase (line {numbers[k]}: {t[k]:g} s)")
                for k in np.flatnonzero(dt <= 0.0)]
    if problems:
        raise bad_rows(source, problems, WINDOW_ADVICE if window else None)


def refuse_splits(found: LogGaps, source: str, window: bool = True) -> None:
    """With segments refused: every gap longer than the limit, named by its lines, and what would
    take it (``window``: the input form can select a window of lines, a CSV log; a bag cannot)."""
    problems = [(g.lines[0], f"gap of {g.duration:g} s to line {g.lines[1]} ({g.periods:.3g} median steps), "
                             f"longer than the {found.max_gap:g} s that can be bridged")
                for g in found.splits]
    if problems:
        bridge = _round_up(max(g.duration for g in found.splits))
        advice = (("select a window without it with --rows FIRST:LAST or --from/--to, " if window else "")
                  + f"let it split the log into segments (without --no-segments) or bridge it with --max-gap "
                    f"{bridge:g} (" + ("rows=, t_from=, t_to=, " if window else "")
                  + "segments=True, max_gap= in Python)")
        raise bad_rows(source, problems, advice)


def _round_up(seconds: float) -> float:
    """A round time just above ``seconds`` (2 significant digits), for a --max-gap that bridges it."""
    scale = 10.0 ** (math.floor(math.log10(seconds)) - 1)
    return math.floor(seconds / scale + 1.0) * scale


def check_positions(q: np.ndarray, t: np.ndarray, numbers: Sequence[int], cmap: ColumnMap,
                     robot: rx90sym.Robot, source: str, window: bool = True) -> None:
    """Positions (model angles) within the limits + POSITION_MARGIN, and no faster jump than
    JUMP_SAFETY x the velocity limit between two rows (a corrupt value inside the limits);
    ``window`` as for :func:`check_increasing`."""
    advice = WINDOW_ADVICE if window else None
    lo = np.asarray(robot.limits.q_min, dtype=float) - POSITION_MARGIN
    hi = np.asarray(robot.limits.q_max, dtype=float) + POSITION_MARGIN
    problems = []
    for k in np.flatnonzero(np.any((q < lo) | (q > hi), axis=1)):
        j = int(np.flatnonzero((q[k] < lo) | (q[k] > hi))[0])
        problems.append((numbers[k], f"column {cmap.q[j] + 1} ('q{j + 1}'): {q[k, j]:g} rad (model angle) is "
                                     f"beyond joint {j + 1}'s limits [{lo[j] + POSITION_MARGIN:g}, "
                                     f"{hi[j] - POSITION_MARGIN:g}] rad by more than {POSITION_MARGIN:g} rad"))
    if problems:
        raise bad_rows(source, problems, advice)
    qd_max = np.asarray(robot.limits.qd_max, dtype=float)
    allowed = JUMP_SAFETY * qd_max[None, :] * np.diff(t)[:, None] + JUMP_ATOL
    jumps = np.abs(np.diff(q, axis=0)) > allowed  # inf limits never flag
    for k in np.flatnonzero(np.any(jumps, axis=1)):
        j = int(np.flatnonzero(jumps[k])[0])
        problems.append((numbers[k + 1], f"joint {j + 1} jumps {abs(q[k + 1, j] - q[k, j]):g} rad from line "
                                         f"{numbers[k]} in {t[k + 1] - t[k]:g} s (more than {JUMP_SAFETY:g} x "
                                         f"its velocity limit {qd_max[j]:g} rad/s)"))
    if problems:
        raise bad_rows(source, problems, advice)


def check_velocities(dq: np.ndarray | None, q: np.ndarray, t: np.ndarray, span: np.ndarray,
                      numbers: Sequence[int], cmap: ColumnMap, source: str) -> None:
    """A velocity column that is 0 on every row while its joint moves is not a velocity (the
    Hermite interpolation would flatten the motion between samples); one that does not match
    the derivative of its joint's positions (relative RMS difference above VELOCITY_MISMATCH) is a
    wrong column map (swapped or mislabelled columns, deg/s)."""
    if dq is None:
        return
    for j in np.flatnonzero(np.all(dq == 0.0, axis=0) & (span >= STILL)):
        raise RecordingError(f"{source}: column {cmap.qd[j] + 1} ('qd{j + 1}') is 0 on every row of lines "
                             f"{numbers[0]}..{numbers[-1]} while joint {j + 1} moves {span[j]:g} rad: it holds "
                             f"no recorded velocities; map it as _")
    moving = np.flatnonzero(span >= MOVING_SPAN)
    if t.size < 3 or not moving.size:
        return
    derivative = np.gradient(q, t, axis=0)
    scale = np.sqrt(np.mean(derivative ** 2, axis=0))

    def mismatch(v: np.ndarray, k: int) -> float:
        return float(np.sqrt(np.mean((v - derivative[:, k]) ** 2)) / scale[k])

    for j in moving:
        off = mismatch(dq[:, j], j)
        if off <= VELOCITY_MISMATCH:
            continue
        others = [(mismatch(dq[:, j], k), k) for k in moving if k != j]
        best = min(others, default=(np.inf, -1))
        hint = (f"; it matches the derivative of q{best[1] + 1} ({best[0]:.0%}): are columns swapped?"
                if best[0] <= VELOCITY_MISMATCH else
                "; check the column map (swapped or mislabelled columns) and the unit (rad/s)")
        raise RecordingError(f"{source}: column {cmap.qd[j] + 1} ('qd{j + 1}') is not the velocity of column "
                             f"{cmap.q[j] + 1} ('q{j + 1}'): RMS difference to the derivative of the positions "
                             f"{off:.0%} of its RMS over lines {numbers[0]}..{numbers[-1]} (at most "
                             f"{VELOCITY_MISMATCH:.0%}){hint}")


# --------------------------------------------------------------------------------------------
# Time grid
# --------------------------------------------------------------------------------------------


def irregular_refusal(t: np.ndarray, numbers: Sequence[int], source: str, found: LogGaps | None = None) -> str | None:
    """None when every step inside a segment is within TIME_RTOL of the median step, else the
    refusal text (lost packets are irregular steps too: resampling bridges them)."""
    dt = np.diff(t)
    step = float(np.median(dt))
    inside = np.diff(found.segment) == 0 if found is not None else np.ones(t.size - 1, dtype=bool)
    off = np.flatnonzero((np.abs(dt - step) > TIME_RTOL * step) & inside)
    if not off.size:
        return None
    lost = "" if found is None else (f", {len(found.bridged)} of them lost packets up to {found.max_gap:g} s that resampling bridges"
            if found.bridged else "")
    stream = dt[dt <= LOST_STEPS * step]  # the stream's own steps: lost packets would lower its rate
    dt = dt[inside]
    return (f"{source}: irregular time steps: {off.size} of {dt.size} steps differ from the median step "
            f"{step:g} s by more than {TIME_RTOL:.0%} (steps from {dt.min():g} to {dt.max():g} s, the first "
            f"at line {numbers[off[0] + 1]}{lost}); resample on a uniform grid with --resample HZ (resample= in "
            f"Python), e.g. --resample {_round_rate(1.0 / float(np.mean(stream))):g} (1 / mean step without "
            f"lost packets)")


def _round_rate(rate: float) -> float:
    """A round rate near ``rate`` (2 significant digits) for the hint."""
    digits = max(0, 1 - int(math.floor(math.log10(rate))))
    return round(rate, digits) if digits else float(round(rate, -int(math.floor(math.log10(rate))) + 1))


#: How many stale rows the report lists by line.
LISTED_ROWS = 10


def gains_label(drive: DriveGains) -> str:
    """How the report names the drive gains: their file, or their values."""
    return drive.source if drive.source not in ("--gains", "<memory>") else ",".join(f"{k:g}" for k in drive.gains) + " N·m/A"


def log_options(p: Path, robot: rx90sym.Robot, columns: str | Sequence[str], rows: tuple[int, int] | None,
                 t_from: float | None, t_to: float | None, gains: DriveGains | str | None,
                 convention: str | None, time: bool = True) -> tuple[ColumnMap, str, DriveGains | None]:
    """The column map (``time``: with a time column), the convention and the drive gains of a log,
    checked together."""
    if rows is not None and (t_from is not None or t_to is not None):
        raise ValueError("give rows or t_from/t_to (--rows or --from/--to), not both")
    cmap = parse_columns(columns, robot, time=time)
    conv = _normalise_convention(convention, p.name) or "controller"
    return cmap, conv, log_drive(cmap, gains, robot)


def log_drive(cmap: ColumnMap, gains: DriveGains | str | None, robot: rx90sym.Robot) -> DriveGains | None:
    """The drive gains of a log (read from their file or list), refused when the log has no
    currents or already holds torques."""
    if gains is not None and not cmap.i:
        raise ValueError(f"drive gains given, but the column map names no motor currents (i1..i{robot.n})")
    if gains is not None and cmap.tau:
        raise ValueError("drive gains given, but the log already holds joint torques (tau1..): "
                         "the gains would replace them; map the torques as x:NAME to keep both")
    if isinstance(gains, (str, os.PathLike)):
        return read_gains(gains, robot)  # warns of negative gains
    if gains is not None:
        warn_negative(gains)
    return gains
