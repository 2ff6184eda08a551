"""A controller log of any length converted to a recording file block by block (``rx90 convert`` on long logs).

:func:`convert_log` does what :func:`identify.read_log` then :func:`identify.write_recording` do,
holding one block of lines at a time: lines are read and numbered in Python (comments, header),
each block's numbers parsed by pyarrow's CSV parser (C++, multithreaded; a block it refuses is
parsed again by the whole-log parser, whose message names the bad lines), stale rows dropped (each
block's first row compared with the previous block's last), checked with the whole-log checks
(each block after the previous block's last kept row, so steps, jumps and gaps across blocks are
checked too), gaps bridged or split into segments (:mod:`identify.io.gaps`; a new segment gets
its own grid), resampled when asked (see :class:`_Resampler`), and appended to the output through
the atomic writer: an error leaves no file behind. The output always has a ``segment`` column
(and ``measured`` when resampled): the blocks to come may need them; the stale-row count and the
gaps that split the log go in header fields filled in at the end (:mod:`identify.io.log_fields`).

Differences from the whole-log reader, by construction: the median time step of the checks
(irregular steps, gaps, a gap's ``periods``) is each block's, so a step is a lost packet when it is
longer than 1.5 of its block's median step (the same steps as on the whole log unless the clock
drifts by a third of a period between blocks); the report's median step, steps off by more than
1 % and rate are the whole log's, as the whole-log reader prints them
(:func:`identify.io.steps.step_figures` on every step); the recorded-velocity check compares each block's
RMS, and the units check (:func:`identify.io.units.check_units`: degrees, swapped q/qd groups)
counts the rows of the block where it refuses (the same message, the block's counts); with
``t_from``/``t_to`` every row is parsed, so a corrupt row outside the window stops the
conversion.
"""
from __future__ import annotations

import io
import os
from pathlib import Path
from typing import IO, Any, Iterator

import numpy as np

import rx90sym
from rx90sym.files import atomic_write
from rx90sym.recording import Recording, RecordingError

from identify.io.blocks import DEFAULT_LOG_BLOCK
from identify.io.columns import ColumnMap
from identify.io.gains import apply_gains
from identify.io.log_rows import ABSURD, LogLines, check_header, parse_rows
from identify.io.logs import (LISTED_ROWS, check_increasing, check_positions, check_velocities, gains_label,
                              irregular_refusal, log_options, refuse_splits)
from identify.io.log_block_report import BlockReport
from identify.io.log_fields import SPLITS_LISTED, format_splits
from identify.io.units import check_units
from identify.io.gaps import (DEFAULT_MAX_GAP, MIN_SEGMENT_ROWS, LogGaps, all_segments_short, find_gaps,
                                  stale_rows)
from identify.io.resampling import interpolate

__all__ = ["DEFAULT_LOG_BLOCK", "convert_log"]

#: Samples beyond a resampled block's end: the not-a-knot spline's dependence on far samples decays
#: by ≈ 0.27 per sample, so 40 samples change an interpolated value by < 1e-20 of the signal.
SPLINE_MARGIN = 40


def _line_blocks(path: Path, header: bool, n_cols: int, size: int) -> Iterator[LogLines]:
    """Data lines (number, text) in blocks of ``size``; comments and trailing blank lines dropped."""
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
    try:
        table = csv.read_csv(io.BytesIO("\n".join(lines.text).encode()),
                             read_options=csv.ReadOptions(column_names=names),
                             convert_options=csv.ConvertOptions(column_types={c: pa.float64() for c in names}))
        values = np.column_stack([table.column(c).to_numpy(zero_copy_only=False) for c in names])
    except (pa.ArrowInvalid, ValueError):
        return parse_rows(lines, 0, len(lines.text), cmap)
    used = [c for c, name in enumerate(cmap.names) if name != "_" and c != cmap.t]
    if (values.shape[0] != len(lines.text) or not np.all(np.isfinite(values[:, [cmap.t] + used]))
            or np.any(np.abs(values[:, used]) > ABSURD)):
        return parse_rows(lines, 0, len(lines.text), cmap)
    return values


class _Resampler:
    """The rule of :func:`identify.resample` (grid ``t0 + k/rate``, splines) on a stream of blocks of one
    segment (a new segment takes a new resampler: its grid starts at its first sample).

    Rows are buffered until SPLINE_MARGIN samples lie beyond the grid points emitted, so each
    emitted point sees the samples around it as the whole-log spline does.
    """

    def __init__(self, rate: float) -> None:
        self.rate, self.k, self.t0 = float(rate), 0, None
        self.buffer: Recording | None = None

    def feed(self, rec: Recording | None, last: bool) -> Recording | None:
        """The grid points ``rec`` completes (``last``: the segment ends with it; ``rec`` None: flush)."""
        buf = rec if self.buffer is None else (self.buffer if rec is None else _joined(self.buffer, rec))
        if buf is None or (buf.t.size < 2 and not last):  # a segment's first row alone: wait for the next
            self.buffer = buf
            return None
        if self.t0 is None:
            self.t0 = float(buf.t[0])
        limit = float(buf.t[-1]) if last else float(buf.t[max(0, buf.t.size - 1 - SPLINE_MARGIN)])
        count = int(np.floor((limit - self.t0) * self.rate * (1.0 + 1e-12))) + 1
        grid = self.t0 + np.arange(self.k, count) / self.rate
        if last and grid.size:
            grid[-1] = min(grid[-1], limit)  # never beyond the last sample through rounding
        self.k = max(self.k, count)
        self.buffer = None
        if not last:  # keep what the next points need: SPLINE_MARGIN samples before them
            start = max(0, int(np.searchsorted(buf.t, limit)) - 2 * SPLINE_MARGIN)
            self.buffer = buf.select(slice(start, None))
        return interpolate(buf, grid) if grid.size else None


def _joined(a: Recording, b: Recording) -> Recording:
    def cat(x: np.ndarray | None, y: np.ndarray | None) -> np.ndarray | None:
        return None if x is None else np.concatenate([x, y])

    return Recording(t=np.concatenate([a.t, b.t]), q=np.concatenate([a.q, b.q]), tau=cat(a.tau, b.tau),
                     dq=cat(a.dq, b.dq), source=a.source, robot=a.robot, current=cat(a.current, b.current),
                     aux={k: np.concatenate([v, b.aux[k]]) for k, v in a.aux.items()})


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


class _LogStream:
    """The rules of :func:`identify.io.logs.rows_to_recording` on consecutive blocks of rows: stale rows
    (each block's first row compared with the previous block's last), checks, gaps and segments (each
    block after the previous block's last kept row), the grid of each segment. Yields the parts to
    write, each with its segment number."""

    def __init__(self, cmap: ColumnMap, robot: rx90sym.Robot, conv: str, source: str, resample: float | None,
                 max_gap: float, segments: bool, report: BlockReport) -> None:
        self.cmap, self.robot, self.conv, self.source = cmap, robot, conv, source
        self.resample, self.max_gap, self.segments, self.report = resample, max_gap, segments, report
        self.used = [c for c, name in enumerate(cmap.names) if name != "_"]
        self.last_raw: np.ndarray | None = None
        self.last_kept: tuple[np.ndarray, list[int]] | None = None
        self.segment, self.out = 0, -1  # the segment found, and its number in the output
        self.keeping, self.resampler = False, None  # the segment is long enough to keep; its grid
        self.held: list[Recording] = []  # its first rows, until it is
        self.held_rows, self.held_lines = 0, None
        self.t0: float | None = None  # the log's clock at its first sample [s]

    def block(self, values: np.ndarray, numbers: list[int], last: bool) -> Iterator[tuple[Recording, int]]:
        report = self.report
        report.rows += values.shape[0]
        both = values if self.last_raw is None else np.vstack([self.last_raw, values])
        stale = stale_rows(both, self.cmap.t, self.used)[both.shape[0] - values.shape[0]:]
        self.last_raw = values[-1:]
        report.stale += int(stale.sum())
        report.stale_lines += [numbers[k] for k in np.flatnonzero(stale)[:max(0, LISTED_ROWS - len(report.stale_lines))]]
        values, numbers = values[~stale], [n for n, s in zip(numbers, stale) if not s]
        new = values.shape[0]
        if new:  # 0 s at the first sample, as identify.io.logs.rows_to_recording
            if self.t0 is None:
                self.t0 = report.t0_s = float(values[0, self.cmap.t])
            values = values.copy()
            values[:, self.cmap.t] -= self.t0
            if self.last_kept is not None:
                values, numbers = np.vstack([self.last_kept[0], values]), self.last_kept[1] + numbers
            yield from self._kept(values, numbers, new)
        if last:
            yield from self._end(final=True)

    def _kept(self, values: np.ndarray, numbers: list[int], new: int) -> Iterator[tuple[Recording, int]]:
        t = values[:, self.cmap.t]
        if t.size >= 2:
            check_increasing(t, numbers, self.source)
        found = (find_gaps(t, numbers, self.max_gap) if t.size >= 2
                 else LogGaps((), np.zeros(t.size, np.int64), self.max_gap))
        if not self.segments:
            refuse_splits(found, self.source)
        rec = _checked(values, numbers, self.cmap, self.robot, self.conv, self.source)
        if self.resample is None and t.size >= 2:
            refusal = irregular_refusal(t, numbers, self.source, found)
            if refusal:
                raise RecordingError(refusal)
        self.report.add(t, numbers, found)
        self.last_kept = (values[-1:], numbers[-1:])
        segment = found.segment[t.size - new:] + self.segment  # the carried row is in self.segment
        rec = rec.select(slice(t.size - new, None))
        lines = np.asarray(numbers[t.size - new:])
        for number in np.unique(segment):
            if number != self.segment:
                yield from self._end(final=False)
                self.segment = int(number)
            yield from self._add(rec.select(segment == number), lines[segment == number])

    def _add(self, part: Recording, lines: np.ndarray) -> Iterator[tuple[Recording, int]]:
        """A part of the current segment: held until the segment has MIN_SEGMENT_ROWS rows (a shorter
        one is dropped, as by the whole-log reader), then resampled and written."""
        self.held.append(part)
        self.held_rows += part.n_samples
        self.held_lines = (self.held_lines[0] if self.held_lines else int(lines[0]), int(lines[-1]))
        if not self.keeping and self.held_rows >= MIN_SEGMENT_ROWS:
            self._keep()
        if self.keeping:
            yield from self._emit()

    def _keep(self) -> None:
        self.keeping = True
        self.out += 1  # the segment's number in the output: a dropped one leaves no hole
        self.resampler = _Resampler(self.resample) if self.resample else None

    def _emit(self) -> Iterator[tuple[Recording, int]]:
        parts, self.held = self.held, []
        for part in parts:
            part = self.resampler.feed(part, False) if self.resampler is not None else part
            if part is not None:
                yield part, self.out

    def _end(self, final: bool) -> Iterator[tuple[Recording, int]]:
        """The current segment ends: its last grid points, or it is dropped when too short (kept when it
        is the log's only segment; every segment too short is an error)."""
        if not self.keeping and self.held:
            if final and self.out < 0 and not self.report.dropped:  # the only segment: kept whatever its length
                self._keep()
                yield from self._emit()
            else:
                self.report.dropped.append((*self.held_lines, self.held_rows))
                if final and self.out < 0:
                    raise all_segments_short(self.source, self.max_gap, self.report.dropped[0][:2])
        if self.keeping and self.resampler is not None:
            part = self.resampler.feed(None, True)
            if part is not None:
                yield part, self.out
        self.keeping, self.resampler, self.held, self.held_rows, self.held_lines = False, None, [], 0, None


def convert_log(path: str | os.PathLike[str], robot: rx90sym.Robot, columns: str, out: str | os.PathLike[str],
                header: bool = False, rows: tuple[int, int] | None = None, t_from: float | None = None,
                t_to: float | None = None, resample: float | None = None, gains: Any = None,
                convention: str | None = None, block: int = DEFAULT_LOG_BLOCK, max_gap: float = DEFAULT_MAX_GAP,
                segments: bool = True) -> dict[str, Any]:
    """Convert the log ``path`` (a column map ``columns``, as :func:`identify.read_log`) to the recording
    file ``out`` (CSV, controller angles), ``block`` lines at a time. Stale rows, lost packets and
    segments (``max_gap`` [s], ``segments``) as :func:`identify.read_log`. Returns the ``meta["log"]`` report.
    """
    p = Path(path)
    if Path(out).suffix.lower() != ".csv":
        raise RecordingError(f"{p.name}: a log converted block by block is written as CSV")
    if not (np.isfinite(max_gap) and max_gap > 0):
        raise ValueError(f"max_gap must be a positive time in s, got {max_gap!r}")
    cmap, conv, drive = log_options(p, robot, columns, rows, t_from, t_to, gains, convention)
    report = BlockReport()
    stream = _LogStream(cmap, robot, conv, p.name, resample, max_gap, segments, report)

    def write(fh: IO) -> None:
        fields_at = None
        blocks = _selected(_line_blocks(p, header, len(cmap.names), block), cmap, rows, t_from, t_to)
        pending = next(blocks, None)
        if pending is None:
            raise RecordingError(f"{p.name}: no data rows" + (" in the window asked" if (rows or t_from or t_to) else ""))
        while pending is not None:
            values, numbers = pending
            pending = next(blocks, None)
            for rec, segment in stream.block(values, numbers, pending is None):
                if drive is not None:
                    rec = apply_gains(rec, drive, robot)
                names, table = _columns(rec, robot, "controller", segment, resample is not None)
                if fields_at is None:
                    fh.write(f"# convention: controller\n# robot: {robot.name}\n")
                    fields_at = {}  # the fields are known at the end: blank, filled in then
                    for key, width in _FIELD_WIDTHS.items():
                        fh.write(f"# {key}: ")
                        fields_at[key] = fh.tell()
                        fh.write(" " * width + "\n")
                    fh.write(",".join(names) + "\n")
                report.samples += table.shape[0]
                report.bridged += int(np.sum(~rec.measured_mask))
                _write_rows(fh, table)
        if fields_at is not None:
            splits = report.result(max_gap)["gaps"]
            values = {"stale_rows": str(report.stale), "split_gaps": format_splits(splits["splits"], splits["splits_total"])}
            for key, at in fields_at.items():
                fh.seek(at)
                fh.write(f"{values[key]:<{_FIELD_WIDTHS[key]}}")

    atomic_write(out, write, binary=False)
    if report.rows - report.stale < 2:
        raise RecordingError(f"{p.name}: line {report.first_line}: a log needs at least 2 rows")
    return {**report.result(max_gap), "resampled_hz": float(resample) if resample else None,
            "gains": None if drive is None else gains_label(drive), "convention": conv, "blocks_of_lines": block}


#: Characters kept in the header for the fields of identify.io.log_fields (filled in at the end): a
#: count, and a count with SPLITS_LISTED gaps of two line numbers and a duration each.
_FIELD_WIDTHS = {"stale_rows": 20, "split_gaps": 20 + SPLITS_LISTED * 64}


def _selected(blocks: Iterator[LogLines], cmap: ColumnMap, rows: tuple[int, int] | None, t_from: float | None,
              t_to: float | None) -> Iterator[tuple[np.ndarray, list[int]]]:
    """Parsed blocks restricted to the lines ``rows`` or the times [t_from, t_to] (empty blocks skipped)."""
    for lines in blocks:
        if rows is not None:
            keep = [k for k, num in enumerate(lines.numbers) if rows[0] <= num <= rows[1]]
            if not keep:
                if lines.numbers[0] > rows[1]:
                    return
                continue
            lines = LogLines(lines.source, [lines.numbers[k] for k in keep], [lines.text[k] for k in keep])
        values = _parse_fast(lines, cmap)
        numbers = list(lines.numbers)
        if t_from is not None or t_to is not None:
            t = values[:, cmap.t]
            inside = (t >= (-np.inf if t_from is None else t_from)) & (t <= (np.inf if t_to is None else t_to))
            values, numbers = values[inside], [n for n, ok in zip(numbers, inside) if ok]
            if t_to is not None and t.size and t[-1] > t_to and not inside.any():
                return
        if values.shape[0]:
            yield values, numbers


def _checked(values: np.ndarray, numbers: list[int], cmap: ColumnMap, robot: rx90sym.Robot, conv: str,
             source: str) -> Recording:
    """One block through the checks of :func:`identify.read_log`, as a recording in model angles."""
    t = values[:, cmap.t]
    q_file = values[:, list(cmap.q)]
    q = np.asarray(robot.to_model(q_file), dtype=float) if conv == "controller" else q_file
    dq = values[:, list(cmap.qd)] if cmap.qd else None
    # Degrees and swapped q/qd groups named as such, before they read as corrupt rows (as read_log).
    check_units(t, q_file, dq, robot, source, numbers, to_model=conv == "controller", ranges=False)
    check_positions(q, t, numbers, cmap, robot, source)
    if t.size >= 3:
        check_velocities(dq, q, t, np.ptp(q, axis=0), numbers, cmap, source)

    def take(cols: tuple[int, ...]) -> np.ndarray | None:
        return values[:, list(cols)] if cols else None

    return Recording(t=t, q=q, tau=take(cmap.tau), dq=dq, source=source, robot=robot.name, current=take(cmap.i),
                     aux={name: values[:, col] for name, col in cmap.aux})
