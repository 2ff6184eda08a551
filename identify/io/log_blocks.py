"""A controller log read block by block: :func:`read_log` (a recording in memory) and
:func:`convert_log` (a recording file written as the blocks come), one reader for every length.

Lines are read and numbered in Python (comments, header), each block's numbers parsed by pyarrow's
CSV parser (C++, multithreaded; a block it refuses is parsed again by
:func:`identify.io.log_rows.parse_rows`, whose message names the bad lines), the window asked
(``rows`` or ``t_from``/``t_to``) selected on the way, then the rows go through the rules of
:mod:`identify.io.log_rules` (stale rows, checks, gaps and segments, resampling, drive gains).
``convert_log`` appends each part to the output through the atomic writer (an error leaves no file
behind); its output always has a ``segment`` column (and ``measured`` when resampled): the blocks to
come may need them; the stale-row count and the gaps that split the log go in header fields filled
in at the end (:mod:`identify.io.log_fields`). Memory: one block of lines (``read_log`` also holds the
recording it returns).
"""
from __future__ import annotations

import io
import math
import os
from pathlib import Path
from typing import IO, Any, Iterator, Sequence

import numpy as np

import rx90sym
from rx90sym.files import atomic_write
from rx90sym.recording import Recording, RecordingError

from identify.io.blocks import DEFAULT_LOG_BLOCK, check_block
from identify.io.checks import check_period
from identify.io.columns import ColumnMap, parse_columns, rtde_columns, rtde_refusal
from identify.io.gains import DriveGains
from identify.io.gaps import DEFAULT_MAX_GAP
from identify.io.log_block_report import BlockReport
from identify.io.log_fields import SPLITS_LISTED, file_fields
from identify.io.log_rows import ABSURD, LogLines, check_header, header_cells, parse_rows
from identify.io.log_rules import collected, log_parts, log_report, retimed_rate
from identify.io.logs import log_options
from identify.io.torque_signs import parse_torque_signs

__all__ = ["DEFAULT_LOG_BLOCK", "convert_log", "read_log"]


def _line_blocks(path: Path, header: bool, n_cols: int, size: int, spaced: bool = False) -> Iterator[LogLines]:
    """Data lines (number, text) in blocks of ``size``; comments and trailing blank lines dropped
    (``spaced``: cells separated by blanks, as UR's RTDE recorder writes them, read as commas)."""
    source = path.name
    numbers: list[int] = []
    text: list[str] = []
    blanks: list[tuple[int, str]] = []
    header_seen = not header
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            for k, line in enumerate(fh, start=1):
                line = line.rstrip("\n").rstrip("\r")
                if line.lstrip().startswith("#"):
                    continue
                if spaced:
                    line = ",".join(line.split())
                if not line.strip():
                    blanks.append((k, line))  # a row only if data follow (then parse_rows names it)
                    continue
                if not header_seen:
                    check_header(source, k, line, n_cols)
                    header_seen = True
                    continue
                for kb, lb in blanks:
                    numbers.append(kb)
                    text.append(lb)
                blanks = []
                numbers.append(k)
                text.append(line)
                if len(text) >= size:
                    yield LogLines(source, numbers, text)
                    numbers, text = [], []
    except UnicodeDecodeError as exc:
        raise RecordingError(f"{source}: not a UTF-8 text file ({exc})") from None
    if text:
        yield LogLines(source, numbers, text)


def _parse_fast(lines: LogLines, cmap: ColumnMap) -> np.ndarray:
    """Numbers of a block by pyarrow; anything it refuses goes to :func:`identify.io.logs.parse_rows`."""
    import pyarrow as pa
    from pyarrow import csv

    n_cols = len(cmap.names)
    names = [f"c{k}" for k in range(n_cols)]
    try:  # one thread: a refused log ends the command while Arrow's pool may still run (once killed it, -6)
        table = csv.read_csv(io.BytesIO("\n".join(lines.text).encode()),
                             read_options=csv.ReadOptions(column_names=names, use_threads=False),
                             convert_options=csv.ConvertOptions(column_types={c: pa.float64() for c in names}))
        values = np.column_stack([table.column(c).to_numpy(zero_copy_only=False) for c in names])
    except (pa.ArrowInvalid, ValueError):
        return parse_rows(lines, 0, len(lines.text), cmap)
    used = [c for c, name in enumerate(cmap.names) if name != "_" and c != cmap.t]
    if (values.shape[0] != len(lines.text) or not np.all(np.isfinite(values[:, [cmap.t] + used]))
            or np.any(np.abs(values[:, used]) > ABSURD)):
        return parse_rows(lines, 0, len(lines.text), cmap)
    return values


def _times(lines: LogLines, t_col: int) -> np.ndarray:
    """The time cell of each line (NaN where it cannot be read: such a row never bounds a window)."""
    times = np.full(len(lines.text), np.nan)
    for k, line in enumerate(lines.text):
        cells = line.split(",")
        if t_col < len(cells):
            try:
                times[k] = float(cells[t_col])
            except ValueError:
                pass
    return times


def _selected(blocks: Iterator[LogLines], cmap: ColumnMap, rows: tuple[int, int] | None, t_from: float | None,
              t_to: float | None, period: float | None = None) -> Iterator[tuple[np.ndarray, list[int]]]:
    """Parsed blocks of the window asked: the lines ``rows`` (FIRST, LAST, 1-based, inclusive), or from
    the first row at or after ``t_from`` to the last at or before ``t_to`` [s of the log's clock]; only
    the window's rows are parsed (a corrupt row outside it is not read). ``period`` [s]: a log without
    time column, sample k of the window at k period (a clock column appended last)."""
    if rows is not None:
        first, last = (int(r) for r in rows)
        if first < 1 or last < first:
            raise ValueError(f"rows {first}:{last}: expected 1 <= FIRST <= LAST (1-based line numbers)")
    if t_from is not None and t_to is not None and t_to <= t_from:
        raise ValueError(f"--to {t_to:g} s must be after --from {t_from:g} s")
    timed = t_from is not None or t_to is not None
    lo = -math.inf if t_from is None else float(t_from)
    hi = math.inf if t_to is None else float(t_to)
    source, end, count, started, done = "", 0, 0, False, False
    waiting: list[tuple[int, str]] = []  # rows of unreadable time after the window's start: kept if a row follows
    clock = [math.inf, -math.inf]
    for lines in blocks:
        source, end = lines.source, lines.numbers[-1]
        pairs = list(zip(lines.numbers, lines.text))
        if rows is not None:
            pairs = [(num, text) for num, text in pairs if first <= num <= last]
            done = lines.numbers[-1] >= last
        elif timed:
            times = _times(lines, cmap.t)
            finite = times[np.isfinite(times)]
            if finite.size:
                clock = [min(clock[0], float(finite.min())), max(clock[1], float(finite.max()))]
            kept = []
            for (num, text), t in zip(pairs, times):
                if not started:
                    started = bool(lo <= t <= hi)
                    if started:
                        kept.append((num, text))
                elif not np.isfinite(t):
                    waiting.append((num, text))
                elif t <= hi:
                    kept += waiting + [(num, text)]
                    waiting = []
                else:
                    done = True
                    break
            pairs = kept
        if pairs:
            part = LogLines(source, [num for num, _ in pairs], [text for _, text in pairs])
            values = _parse_fast(part, cmap)
            if period is not None:
                values = np.column_stack([values, (count + np.arange(values.shape[0])) * float(period)])
            count += values.shape[0]
            yield values, part.numbers
        if done:
            break
    if rows is not None and last > end and end:
        raise RecordingError(f"{source}: rows {first}:{last}: the file ends at line {end}")
    if rows is not None and not count and end:
        raise RecordingError(f"{source}: rows {first}:{last} hold no data row")
    if timed and not count and end:
        span = f"{clock[0]:g} to {clock[1]:g} s" if clock[0] <= clock[1] else "no readable time"
        raise RecordingError(f"{source}: no row between {lo:g} and {hi:g} s (the log's clock runs {span})")


def _log_blocks(p: Path, robot: rx90sym.Robot, columns: str | Sequence[str] | None, header: bool,
                rows: tuple[int, int] | None, t_from: float | None, t_to: float | None, gains: Any,
                convention: str | None, period: float | None, block: int
                ) -> tuple[ColumnMap, str, DriveGains | None, Iterator[tuple[np.ndarray, list[int]]]]:
    """(the column map of the rows yielded, the convention, the drive gains, the parsed blocks of the window)."""
    block = check_block(block, 1, "lines")
    if period is not None:
        check_period(period)
        if t_from is not None or t_to is not None:
            raise ValueError("t_from/t_to (--from/--to) select by the log's clock; a log read with a sampling period "
                             "(--period) has none: select lines with rows= (--rows FIRST:LAST)")
    spaced = False
    if columns is None:
        cells, spaced = header_cells(p)
        columns = rtde_columns(cells, robot) if header else None
        if columns is None:
            raise ValueError(f"{p.name}: give the column map (columns=, --columns): the first line is not a "
                             f"header this reader knows (UR RTDE: timestamp, actual_q_0..actual_q_{robot.n - 1})")
        refusal = rtde_refusal(cells, robot)
        if refusal:
            raise ValueError(f"{p.name}: {refusal}")
    cmap, conv, drive = log_options(p, robot, columns, rows, t_from, t_to, gains, convention, time=period is None)
    blocks = _selected(_line_blocks(p, header, len(cmap.names), block, spaced), cmap, rows, t_from, t_to, period)
    if period is not None:  # the clock of the period, appended last: column numbers stay the file's
        cmap = parse_columns([*cmap.names, "t"], robot)
    return cmap, conv, drive, blocks


def read_log(path: str | os.PathLike[str], robot: rx90sym.Robot, columns: str | Sequence[str] | None,
             header: bool = False, rows: tuple[int, int] | None = None, t_from: float | None = None,
             t_to: float | None = None, resample: float | None = None, gains: DriveGains | str | None = None,
             convention: str | None = None, max_gap: float = DEFAULT_MAX_GAP, segments: bool = True,
             period: float | None = None, block: int = DEFAULT_LOG_BLOCK,
             torque_signs: str | Sequence[float] | None = None) -> Recording:
    """Read a controller log (a CSV whose columns ``columns`` names, :mod:`identify.io.logs`) as a recording.

    Args:
        path: the log, comma separated; lines starting with ``#`` are skipped.
        robot: the robot the log belongs to.
        columns: the column map (a string or a list of names); None for a log whose header names its
            columns (UR's RTDE recorder: :func:`identify.io.columns.rtde_columns`; cells separated by
            commas or blanks).
        header: the first non-comment line is a header (skipped; its cell count is checked).
        rows: ``(FIRST, LAST)`` 1-based line numbers of the file, inclusive.
        t_from, t_to: window in seconds of the log's clock (not with ``rows``).
        resample: rate in Hz of a uniform grid to put every signal on; required when the time
            steps are irregular (more than 1 % from the median step) or packets were lost.
        gains: drive gains (a :class:`DriveGains`, a comma list in N·m/A joint side, or a JSON
            file) turning the currents into joint torques; without them ``tau`` stays None.
        convention: angles of the log, ``"controller"`` (default: what a controller logs) or
            ``"model"`` (Khalil); converted once to model angles.
        max_gap: longest gap (s) of lost packets bridged by interpolation (default 50 ms,
            :mod:`identify.io.gaps`); a longer one starts a new segment.
        segments: False refuses a gap longer than ``max_gap`` instead of splitting the log.
        period: sampling period, s, of a log without time column (the column map names no ``t``):
            sample k of the rows read is at ``t = k * period`` (t = 0 at the first row read, the
            first of ``rows``); every row is a sample, a row equal to the previous one included
            (no stale rows: the clock is the period's).
        block: lines read and checked at a time (the checks' median step is each block's:
            :mod:`identify.io.log_rules`).
        torque_signs: one sign per joint, 1 (as logged) or -1: the torque (and current) columns of the
            joints given -1 are negated (identify.io.torque_signs; a text "1,-1,..." or a sequence).

    Returns:
        A recording in model angles, with ``segment`` and ``measured`` (when resampled: bridged
        samples False); ``meta["log"]`` says what was done: ``lines`` (first, last line read),
        ``rows`` (count, stale rows included), ``stale_rows`` (dropped), ``stale_lines`` (the first
        few), ``rate_hz`` (1 / mean step, the gaps of lost packets left out), ``median_step_s``
        (:func:`identify.io.steps.step_figures`), ``largest_gap_s`` and ``largest_gap_lines``,
        ``irregular_steps``, ``gaps`` (:meth:`LogGaps.summary`), ``bridged_samples``,
        ``resampled_hz`` (or None), ``samples``, ``gains``, ``convention``, ``t0_s`` (the log's
        clock at the first sample: the recording starts at 0 s), ``columns``, ``period_s``,
        ``torque_signs`` (or None).

    Raises:
        RecordingError: corrupt rows, irregular time without ``resample``, a gap over ``max_gap``
            with ``segments=False``, a time column that counts samples (read it with ``period``)
            (message names file and lines).
        ValueError: a bad column map, window or gains.
    """
    p = Path(path)
    signs = parse_torque_signs(torque_signs, robot)
    cmap, conv, drive, blocks = _log_blocks(p, robot, columns, header, rows, t_from, t_to, gains, convention,
                                            period, block)
    report = BlockReport()
    resample = retimed_rate(resample, period, cmap)
    rec = collected(log_parts(blocks, cmap, robot, conv, p.name, report, resample, max_gap, segments, drive,
                              stale=period is None, signs=signs, period=period), resample is not None)
    from dataclasses import replace

    return replace(rec, meta={**rec.meta, "log": _report(report, cmap, max_gap, resample, drive, conv, period,
                                                         signs)})


def convert_log(path: str | os.PathLike[str], robot: rx90sym.Robot, columns: str | Sequence[str] | None,
                out: str | os.PathLike[str], header: bool = False, rows: tuple[int, int] | None = None,
                t_from: float | None = None, t_to: float | None = None, resample: float | None = None,
                gains: Any = None, convention: str | None = None, block: int = DEFAULT_LOG_BLOCK,
                max_gap: float = DEFAULT_MAX_GAP, segments: bool = True,
                period: float | None = None, torque_signs: str | Sequence[float] | None = None) -> dict[str, Any]:
    """Convert the log ``path`` (the arguments of :func:`read_log`) to the recording file ``out`` (CSV,
    controller angles), ``block`` lines at a time. Returns the ``meta["log"]`` report."""
    p = Path(path)
    if Path(out).suffix.lower() != ".csv":
        raise RecordingError(f"{p.name}: a log converted block by block is written as CSV")
    signs = parse_torque_signs(torque_signs, robot)
    cmap, conv, drive, blocks = _log_blocks(p, robot, columns, header, rows, t_from, t_to, gains, convention,
                                            period, block)
    report = BlockReport()
    resample = retimed_rate(resample, period, cmap)
    parts = log_parts(blocks, cmap, robot, conv, p.name, report, resample, max_gap, segments, drive,
                      stale=period is None, signs=signs, period=period)

    def write(fh: IO) -> None:
        fields_at = None
        for rec, segment in parts:
            names, table = _columns(rec, robot, "controller", segment, resample is not None)
            if fields_at is None:
                fh.write(f"# convention: controller\n# robot: {robot.name}\n")
                fields_at = {}  # the fields are known at the end: blank, filled in then
                for key, width in _FIELD_WIDTHS.items():
                    fh.write(f"# {key}: ")
                    fields_at[key] = fh.tell()
                    fh.write(" " * width + "\n")
                fh.write(",".join(names) + "\n")
            _write_rows(fh, table)
        if fields_at is not None:  # the fields of identify.write_recording, known now
            values = file_fields(report.result(max_gap))
            for key, at in fields_at.items():
                fh.seek(at)
                fh.write(f"{values.get(key, ''):<{_FIELD_WIDTHS[key]}}")

    atomic_write(out, write, binary=False)
    return {**_report(report, cmap, max_gap, resample, drive, conv, period, signs), "blocks_of_lines": block}


def _report(report: BlockReport, cmap: ColumnMap, max_gap: float, resample: float | None, drive: DriveGains | None,
            conv: str, period: float | None, signs: tuple[float, ...] | None = None) -> dict[str, Any]:
    """``meta["log"]``: :func:`identify.io.log_rules.log_report` with the column map read (the clock of
    ``period`` left out) and ``period_s``."""
    log = log_report(report, max_gap, resample, drive, conv, signs)
    log["columns"] = ",".join(cmap.names[:-1] if period is not None else cmap.names)
    if period is not None:
        log["period_s"] = float(period)
    return log


#: Characters kept in the header for the fields of identify.io.log_fields (filled in at the end): a
#: count, a count with SPLITS_LISTED gaps of two line numbers and a duration each, a time [s].
_FIELD_WIDTHS = {"stale_rows": 20, "split_gaps": 20 + SPLITS_LISTED * 64, "t0_s": 32}


def _columns(rec: Recording, robot: rx90sym.Robot, convention: str, segment: int,
             resampled: bool) -> tuple[list[str], np.ndarray]:
    """Header names and the table of :func:`identify.write_recording` for one part of a block (in the
    segment ``segment``; ``resampled``: with the ``measured`` column)."""
    n = robot.n
    q = np.asarray(robot.to_controller(rec.q), dtype=float) if convention == "controller" else rec.q
    names, parts = ["t", *[f"q{j + 1}" for j in range(n)]], [rec.t[:, None], q]
    for values, prefix in ((rec.tau, "tau"), (rec.dq, "dq"), (rec.current, "i")):
        if values is not None:
            names += [f"{prefix}{j + 1}" for j in range(n)]
            parts.append(values)
    names += [f"x:{k}" for k in rec.aux]
    parts += [v[:, None] for v in rec.aux.values()]
    if resampled:  # the layout of identify.write_recording, always written (the blocks to come may need it)
        names.append("measured")
        parts.append(rec.measured_mask[:, None].astype(float))
    names.append("segment")
    parts.append(np.full((rec.n_samples, 1), float(segment)))
    return names, np.hstack(parts)


def _write_rows(fh: IO, table: np.ndarray) -> None:
    import pyarrow as pa
    from pyarrow import csv

    # Shortest round-trip decimal form of each double (like repr): exact on reading back.
    arrow = pa.table({f"c{k}": table[:, k] for k in range(table.shape[1])})
    out = io.BytesIO()
    csv.write_csv(arrow, out, csv.WriteOptions(include_header=False))
    fh.write(out.getvalue().decode())


