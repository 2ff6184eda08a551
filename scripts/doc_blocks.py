"""The fenced blocks of a markdown page, with their tags and `<!-- docs: ... -->` markers.

Read by scripts/run_docs.py (which runs them) and its tests. A fence's info string says what a block
is: `sh`/`bash`/`console` (shell; in a `console` block the commands are the lines after `$ `, the
rest is their output), `python`, and anything else (`text` for synopses, output and diagrams, `toml`,
`csv`, ...) is not run. An untagged fence is an error: every block says what it is.

Markers are HTML comments on the lines right above the fence, one directive each:

    <!-- docs: skip (reason) -->          not run (make test, make demo, a real robot), counted with its reason
    <!-- docs: slow -->                   run by `make docs` only (over ~10 s)
    <!-- docs: files PATH ... -->         repository files linked into the page's folder before the block
    <!-- docs: excerpt REGEX[@N] ... -->  console block: the output written back keeps, in order, the next
                                          line matching each REGEX (and the N-1 lines after it); "..." between
"""
from __future__ import annotations

import re
import shlex
from dataclasses import dataclass, field
from pathlib import Path

SHELL_TAGS = ("sh", "bash", "console")
PYTHON_TAGS = ("python",)
_FENCE = re.compile(r"^(?P<indent>[ \t]*)(?P<fence>`{3,}|~{3,})(?P<info>[^`]*)$")
_MARKER = re.compile(r"^\s*<!--\s*docs:\s*(?P<body>.*?)\s*-->\s*$")
DIRECTIVES = ("skip", "slow", "files", "excerpt")


class DocError(ValueError):
    """A page that cannot be read as runnable docs (untagged fence, unknown marker)."""


@dataclass(frozen=True)
class Excerpt:
    """Which output lines a console block keeps: (regex, line count) in order."""
    picks: tuple[tuple[str, int], ...]

    def apply(self, lines: list[str]) -> list[str]:
        """The kept lines, "..." where lines were left out (start and end included).
        Raises DocError naming the pattern that matched nothing after the previous pick."""
        out: list[str] = []
        cursor = 0
        for pattern, count in self.picks:
            regex = re.compile(pattern)
            hit = next((k for k in range(cursor, len(lines)) if regex.search(lines[k])), None)
            if hit is None:
                raise DocError(f"excerpt: no output line matches {pattern!r} after line {cursor}")
            if hit > cursor:
                out.append("...")
            out.extend(lines[hit:hit + count])
            cursor = hit + count
        if cursor < len(lines):
            out.append("...")
        return out


@dataclass(frozen=True)
class Block:
    """One fenced block: `line` is the 1-based line of its opening fence, `body_lines` its content
    (indent removed), `start`/`end` the 0-based indices of the fences in the page's lines."""
    page: Path
    line: int
    tag: str
    body_lines: tuple[str, ...]
    start: int
    end: int
    indent: str = ""
    skip: str | None = None
    slow: bool = False
    files: tuple[str, ...] = ()
    excerpt: Excerpt | None = None

    @property
    def kind(self) -> str:
        """'shell', 'python' or 'none' (not run)."""
        if self.tag in SHELL_TAGS:
            return "shell"
        if self.tag in PYTHON_TAGS:
            return "python"
        return "none"

    @property
    def where(self) -> str:
        return f"{self.page}:{self.line}"

    @property
    def body(self) -> str:
        return "\n".join(self.body_lines)

    def commands(self) -> str:
        """The shell script of a shell block (a console block's `$ ` lines and their continuations)."""
        if self.tag != "console":
            return self.body
        script, continued = [], False
        for text in self.body_lines:
            if continued or text.startswith("$ "):
                script.append(text if continued else text[2:])
                continued = text.rstrip().endswith("\\")
        return "\n".join(script)

    def command_count(self) -> int:
        """How many leading lines of a console block are commands (output follows them)."""
        count, continued = 0, False
        for text in self.body_lines:
            if not (continued or text.startswith("$ ")):
                break
            count += 1
            continued = text.rstrip().endswith("\\")
        return count


@dataclass
class _Markers:
    skip: str | None = None
    slow: bool = False
    files: list[str] = field(default_factory=list)
    excerpt: Excerpt | None = None


def _parse_marker(body: str, where: str) -> tuple[str, str]:
    word, _, rest = body.partition(" ")
    word = word.rstrip(":")
    if word not in DIRECTIVES:
        raise DocError(f"{where}: unknown docs marker {word!r} (known: {', '.join(DIRECTIVES)})")
    return word, rest.strip()


def _excerpt(rest: str, where: str) -> Excerpt:
    picks = []
    for token in shlex.split(rest):
        pattern, at, count = token.rpartition("@")
        if not at or not count.isdigit():
            pattern, count = token, "1"
        picks.append((pattern, int(count)))
    if not picks:
        raise DocError(f"{where}: excerpt marker without a pattern")
    return Excerpt(tuple(picks))


def _markers_above(lines: list[str], start: int, where: str) -> _Markers:
    found = _Markers()
    k = start - 1
    while k >= 0 and _MARKER.match(lines[k]):
        word, rest = _parse_marker(_MARKER.match(lines[k]).group("body"), f"{where} (line {k + 1})")
        if word == "skip":
            reason = rest.strip().strip("()").strip()
            if not reason:
                raise DocError(f"{where} (line {k + 1}): a skip marker needs its reason: <!-- docs: skip (why) -->")
            found.skip = reason
        elif word == "slow":
            found.slow = True
        elif word == "files":
            found.files.extend(rest.split())
        else:
            found.excerpt = _excerpt(rest, where)
        k -= 1
    return found


def read_blocks(page: Path, text: str | None = None) -> list[Block]:
    """Every fenced block of `page` in order. Raises DocError for an untagged or unclosed fence."""
    lines = (page.read_text(encoding="utf-8") if text is None else text).split("\n")
    blocks: list[Block] = []
    k = 0
    while k < len(lines):
        opening = _FENCE.match(lines[k])
        if not opening:
            k += 1
            continue
        indent, fence, info = opening.group("indent", "fence", "info")
        where = f"{page}:{k + 1}"
        tag = info.strip().split(" ")[0] if info.strip() else ""
        if not tag:
            raise DocError(f"{where}: untagged fence: say what the block is (sh, console, python, text, ...)")
        close = re.compile(rf"^[ \t]*{re.escape(fence[0])}{{{len(fence)},}}\s*$")
        end = next((j for j in range(k + 1, len(lines)) if close.match(lines[j])), None)
        if end is None:
            raise DocError(f"{where}: fence never closed")
        body = tuple(text[len(indent):] if text.startswith(indent) else text.lstrip() for text in lines[k + 1:end])
        marks = _markers_above(lines, k, where)
        blocks.append(Block(page, k + 1, tag, body, k, end, indent, marks.skip, marks.slow, tuple(marks.files),
                            marks.excerpt))
        k = end + 1
    return blocks


def with_output(lines: list[str], block: Block, output: list[str]) -> list[str]:
    """The page's `lines` with console `block`'s output replaced by `output` (after its commands)."""
    if block.tag != "console":
        raise DocError(f"{block.where}: only a console block's output is written back")
    head = block.command_count()
    if any(text.startswith("$ ") for text in block.body_lines[head:]):
        raise DocError(f"{block.where}: commands after output: the output is written back after the last command")
    kept = [block.indent + text if text else text for text in output]
    return lines[:block.start + 1 + head] + kept + lines[block.end:]
