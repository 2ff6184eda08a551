"""Where each table and key of a TOML file is written (line numbers for error messages).

tomllib gives values, not positions; this scan of the text finds the line of every table
header and of every ``key =`` inside it, for the layouts robot files use (``[table]``,
``[[array]]`` tables, ``key = value`` lines, dotted headers). Multi-line values are skipped
by tracking open brackets and triple-quoted strings.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
_KEY = re.compile(r"""^\s*("[^"]*"|'[^']*'|[A-Za-z0-9_\-.]+)\s*=""")


@dataclass
class Lines:
    """Line numbers (1-based) of tables and keys. A table is (name, index): index counts the
    ``[[name]]`` rows from 0, and is 0 for a plain ``[name]`` and for the top level ("")."""

    tables: dict[tuple[str, int], int] = field(default_factory=dict)
    keys: dict[tuple[str, int, str], int] = field(default_factory=dict)

    def table(self, name: str, index: int = 0) -> int | None:
        return self.tables.get((name, index))

    def key(self, table: str, key: str, index: int = 0) -> int | None:
        return self.keys.get((table, index, key))


def scan(text: str) -> Lines:
    """Line numbers of the tables and keys of a TOML text (best effort, never raises)."""
    out = Lines()
    counts: dict[str, int] = {}
    current = ("", 0)
    depth, in_multiline = 0, None
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw
        if in_multiline is not None:
            if in_multiline in line:
                in_multiline = None
            continue
        if depth > 0:
            depth += _bracket_balance(line)
            continue
        header = _HEADER.match(line)
        if header and not _KEY.match(line):
            name = ".".join(part.strip().strip('"\'') for part in header.group(2).split("."))
            if header.group(1) == "[[":
                index = counts.get(name, -1) + 1
                counts[name] = index
            else:
                index = 0
            current = (name, index)
            out.tables.setdefault(current, number)
            continue
        key = _KEY.match(line)
        if key:
            name = key.group(1).strip('"\'')
            out.keys.setdefault((current[0], current[1], name), number)
            rest = line[key.end():]
            for quote in ('"""', "'''"):
                if rest.count(quote) == 1:
                    in_multiline = quote
            depth = max(0, _bracket_balance(rest))
    return out


def _bracket_balance(text: str) -> int:
    text = re.sub(r'"[^"]*"|\'[^\']*\'', "", text).split("#", 1)[0]
    return text.count("[") + text.count("{") - text.count("]") - text.count("}")
