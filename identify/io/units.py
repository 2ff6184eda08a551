"""Units and column groups of a recording checked against its robot, before any fit.

Three mistakes make a log look like corrupt rows, or like another log, although every row is fine:

- positions in **degrees** (a log exported for a person): angles beyond the robot's joint limits
  by more than :data:`MARGIN` on many rows, some beyond a full turn, which the limits would all
  hold once divided by 180/pi;
- the **position and velocity groups swapped** (``qd1..qdn`` mapped as ``q1..qn`` and the other
  way round): the derivative of the "velocities" is the "positions", not the reverse;
- a time column that **counts samples** (0, 1, 2, ...: :func:`sample_clock_refusal`), read as
  seconds at 1 Hz, where the recorded velocities (or, without them, the robot's velocity limits)
  say the rows are far closer in time.

A recording whose positions lie beyond the limits for another reason (another robot, another
angle convention) is refused with the joint and the range named. Each check raises a
:class:`~rx90sym.recording.RecordingError` naming the file, the lines or samples and the cause.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

import rx90sym
from rx90sym.recording import RecordingError

__all__ = ["check_units", "sample_clock_refusal", "MARGIN", "DEGREE_SHARE", "DEGREE_LEAST", "SWAP_MATCH", "COUNTER_PERIOD",
           "COUNTER_SPEED", "COUNTER_PERCENTILE", "COUNTER_SPAN"]

#: Positions further than this beyond a joint's limits (rad) are out of range.
MARGIN = 1.0
#: Degrees: at least this share of the rows out of range, all within the limits once in radians.
DEGREE_SHARE = 0.05
#: Degrees: and some angle beyond a full turn (rad), which small angles in radians never reach.
DEGREE_LEAST = 2 * np.pi
#: Swapped groups: the derivative of the velocity columns matches the position columns within
#: this relative RMS difference while the positions' derivative does not match the velocities
#: (the same 50 % as the log reader's velocity check, identify.io.logs.VELOCITY_MISMATCH).
SWAP_MATCH = 0.5


def _mismatch(value: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Per column: RMS(value - reference) / RMS(reference) (inf where the reference is 0)."""
    scale = np.sqrt(np.mean(reference ** 2, axis=0))
    diff = np.sqrt(np.mean((value - reference) ** 2, axis=0))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(scale > 0, diff / np.where(scale > 0, scale, 1.0), np.inf)


def _swapped_groups(t: np.ndarray, q: np.ndarray, dq: np.ndarray) -> bool:
    """True when the velocity columns integrate to the position columns, not the reverse."""
    if t.size < 3:
        return False
    moving = np.ptp(dq, axis=0) > 0.05  # rad: joints that move (the "velocity" columns are q)
    if not moving.any():
        return False
    forward = _mismatch(dq[:, moving], np.gradient(q, t, axis=0)[:, moving])
    backward = _mismatch(q[:, moving], np.gradient(dq, t, axis=0)[:, moving])
    return bool(np.median(forward) > SWAP_MATCH and np.median(backward) <= SWAP_MATCH)


def _where(numbers: Sequence[int] | None, k: int) -> str:
    return f"line {numbers[k]}" if numbers is not None else f"sample {k + 1}"


def check_units(t: np.ndarray, q: np.ndarray, dq: np.ndarray | None, robot: rx90sym.Robot, source: str,
                numbers: Sequence[int] | None = None, to_model: bool = False, ranges: bool = True) -> None:
    """Refuse positions in degrees, swapped position/velocity groups and positions out of range.

    Args:
        t: (N,) time, s; q: (N, n) positions as read (rad expected); dq: (N, n) recorded
            velocities (rad/s) or None.
        robot: the robot the recording is read for (its joint limits, model angles).
        source: file name for the messages; numbers: 1-based line numbers of the rows (logs),
            else samples are named.
        to_model: q holds controller angles (shifted to model angles with the robot's offsets).
        ranges: also refuse positions out of range for another cause (False: the caller names
            such rows itself, e.g. as corrupt rows of a log).

    Raises:
        RecordingError: naming the cause (degrees, swapped groups, out of range) and where.
    """
    q = np.asarray(q, dtype=float)
    if dq is not None and _swapped_groups(np.asarray(t, float), q, np.asarray(dq, float)):
        raise RecordingError(f"{source}: the position and velocity groups look swapped: the derivative of "
                             f"the velocity columns is the position columns, not the reverse; map the "
                             f"columns q1..q{robot.n} and qd1..qd{robot.n} the other way round")
    model = (lambda x: np.asarray(robot.to_model(x), dtype=float)) if to_model else (lambda x: x)
    lo = np.asarray(robot.limits.q_min, dtype=float) - MARGIN
    hi = np.asarray(robot.limits.q_max, dtype=float) + MARGIN
    qm = model(q)
    out = (qm < lo) | (qm > hi)
    if not out.any():
        return
    rows = np.flatnonzero(out.any(axis=1))
    k = int(rows[0])
    j = int(np.flatnonzero(out[k])[0])
    qr = model(np.deg2rad(q))
    if (rows.size >= DEGREE_SHARE * len(q) and np.max(np.abs(q)) > DEGREE_LEAST
            and not np.any((qr < lo) | (qr > hi))):
        raise RecordingError(f"{source}: positions look like degrees: {rows.size} of {len(q)} rows lie beyond "
                             f"the joint limits of robot {robot.name} (first {_where(numbers, k)}, joint "
                             f"{j + 1}: {q[k, j]:g}), and all fit once converted to radians; give positions "
                             f"in rad (and velocities in rad/s)")
    if not ranges:
        return
    raise RecordingError(f"{source}: {_where(numbers, k)}: joint {j + 1} at {qm[k, j]:g} rad (model angle) is "
                         f"beyond robot {robot.name}'s limits [{lo[j] + MARGIN:g}, {hi[j] - MARGIN:g}] rad by "
                         f"more than {MARGIN:g} rad ({rows.size} of {len(q)} rows out of range): is it a "
                         f"recording of another robot, or in another angle convention?")


#: A time column that counts samples (or milliseconds): whole-number stamps in whole steps (a step of 1 reads
#: as a rate of 1 Hz) while the recorded velocities say one unit of the column is under COUNTER_PERIOD [s]...
COUNTER_PERIOD = 0.1
#: ... or, without recorded velocities, while every joint's steps per unit (their 95th percentile: a lost cycle
#: doubles a step) are below COUNTER_SPEED of its velocity limit per second: an arm counted in samples at 500 Hz
#: or more moves at most that much per row, one logged at 1 Hz crawls at under 0.2 % of its limits (one that
#: does is read with --period 1)...
COUNTER_SPEED = 0.002
#: The percentile of the steps judged against COUNTER_SPEED.
COUNTER_PERCENTILE = 95.0
#: ... and the arm moves: some joint spans at least this [rad].
COUNTER_SPAN = 0.05


def sample_clock_refusal(t: np.ndarray, q: np.ndarray, dq: np.ndarray | None, robot: rx90sym.Robot,
                         column: str) -> str | None:
    """Why the time column ``column`` (its description for the message) holds sample numbers (or
    milliseconds), not seconds (the rule of COUNTER_PERIOD, COUNTER_SPEED, COUNTER_SPAN), or None.

    Stamps that are whole numbers in whole steps (median step k >= 1: a rate of 1/k Hz read as seconds)
    while the recorded velocities say one unit of the column is under COUNTER_PERIOD s, or without them
    the arm moves at under COUNTER_SPEED of its velocity limits per unit.
    t: (N,) the column's values as read (any origin); q: (N, n) positions [rad]; dq: (N, n) recorded
    velocities [rad/s] or None; robot: its velocity limits."""
    t = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    if t.size < 3 or not np.all(t == np.round(t)):
        return None
    dt = np.diff(t)
    k = float(np.median(dt))
    if not (k >= 1 and k == round(k)) or not np.any(np.ptp(q, axis=0) >= COUNTER_SPAN):
        return None
    step = np.diff(q, axis=0)
    head = (f"{column} counts samples (or milliseconds), not seconds: whole numbers ({t[0]:g}, {t[1]:g}, {t[2]:g}, "
            f"...) in steps of {k:g} (read as seconds: a rate of {1 / k:.3g} Hz)")
    fix = "map the column as _ and give the sampling period with --period S (period= in Python)"
    if dq is not None:
        expected = 0.5 * (dq[1:] + dq[:-1]) * dt[:, None]  # the steps the velocities make per unit of the column
        power = float(np.sum(expected ** 2))
        if power > 0:
            unit = float(np.sum(step * expected) / power)  # s per unit of the column
            if not 0 < unit < COUNTER_PERIOD:
                return None
            return (f"{head}, while the recorded velocities say the rows are {unit * k:.3g} s apart; {fix}, "
                    f"e.g. --period {unit * k:.2g}")
    limit = np.asarray(robot.limits.qd_max, dtype=float)
    finite = np.isfinite(limit) & (limit > 0)
    if not finite.any():
        return None
    speed = np.percentile(np.abs(step) / dt[:, None], COUNTER_PERCENTILE, axis=0)[finite] / limit[finite]
    if np.any(speed >= COUNTER_SPEED):
        return None
    return (f"{head}, while read in seconds the arm would move at {100 * float(speed.max()):.2g} % of its velocity "
            f"limits or less ({COUNTER_PERCENTILE:g} % of the rows); {fix} (--period {k:g} if the rows are "
            f"{k:g} s apart)")
