"""CSV tables: the comment lines, header and numbers of a recording or motor file.

Parsing only: the names of the columns are checked here (:func:`_column_index`), what the
numbers mean is up to the readers of :mod:`identify.io.recordings` and :mod:`identify.io.motor_files`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from rx90sym.recording import RecordingError

from identify.io.log_rows import _is_number


@dataclass(frozen=True)
class _Table:
    """A parsed CSV file: comment keys, column names, float values (N, ncols)."""

    source: str
    meta: dict[str, str]
    columns: tuple[str, ...]
    values: np.ndarray
    first_data_line: int  # 1-based line number in the file of data row 1


def _semicolon_hint(line: str) -> str:
    """A hint when a line looks ';'-separated (spreadsheets in many locales write that)."""
    return "; the file seems to use ';' as separator (expected ',')" if ";" in line and "," not in line else ""


def _parse_cells(rows: list[list[str]], columns: Sequence[str], source: str, first_line: int,
                 width_from: str = "the header") -> np.ndarray:
    """Convert cell text to floats; on failure name the first bad cell (``width_from``: what set
    the expected cell count, for the message)."""
    n_cols = len(columns)
    for i, cells in enumerate(rows):
        if len(cells) != n_cols:
            raise RecordingError(
                f"{source}: row {i + 1} (line {first_line + i}) has {len(cells)} cells, "
                f"{width_from} has {n_cols} columns{_semicolon_hint(','.join(cells))}"
            )
    if not rows:
        return np.empty((0, n_cols))
    try:
        return np.array(rows, dtype=float)  # fast path: numpy parses all cells at once
    except ValueError:
        pass
    for i, cells in enumerate(rows):  # slow path, only to locate the bad cell
        for j, cell in enumerate(cells):
            try:
                float(cell)
            except ValueError:
                raise RecordingError(
                    f"{source}: column '{columns[j]}', row {i + 1} (line {first_line + i}): "
                    f"cell {cell.strip()!r} is not a number"
                ) from None
    raise RecordingError(f"{source}: unreadable numbers")  # unreachable in practice


def _read_table(path: Path, header: bool | None = True, names: Sequence[str] = ()) -> _Table:
    """Read comments ``# key: value``, the header and the numbers of a CSV file.

    ``header``: True, the first line after the comments names the columns; None, it does when one
    of its cells is not a number (files exported with or without a header); a file without one
    takes ``names`` (or ``column 1``, ``column 2``, ...) as its column names.
    """
    source = path.name
    try:
        text = path.read_text(encoding="utf-8-sig")  # -sig: tolerate the BOM spreadsheets write
    except UnicodeDecodeError as exc:
        raise RecordingError(f"{source}: not a UTF-8 text file ({exc})") from None
    lines = text.splitlines()
    meta: dict[str, str] = {}
    i = 0
    while i < len(lines) and (not lines[i].strip() or lines[i].lstrip().startswith("#")):
        body = lines[i].lstrip().lstrip("#").strip()
        if ":" in body:
            key, value = body.split(":", 1)
            meta[key.strip().lower()] = value.strip()
        i += 1
    if i == len(lines):
        raise RecordingError(f"{source}: no header line (expected column names)" if header else f"{source}: no data rows")
    cells = lines[i].split(",")
    if header is None:
        header = not all(_is_number(c) for c in cells)
    if header:
        columns = tuple(c.strip() for c in cells)
        header_line = i + 1
        if len(columns) == 1 and _semicolon_hint(lines[i]):
            raise RecordingError(f"{source}: line {header_line}: the header is one column "
                                 f"'{columns[0][:40]}'{_semicolon_hint(lines[i])}")
    else:
        columns = tuple(names) if len(names) == len(cells) else tuple(f"column {k + 1}" for k in range(len(cells)))
        header_line = i
    data = lines[header_line:]
    while data and not data[-1].strip():  # tolerate trailing blank lines only
        data.pop()
    rows = [line.split(",") for line in data]
    values = _parse_cells(rows, columns, source, header_line + 1, "the header" if header else "the first row")
    return _Table(source=source, meta=meta, columns=columns, values=values, first_data_line=header_line + 1)


def _check_same_rows(tables: Sequence[_Table]) -> None:
    """Files read side by side (one sample per row in each) have the same number of rows: the
    message names the shorter file, its first missing row and every file's row count."""
    counts = [t.values.shape[0] for t in tables]
    if len(set(counts)) > 1:
        short = tables[int(np.argmin(counts))]
        listed = ", ".join(f"{t.source} has {c} rows" for t, c in zip(tables, counts))
        raise RecordingError(f"{short.source}: column '{short.columns[0]}', row {min(counts) + 1}: missing "
                             f"({listed}; mismatched lengths)")


def _column_index(table: _Table, expected: Sequence[str],
                  optional: Sequence[Sequence[str]] = (), aux: bool = False) -> dict[str, int]:
    """Map names to column positions; refuse missing, duplicated and unknown columns.

    ``optional`` lists groups of columns that come all together or not at all; with ``aux``,
    columns named ``x:NAME`` are accepted (auxiliary signals).
    """
    positions: dict[str, list[int]] = {}
    for k, name in enumerate(table.columns):
        positions.setdefault(name, []).append(k)
    for name, where in positions.items():
        if len(where) > 1:
            cols = ", ".join(str(k + 1) for k in where)
            raise RecordingError(f"{table.source}: column '{name}' appears more than once (header positions {cols})")
    known = set(expected).union(*[set(g) for g in optional])
    for name in table.columns:
        if name not in known and not (aux and name.startswith("x:") and len(name) > 2):
            groups = "".join(f", optionally {g[0]}..{g[-1]}" for g in optional)
            raise RecordingError(
                f"{table.source}: column '{name}' is unknown (expected {expected[0]}, {expected[1]}.."
                f"{expected[-1]}{groups}{', x:NAME' if aux else ''})"
            )
    for name in expected:
        if name not in positions:
            raise RecordingError(f"{table.source}: column '{name}' is missing")
    index = {name: positions[name][0] for name in expected}
    for group in optional:
        present = [name for name in group if name in positions]
        if present and len(present) != len(group):
            missing = next(name for name in group if name not in positions)
            raise RecordingError(
                f"{table.source}: column '{missing}' is missing (the optional columns "
                f"{group[0]}..{group[-1]} come all together or not at all)"
            )
        index.update({name: positions[name][0] for name in present})
    if aux:
        index.update({name: positions[name][0] for name in table.columns if name.startswith("x:")})
    return index
