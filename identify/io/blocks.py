"""Recordings read in blocks: a CSV recording of any length streamed by pyarrow, or one in memory.

A :class:`BlockSource` gives two kinds of pieces, both :class:`~identify.io.recordings.Recording`
objects in model angles (joint torques through the drive gains when given):

* :meth:`BlockSource.scan` — consecutive blocks, each checked like a whole file (finite values,
  increasing time, radians, jumps; the messages name the file's row), overlapping the previous
  block by one sample so that steps between blocks are checked too;
* :meth:`BlockSource.windows` — overlapping spans in increasing order (the blocks of
  :func:`identify.signal.blocks.motion_windows`), for the block-wise pipeline.

Only the rows of the current block (and its margins) are held: pyarrow's streaming CSV reader
parses the file in record batches (multithreaded, C++), a rolling buffer keeps what the next span
needs. A recording may be given in memory too (:class:`MemorySource`), e.g. a twin simulation.
"""
from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any, Iterable, Iterator

import numpy as np

import rx90sym
from rx90sym.recording import Recording, RecordingError

from identify.io.arrays import _check_layout, _resolve_convention, _to_model
from identify.io.checks import _check_robot_name, _default_labels, _validate, _warn_no_robot
from identify.io.defaults import DEFAULT_BLOCK, DEFAULT_LOG_BLOCK
from identify.io.csv_tables import _column_index, _parse_cells, _semicolon_hint, _Table
from identify.io.gains import DriveGains, apply_gains
from identify.io.log_fields import read_fields

__all__ = ["BlockSource", "CsvSource", "MemorySource", "block_source", "check_block", "CSV_BATCH_BYTES",
           "DEFAULT_BLOCK", "DEFAULT_LOG_BLOCK"]

#: Bytes of CSV text pyarrow parses per record batch (≈ 45,000 rows of a 7-joint recording).
CSV_BATCH_BYTES = 8 << 20


def check_block(block: Any, least: int = 1000, unit: str = "samples") -> int:
    """``block`` as a whole number of ``unit`` of at least ``least``, or a ValueError saying so."""
    if isinstance(block, bool) or not isinstance(block, (int, np.integer, float)) or int(block) != block \
            or block < least:
        raise ValueError(f"block must be a whole number of {unit} >= {least}, got {block!r}")
    return int(block)


def _shift_rows(exc: RecordingError, offset: int, first_line: int | None = None) -> RecordingError:
    """The same message with its 1-based row numbers counted from the file's first data row, and the
    line of the file beside each (``first_line``: the line of data row 1; None: a recording in memory)."""
    def where(m: re.Match) -> str:
        row = int(m.group(1)) + offset
        return f"row {row}" + ("" if first_line is None else f" (line {row + first_line - 1})")

    return RecordingError(re.sub(r"row (\d+)", where, str(exc)))


class BlockSource:
    """Samples of one recording, served block by block (subclasses say where they come from)."""

    source: str = "<memory>"
    first_line: int | None = None  # the file's line of data row 1 (None: no file)
    n_samples: int | None = None  # known after a scan
    log: dict | None = None  # what the file keeps of its log (identify.io.log_fields; None: nothing)
    holds_current: bool = False  # motor currents among its columns (drive gains turn them into torques)

    def __init__(self, robot: rx90sym.Robot, gains: DriveGains | None = None) -> None:
        self.robot, self.gains = robot, gains

    def _rows(self) -> Iterator[np.ndarray]:  # (m, k) raw columns, consecutive
        raise NotImplementedError

    def _record(self, table: np.ndarray, first: bool = False) -> Recording:
        """The rows ``table`` as a recording; its ``segment`` counted from the rows' first segment, whose
        number in the whole recording is ``meta["segment0"]`` (``first``: the rows start the recording)."""
        raise NotImplementedError

    def _finish(self, rec: Recording) -> Recording:
        if self.gains is not None and rec.current is not None:
            return apply_gains(rec, self.gains, self.robot)
        return rec

    def scan(self, block: int) -> Iterator[Recording]:
        """Consecutive checked blocks of ``block`` new samples, each after the previous block's last
        samples (as many as the robot has parameters; ``Recording.meta["new_from"]`` says where the
        new ones start)."""
        carry: np.ndarray | None = None
        start = 0  # index in the file of the first row of ``pending``
        pending: list[np.ndarray] = []
        held = 0
        keep = len(self.robot.parameter_names)  # carried rows: the last block is long enough to check
        for rows in self._rows():
            pending.append(rows)
            held += rows.shape[0]
            while held >= block:
                table = np.concatenate(pending)
                yield self._checked(table[:block], carry, start)
                carry, rest = table[max(0, block - keep):block], table[block:]
                start += block
                pending, held = [rest], rest.shape[0]
        if held or carry is None:
            table = np.concatenate(pending) if pending else np.empty((0, 0))
            if table.shape[0]:
                yield self._checked(table, carry, start)
            start += held
        self.n_samples = start

    def _checked(self, table: np.ndarray, carry: np.ndarray | None, start: int) -> Recording:
        full = table if carry is None else np.concatenate([carry, table])
        offset = start - (0 if carry is None else carry.shape[0])
        labels = _default_labels(self.source, self.robot.n)
        try:
            rec = self._record(full, first=carry is None)
            _validate(rec.t, rec.q, rec.tau, rec.dq, self.robot, labels, self.source, rec.current, rec.aux,
                      rec.segment)
        except RecordingError as exc:
            raise _shift_rows(exc, offset, self.first_line) from None
        rec.meta["new_from"] = start - offset
        return self._finish(rec)

    def thinned(self, block: int, every: int) -> Recording:
        """Every ``every``-th sample and the last one, read block by block (checked as by :meth:`scan`): a
        long recording's extent and motion for figures, in bounded memory (no ``measured``/``segment``)."""
        parts, at, last = [], 0, None
        for rec in self.scan(block):
            new = int(rec.meta.get("new_from", 0))
            parts.append(rec.select(np.arange(new + (-at) % every, rec.n_samples, every)))
            at += rec.n_samples - new
            last = rec.select(slice(rec.n_samples - 1, None))
        if (at - 1) % every:
            parts.append(last)

        def cat(name: str) -> np.ndarray | None:
            return None if getattr(parts[0], name) is None else np.concatenate([getattr(r, name) for r in parts])

        return Recording(t=cat("t"), q=cat("q"), tau=cat("tau"), dq=cat("dq"), source=self.source,
                         robot=self.robot.name, current=cat("current"))

    def windows(self, spans: Iterable[tuple[int, int]]) -> Iterator[Recording]:
        """The samples [r0, r1) of each span, spans in increasing order of r0 and r1."""
        buffer: np.ndarray | None = None
        first = 0  # file index of buffer[0]
        rows = self._rows()
        for r0, r1 in spans:
            while buffer is None or first + buffer.shape[0] < r1:
                more = next(rows, None)
                if more is None:
                    break
                buffer = more if buffer is None else np.concatenate([buffer, more])
                if first + buffer.shape[0] <= r0:  # rows before the span: not kept
                    first, buffer = first + buffer.shape[0], None
            if buffer is None:
                raise ValueError(f"{self.source}: samples {r0}..{r1} asked beyond the end of the file")
            if r0 > first:
                buffer, first = buffer[r0 - first:], r0
            yield self._finish(self._record(buffer[:r1 - first]))


class MemorySource(BlockSource):
    """A recording already in memory (already checked and in model angles)."""

    def __init__(self, rec: Recording, robot: rx90sym.Robot, gains: DriveGains | None = None) -> None:
        super().__init__(robot, gains)
        self.rec, self.source, self.n_samples = rec, rec.source, rec.n_samples
        self.holds_current = rec.current is not None
        self.log = rec.meta.get("log")

    def scan(self, block: int) -> Iterator[Recording]:
        keep = len(self.robot.parameter_names)
        for start in range(0, self.rec.n_samples, block):
            rec = self.rec.select(slice(max(0, start - keep), start + block))
            rec.meta["new_from"] = start - max(0, start - keep)
            rec.meta["segment0"] = 0 if self.rec.segment is None else int(self.rec.segment[max(0, start - keep)])
            yield self._finish(rec)

    def windows(self, spans: Iterable[tuple[int, int]]) -> Iterator[Recording]:
        for r0, r1 in spans:
            yield self._finish(self.rec.select(slice(r0, r1)))


class CsvSource(BlockSource):
    """A CSV recording (the format of :func:`identify.write_recording`) streamed by pyarrow."""

    def __init__(self, path: str | os.PathLike[str], robot: rx90sym.Robot, convention: str | None = None,
                 gains: DriveGains | None = None, batch_bytes: int = CSV_BATCH_BYTES) -> None:
        super().__init__(robot, gains)
        self.path, self.source, self.batch_bytes = Path(path), Path(path).name, int(batch_bytes)
        meta, columns, self.skip = self._header()
        self.first_line = self.skip + 2  # the header is line skip + 1
        _check_robot_name(meta.get("robot"), robot, self.source)
        n = robot.n
        self.names = {p: [f"{p}{j + 1}" for j in range(n)] for p in ("q", "tau", "dq", "i")}
        table = _Table(self.source, meta, columns, np.empty((0, len(columns))), self.skip + 1)
        self.index = _column_index(table, ["t", *self.names["q"]],
                                   [self.names["tau"], self.names["dq"], self.names["i"], ["measured"], ["segment"]],
                                   aux=True)
        self.holds_current = "i1" in self.index
        if "tau1" not in self.index and not self.holds_current:
            raise RecordingError(f"{self.source}: column 'tau1' is missing (joint torques tau1..tau{n}, or "
                                 f"motor currents i1..i{n})")
        _warn_no_robot(meta.get("robot"), robot, self.source)
        self.log = read_fields(meta, self.source)
        self.convention = _resolve_convention(convention, meta.get("convention"), self.source)
        self.columns = columns

    def _header(self) -> tuple[dict[str, str], tuple[str, ...], int]:
        meta: dict[str, str] = {}
        with open(self.path, encoding="utf-8-sig") as fh:
            for skip, line in enumerate(fh):
                if line.strip() and not line.lstrip().startswith("#"):
                    columns = tuple(c.strip() for c in line.split(","))
                    if len(columns) == 1 and _semicolon_hint(line):
                        raise RecordingError(f"{self.source}: line {skip + 1}: the header is one column "
                                             f"'{columns[0][:40]}'{_semicolon_hint(line)}")
                    return meta, columns, skip
                body = line.lstrip().lstrip("#").strip()
                if ":" in body:
                    key, value = body.split(":", 1)
                    meta[key.strip().lower()] = value.strip()
        raise RecordingError(f"{self.source}: no header line (expected column names)")

    def _rows(self) -> Iterator[np.ndarray]:
        import pyarrow as pa
        from pyarrow import csv

        read = csv.ReadOptions(skip_rows=self.skip + 1, column_names=list(self.columns),
                               block_size=self.batch_bytes, encoding="utf8")
        convert = csv.ConvertOptions(column_types={c: pa.float64() for c in self.columns})
        try:
            with csv.open_csv(self.path, read_options=read, convert_options=convert) as reader:
                for batch in reader:
                    yield np.column_stack([batch.column(k).to_numpy(zero_copy_only=False)
                                           for k in range(batch.num_columns)])
        except pa.ArrowInvalid as exc:
            raise self._bad_line() or RecordingError(f"{self.source}: {_arrow_message(exc)}") from None

    def _bad_line(self) -> RecordingError | None:
        """The first data line that does not read (its cell count, or the cell that is no number: the
        whole-file reader's message), found by reading the file again line by line (only once pyarrow
        refused it), or None."""
        with open(self.path, encoding="utf-8-sig") as fh:
            for k, line in enumerate(fh, start=1):
                if k < self.first_line or not line.strip():
                    continue
                try:
                    _parse_cells([line.rstrip("\r\n").split(",")], self.columns, self.source, k)
                except RecordingError as exc:  # its row 1 is the file's data row k - first_line + 1
                    return _shift_rows(exc, k - self.first_line)
        return None

    def _record(self, table: np.ndarray, first: bool = False) -> Recording:
        def take(prefix: str) -> np.ndarray | None:
            return table[:, [self.index[c] for c in self.names[prefix]]] if f"{prefix}1" in self.index else None

        aux = {name[2:]: table[:, col] for name, col in self.index.items() if name.startswith("x:")}
        q = _to_model(take("q"), self.robot, self.convention)
        measured = table[:, self.index["measured"]] if "measured" in self.index else None
        segment = table[:, self.index["segment"]] if "segment" in self.index else None
        segment0 = 0.0 if segment is None or first or not segment.size else float(segment[0])
        segment = _check_layout(measured, None if segment is None else segment - segment0, self.source)
        rec = Recording(t=table[:, self.index["t"]], q=q, tau=take("tau"), dq=take("dq"), source=self.source,
                        robot=self.robot.name, current=take("i"), aux=aux,
                        measured=None if measured is None else measured == 1, segment=segment)
        rec.meta["segment0"] = int(segment0)
        return rec


def _arrow_message(exc: Exception) -> str:
    """pyarrow's parse error in the words of the other readers (which cell, which line)."""
    text = str(exc).strip().splitlines()[0]
    return text.replace("CSV conversion error to double: invalid value", "cell is not a number:")


def block_source(item: Any, robot: rx90sym.Robot, convention: str | None = None,
                 gains: DriveGains | None = None) -> BlockSource:
    """A :class:`BlockSource` for a recording, a CSV path or an existing source."""
    if isinstance(item, BlockSource):
        return item
    if isinstance(item, Recording):
        return MemorySource(item, robot, gains)
    path = Path(item)
    if path.suffix.lower() == ".csv":
        return CsvSource(path, robot, convention, gains)
    from identify.io.recordings import read_recording  # NPZ: arrays are memory-mapped by numpy only whole

    return MemorySource(read_recording(path, robot, convention), robot, gains)
