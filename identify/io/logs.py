"""Controller logs: a raw CSV whose columns the user names, read into a :class:`Recording`.

A log is what a robot controller writes: no header (or one this reader does not trust), one row
per sample, time stamps of the controller's own clock, the controller's joint angles, often
motor currents instead of torques, an irregular period, and sometimes corrupt rows. The user
names every column with a *column map* (``columns=``, ``rx90 convert --columns``)::

    t,q1..q6,qd1..qd6,i1..i6,x:i_target1..x:i_target6,x:tau_target1..x:tau_target6

Names (n = the robot's number of joints):

====================  ==================================================================
``t``                 time stamp, s (the log's own clock; kept as recorded)
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
  :data:`POSITION_MARGIN` beyond the robot's limits, a time that does not increase, or a time
  step larger than :data:`MAX_GAP_PERIODS` median steps (a gap). Corrupt rows inside the window
  raise :class:`RecordingError` naming the first bad rows by line number of the file.
* ``rows=(FIRST, LAST)`` (1-based line numbers, inclusive) or ``t_from``/``t_to`` (seconds of
  the log's clock: from the first row at or after ``t_from`` to the last row at or before
  ``t_to``) select a clean window; only the window is checked. When the time stamps of a
  corrupt head jump forward and back, select by ``rows``.
* Time steps within 1 % of the median step are regular (rate = 1 / mean step). Beyond that the
  log is refused with the figures unless ``resample=HZ`` puts every signal on a uniform grid
  ``t0 + k/HZ`` (:func:`identify.signal.resampling.resample`: positions by cubic Hermite interpolation
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
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

import rx90sym
from rx90sym.recording import Recording, RecordingError

from identify.io.columns import ColumnMap, parse_columns
from identify.io.units import check_units
from identify.io.gains import DriveGains, apply_gains, read_gains
from identify.signal.resampling import resample as resample_recording
from identify.io.recordings import JUMP_ATOL, JUMP_SAFETY, TIME_RTOL, RecordingWarning, _normalise_convention

__all__ = ["ColumnMap", "parse_columns", "read_log", "ABSURD", "POSITION_MARGIN", "MAX_GAP_PERIODS",
           "STILL", "MOVING_SPAN", "VELOCITY_MISMATCH"]

#: A value larger than this in magnitude (any column but time) marks its row as corrupt.
ABSURD = 1e6
#: A position further than this beyond the robot's joint limits (rad) marks its row as corrupt.
POSITION_MARGIN = 1.0
#: A time step longer than this many median steps is a gap: an error naming the rows.
MAX_GAP_PERIODS = 5.0
#: A joint whose position spans less than this (rad) in the window does not move (the UR10e logs
#: print 4 decimals: 1e-4 rad of quantisation).
STILL = 1e-3
#: Recorded velocities are compared with the derivative of the positions on joints that move at
#: least this much (rad) in the window (below, quantisation dominates the derivative).
MOVING_SPAN = 0.05
#: Largest RMS difference between a recorded velocity and the derivative of its positions, as a
#: fraction of the derivative's RMS (measured on the UR10e logs: see docs/real-logs.md).
VELOCITY_MISMATCH = 0.5
#: How many bad rows a message names before "and K more".
_SHOWN = 3

# --------------------------------------------------------------------------------------------
# Rows of the file
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Lines:
    """The data lines of a log: their 1-based line numbers and text."""

    source: str
    numbers: list[int]
    text: list[str]


def _data_lines(path: Path, header: bool, n_cols: int) -> _Lines:
    source = path.name
    try:
        raw = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise RecordingError(f"{source}: not a UTF-8 text file ({exc})") from None
    lines = [line.rstrip("\r") for line in raw.split("\n")]  # the numbering of editors and sed -n
    while lines and not lines[-1].strip():  # trailing blank lines are not rows
        lines.pop()
    numbers, text = [], []
    header_line = None
    for k, line in enumerate(lines, start=1):
        if line.lstrip().startswith("#"):
            continue
        if header and header_line is None:
            header_line = k
            _check_header(source, k, line, n_cols)
            continue
        numbers.append(k)
        text.append(line)
    if not numbers:
        raise RecordingError(f"{source}: no data rows")
    return _Lines(source, numbers, text)


def _check_header(source: str, k: int, line: str, n_cols: int) -> None:
    """The header line ``k`` has the column map's cell count and is not a row of numbers."""
    cells = line.split(",")
    if len(cells) != n_cols:
        raise RecordingError(f"{source}: line {k} (the header) has {len(cells)} cells, the column map "
                             f"names {n_cols}{_separator_hint(line, n_cols)}")
    if all(_is_number(c) for c in cells):
        raise RecordingError(f"{source}: line {k}, read as the header, holds only numbers: the log "
                             f"has no header (--no-header, header=False in Python)")


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _separator_hint(line: str, n_cols: int) -> str:
    if line.count(",") + 1 < n_cols and line.count(";") + 1 >= n_cols:
        return "; the file seems to use ';' as separator (expected ',')"
    return ""


def _window(lines: _Lines, rows: tuple[int, int] | None, t_from: float | None, t_to: float | None,
            t_col: int) -> tuple[int, int]:
    """Indices [a, b) into ``lines`` of the selected window."""
    source, numbers = lines.source, lines.numbers
    if rows is not None:
        first, last = (int(r) for r in rows)
        if first < 1 or last < first:
            raise ValueError(f"rows {first}:{last}: expected 1 <= FIRST <= LAST (1-based line numbers)")
        if last > numbers[-1]:
            raise RecordingError(f"{source}: rows {first}:{last}: the file ends at line {numbers[-1]}")
        a = int(np.searchsorted(numbers, first))
        b = int(np.searchsorted(numbers, last, side="right"))
        if b - a < 1:
            raise RecordingError(f"{source}: rows {first}:{last} hold no data row")
        return a, b
    if t_from is None and t_to is None:
        return 0, len(numbers)
    if t_from is not None and t_to is not None and t_to <= t_from:
        raise ValueError(f"--to {t_to:g} s must be after --from {t_from:g} s")
    times = np.full(len(numbers), np.nan)  # rows whose time cannot be read never bound a window
    for k, line in enumerate(lines.text):
        cells = line.split(",")
        if t_col < len(cells):
            try:
                times[k] = float(cells[t_col])
            except ValueError:
                pass
    lo = -np.inf if t_from is None else float(t_from)
    hi = np.inf if t_to is None else float(t_to)
    after = np.flatnonzero(times >= lo)
    before = np.flatnonzero(times <= hi)
    if not after.size or not before.size or before[-1] < after[0]:
        finite = times[np.isfinite(times)]
        span = f"{finite.min():g} to {finite.max():g} s" if finite.size else "no readable time"
        raise RecordingError(f"{source}: no row between {lo:g} and {hi:g} s (the log's clock runs {span})")
    return int(after[0]), int(before[-1]) + 1


def _bad(source: str, problems: list[tuple[int, str]]) -> RecordingError:
    """One message naming the first bad rows by line number and what is wrong with them."""
    problems = sorted(problems)
    shown = "; ".join(f"line {line}: {what}" for line, what in problems[:_SHOWN])
    more = len(problems) - _SHOWN
    tail = f" (and {more} more bad rows, the last at line {problems[-1][0]})" if more > 0 else ""
    return RecordingError(f"{source}: {shown}{tail}; select a clean window with --rows FIRST:LAST "
                          f"or --from/--to (rows=, t_from=, t_to= in Python)")


def _parse(lines: _Lines, a: int, b: int, cmap: ColumnMap) -> np.ndarray:
    """Numbers of the window's rows (N, ncols); corrupt rows raise naming their lines."""
    n_cols = len(cmap.names)
    cells = [line.split(",") for line in lines.text[a:b]]
    problems: dict[int, str] = {}  # row index in the window -> what is wrong (the first thing)
    for k, row in enumerate(cells):
        if not "".join(row).strip():
            problems[k] = "empty row"
        elif len(row) != n_cols:
            problems[k] = (f"{len(row)} cells, the column map names {n_cols}"
                           f"{_separator_hint(lines.text[a + k], n_cols)}")
    counts = {len(row) for row in cells}
    if len(counts) == 1 and n_cols not in counts:
        # Not corrupt rows: a column map that does not fit the file.
        raise RecordingError(f"{lines.source}: every row of lines {lines.numbers[a]}..{lines.numbers[b - 1]} has "
                             f"{len(cells[0])} cells, the column map names {n_cols}"
                             f"{_separator_hint(lines.text[a], n_cols)}; fix the column map (--columns, "
                             f"columns= in Python)")
    values = np.full((len(cells), n_cols), np.nan)
    whole = [k for k in range(len(cells)) if k not in problems]
    try:
        values[whole] = np.array([cells[k] for k in whole], dtype=float).reshape(len(whole), n_cols)
    except ValueError:  # locate the text cells, row by row
        for k in whole:
            for col, cell in enumerate(cells[k]):
                try:
                    values[k, col] = float(cell)
                except ValueError:
                    problems.setdefault(k, f"column {col + 1} ('{cmap.names[col]}'): {cell.strip()!r} is "
                                           f"not a number")
    used = [c for c, name in enumerate(cmap.names) if name != "_"]
    for k in whole:
        if k in problems:
            continue
        for col in used:
            v = values[k, col]
            if not math.isfinite(v):
                problems[k] = f"column {col + 1} ('{cmap.names[col]}'): value {v:g} is not finite"
            elif col != cmap.t and abs(v) > ABSURD:
                problems[k] = f"column {col + 1} ('{cmap.names[col]}'): value {v:g} is absurdly large (> {ABSURD:g})"
            else:
                continue
            break
    if problems:
        raise _bad(lines.source, [(lines.numbers[a + k], what) for k, what in problems.items()])
    return values


def _check_time(t: np.ndarray, numbers: Sequence[int], source: str) -> None:
    """Time increases, with no step beyond MAX_GAP_PERIODS median steps."""
    if t.size < 2:
        raise RecordingError(f"{source}: line {numbers[0]}: a log needs at least 2 rows")
    dt = np.diff(t)
    problems = [(numbers[k + 1], f"time {t[k + 1]:g} s does not increase (line {numbers[k]}: {t[k]:g} s)")
                for k in np.flatnonzero(dt <= 0.0)]
    if problems:
        raise _bad(source, problems)
    step = float(np.median(dt))
    problems = [(numbers[k], f"gap of {dt[k]:g} s to line {numbers[k + 1]} ({dt[k] / step:.3g} median steps of "
                             f"{step:g} s, at most {MAX_GAP_PERIODS:g})")
                for k in np.flatnonzero(dt > MAX_GAP_PERIODS * step)]
    if problems:
        raise _bad(source, problems)


def _check_positions(q: np.ndarray, t: np.ndarray, numbers: Sequence[int], cmap: ColumnMap,
                     robot: rx90sym.Robot, source: str) -> None:
    """Positions (model angles) within the limits + POSITION_MARGIN, and no faster jump than
    JUMP_SAFETY x the velocity limit between two rows (a corrupt value inside the limits)."""
    lo = np.asarray(robot.limits.q_min, dtype=float) - POSITION_MARGIN
    hi = np.asarray(robot.limits.q_max, dtype=float) + POSITION_MARGIN
    problems = []
    for k in np.flatnonzero(np.any((q < lo) | (q > hi), axis=1)):
        j = int(np.flatnonzero((q[k] < lo) | (q[k] > hi))[0])
        problems.append((numbers[k], f"column {cmap.q[j] + 1} ('q{j + 1}'): {q[k, j]:g} rad (model angle) is "
                                     f"beyond joint {j + 1}'s limits [{lo[j] + POSITION_MARGIN:g}, "
                                     f"{hi[j] - POSITION_MARGIN:g}] rad by more than {POSITION_MARGIN:g} rad"))
    if problems:
        raise _bad(source, problems)
    qd_max = np.asarray(robot.limits.qd_max, dtype=float)
    allowed = JUMP_SAFETY * qd_max[None, :] * np.diff(t)[:, None] + JUMP_ATOL
    jumps = np.abs(np.diff(q, axis=0)) > allowed  # inf limits never flag
    for k in np.flatnonzero(np.any(jumps, axis=1)):
        j = int(np.flatnonzero(jumps[k])[0])
        problems.append((numbers[k + 1], f"joint {j + 1} jumps {abs(q[k + 1, j] - q[k, j]):g} rad from line "
                                         f"{numbers[k]} in {t[k + 1] - t[k]:g} s (more than {JUMP_SAFETY:g} x "
                                         f"its velocity limit {qd_max[j]:g} rad/s)"))
    if problems:
        raise _bad(source, problems)


def _check_velocities(dq: np.ndarray | None, q: np.ndarray, t: np.ndarray, span: np.ndarray,
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


def _irregular(t: np.ndarray, numbers: Sequence[int], source: str) -> str | None:
    """None when every step is within TIME_RTOL of the median step, else the refusal text."""
    dt = np.diff(t)
    step = float(np.median(dt))
    off = np.flatnonzero(np.abs(dt - step) > TIME_RTOL * step)
    if not off.size:
        return None
    return (f"{source}: irregular time steps: {off.size} of {dt.size} steps differ from the median step "
            f"{step:g} s by more than {TIME_RTOL:.0%} (steps from {dt.min():g} to {dt.max():g} s, the first "
            f"at line {numbers[off[0] + 1]}); resample on a uniform grid with --resample HZ (resample= in "
            f"Python), e.g. --resample {_round_rate(1.0 / float(np.mean(dt))):g}")


def _round_rate(rate: float) -> float:
    """A round rate near ``rate`` (2 significant digits) for the hint."""
    digits = max(0, 1 - int(math.floor(math.log10(rate))))
    return round(rate, digits) if digits else float(round(rate, -int(math.floor(math.log10(rate))) + 1))


# --------------------------------------------------------------------------------------------
# The reader
# --------------------------------------------------------------------------------------------


def read_log(
    path: str | os.PathLike[str], robot: rx90sym.Robot, columns: str | Sequence[str],
    header: bool = False, rows: tuple[int, int] | None = None, t_from: float | None = None,
    t_to: float | None = None, resample: float | None = None, gains: DriveGains | str | None = None,
    convention: str | None = None,
) -> Recording:
    """Read a controller log (a CSV whose columns ``columns`` names) as a recording.

    Args:
        path: the log, comma separated; lines starting with ``#`` are skipped.
        robot: the robot the log belongs to.
        columns: the column map (module docstring), a string or a list of names.
        header: the first non-comment line is a header (skipped; its cell count is checked).
        rows: ``(FIRST, LAST)`` 1-based line numbers of the file, inclusive.
        t_from, t_to: window in seconds of the log's clock (not with ``rows``).
        resample: rate in Hz of a uniform grid to put every signal on; required when the time
            steps are irregular (more than 1 % from the median step).
        gains: drive gains (a :class:`DriveGains`, a comma list in N·m/A joint side, or a JSON
            file) turning the currents into joint torques; without them ``tau`` stays None.
        convention: angles of the log, ``"controller"`` (default: what a controller logs) or
            ``"model"`` (Khalil); converted once to model angles.

    Returns:
        A recording in model angles; ``meta["log"]`` says what was done: ``lines`` (first, last
        line read), ``rows`` (count), ``rate_hz`` (1 / mean step of the log), ``median_step_s``,
        ``largest_gap_s`` and ``largest_gap_lines``, ``irregular_steps``, ``resampled_hz`` (or
        None), ``samples``, ``gains`` (their source, or None), ``convention``.

    Raises:
        RecordingError: corrupt rows, gaps or irregular time (message names file and lines).
        ValueError: a bad column map, window or gains.
    """
    p = Path(path)
    cmap, conv, drive = _log_options(p, robot, columns, rows, t_from, t_to, gains, convention)
    lines = _data_lines(p, header, len(cmap.names))
    a, b = _window(lines, rows, t_from, t_to, cmap.t)
    values = _parse(lines, a, b, cmap)
    numbers = lines.numbers[a:b]
    t = values[:, cmap.t]
    _check_time(t, numbers, p.name)
    q_file = values[:, list(cmap.q)]
    q = np.asarray(robot.to_model(q_file), dtype=float) if conv == "controller" else q_file
    dq = values[:, list(cmap.qd)] if cmap.qd else None
    # Degrees and swapped q/qd groups named as such, before they read as corrupt rows.
    check_units(t, q_file, dq, robot, p.name, numbers, to_model=conv == "controller", ranges=False)
    _check_positions(q, t, numbers, cmap, robot, p.name)

    span = np.ptp(q, axis=0)
    _check_velocities(dq, q, t, span, numbers, cmap, p.name)
    if np.all(span < STILL):
        warnings.warn(f"{p.name}: no joint moves in lines {numbers[0]}..{numbers[-1]} (largest position span "
                      f"{span.max():g} rad): a recording at rest identifies gravity and offsets at most",
                      RecordingWarning, stacklevel=2)
    dt = np.diff(t)
    k_gap = int(np.argmax(dt))
    report = {"lines": [numbers[0], numbers[-1]], "rows": int(t.size), "rate_hz": float(1.0 / np.mean(dt)),
              "median_step_s": float(np.median(dt)), "largest_gap_s": float(dt[k_gap]),
              "largest_gap_lines": [numbers[k_gap], numbers[k_gap + 1]],
              "irregular_steps": int(np.sum(np.abs(dt - np.median(dt)) > TIME_RTOL * np.median(dt))),
              "resampled_hz": None, "samples": int(t.size), "gains": None, "convention": conv,
              "position_span_rad": span.tolist()}
    if resample is None:
        refusal = _irregular(t, numbers, p.name)
        if refusal:
            raise RecordingError(refusal)

    def take(cols: tuple[int, ...]) -> np.ndarray | None:
        return values[:, list(cols)] if cols else None

    rec = Recording(t=t, q=q, tau=take(cmap.tau), dq=dq, source=p.name, robot=robot.name,
                    meta={"log": report}, current=take(cmap.i),
                    aux={name: values[:, col] for name, col in cmap.aux})
    if resample is not None:
        rec = resample_recording(rec, float(resample))
        report["resampled_hz"] = float(resample)
        report["samples"] = rec.n_samples
    if drive is not None:
        rec = apply_gains(rec, drive, robot)
        rec.meta["log"]["gains"] = gains_label(drive)
    return rec


def gains_label(drive: DriveGains) -> str:
    """How the report names the drive gains: their file, or their values."""
    return drive.source if drive.source not in ("--gains", "<memory>") else ",".join(f"{k:g}" for k in drive.gains) + " N·m/A"


def _log_options(p: Path, robot: rx90sym.Robot, columns: str | Sequence[str], rows: tuple[int, int] | None,
                 t_from: float | None, t_to: float | None, gains: DriveGains | str | None,
                 convention: str | None) -> tuple[ColumnMap, str, DriveGains | None]:
    """The column map, the convention and the drive gains of a log, checked together."""
    if rows is not None and (t_from is not None or t_to is not None):
        raise ValueError("give rows or t_from/t_to (--rows or --from/--to), not both")
    cmap = parse_columns(columns, robot)
    conv = _normalise_convention(convention, p.name) or "controller"
    if gains is not None and not cmap.i:
        raise ValueError(f"drive gains given, but the column map names no motor currents (i1..i{robot.n})")
    if gains is not None and cmap.tau:
        raise ValueError("drive gains given, but the log already holds joint torques (tau1..): "
                         "the gains would replace them; map the torques as x:NAME to keep both")
    return cmap, conv, read_gains(gains, robot) if isinstance(gains, (str, os.PathLike)) else gains
