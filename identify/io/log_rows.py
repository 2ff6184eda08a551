"""The rows of a controller log: its data lines, the selected window and their numbers.

Every message names the file and the line numbers of the file (the numbering of editors and
``sed -n``), so that a user can look at the bad rows; :mod:`identify.io.logs` reads the log.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rx90sym.recording import RecordingError

from identify.io.columns import ColumnMap

__all__ = ["ABSURD", "WINDOW_ADVICE", "LogLines", "header_cells", "check_header", "bad_rows",
           "parse_rows"]

#: A value larger than this in magnitude (any column but time) marks its row as corrupt.
ABSURD = 1e6
#: How many bad rows a message names before "and K more".
_SHOWN = 3


@dataclass(frozen=True)
class LogLines:
    """The data lines of a log: their 1-based line numbers and text."""

    source: str
    numbers: list[int]
    text: list[str]


def _file_lines(path: Path) -> list[str]:
    """The lines of a text file, numbered as editors and ``sed -n`` do, trailing blanks dropped."""
    try:
        raw = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise RecordingError(f"{path.name}: not a UTF-8 text file ({exc})") from None
    return [line.rstrip("\r") for line in raw.split("\n")]


def header_cells(path: Path) -> tuple[list[str], bool]:
    """The first non-comment line's cells, and whether they are separated by blanks (no comma)."""
    for line in _file_lines(path):
        if line.strip() and not line.lstrip().startswith("#"):
            return (line.split(), True) if "," not in line else (line.split(","), False)
    return [], False


def check_header(source: str, k: int, line: str, n_cols: int) -> None:
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


#: The advice of a message naming bad rows of a CSV log (a bag has no window: its messages name none).
WINDOW_ADVICE = "select a clean window with --rows FIRST:LAST or --from/--to (rows=, t_from=, t_to= in Python)"


def bad_rows(source: str, problems: list[tuple[int, str]], advice: str | None = WINDOW_ADVICE) -> RecordingError:
    """One message naming the first bad rows by line number and what is wrong with them, then
    ``advice`` (None: none, for an input whose form has no option that helps)."""
    problems = sorted(problems)
    shown = "; ".join(f"line {line}: {what}" for line, what in problems[:_SHOWN])
    more = len(problems) - _SHOWN
    tail = f" (and {more} more bad rows, the last at line {problems[-1][0]})" if more > 0 else ""
    return RecordingError(f"{source}: {shown}{tail}" + (f"; {advice}" if advice else ""))


def parse_rows(lines: LogLines, a: int, b: int, cmap: ColumnMap) -> np.ndarray:
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
        raise bad_rows(lines.source, [(lines.numbers[a + k], what) for k, what in problems.items()])
    return values
