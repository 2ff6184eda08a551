"""The one page builder of every report (identify, payload, gains, excite): summary first, then sections.

A report is a :class:`Page`: a title, a :class:`Summary` (the verdict, the facts a reader checks
first, a small table such as the held-out error, flags and what to do next) and sections of
:class:`Table`, :class:`Figure` and :class:`Text` blocks. Callers pass plain values (rows of
numbers, flags as dicts); this module does the HTML: one self-contained file (figures inline as
base64 PNG, style and a few lines of sorting script inline, no network fetch), sections with
anchors, a layout as wide as a normal screen, and print rules.
"""
from __future__ import annotations

import base64
import html
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

from rx90sym.files import atomic_write

from .cells import fixed, fmt, number

#: Marks of a cell or a flag, from good to bad (CSS class and the symbol that survives printing).
MARKS = {"ok": "✓", "check": "!", "poor": "✗", "": ""}
SEVERITIES = ("error", "warning", "info")
_SEVERITY_MARK = {"error": "poor", "warning": "check", "info": ""}


@dataclass(frozen=True)
class Column:
    """A table column: label, unit (shown in the header as [unit]), digits (significant) or decimals."""

    label: str
    unit: str = ""
    digits: int = 4
    decimals: int | None = None
    text: bool = False

    def header(self) -> str:
        return f"{self.label} [{self.unit}]" if self.unit else self.label

    def cell(self, value: Any) -> str:
        if self.text:
            return "–" if value is None else str(value)
        return fixed(value, self.decimals) if self.decimals is not None else fmt(value, self.digits)


@dataclass(frozen=True)
class Cell:
    """A value with a mark ("ok", "check", "poor") and an optional tooltip."""

    value: Any
    mark: str = ""
    title: str = ""


@dataclass(frozen=True)
class Table:
    """Rows of values under columns; sortable by a click on a header."""

    id: str
    caption: str
    columns: tuple[Column, ...]
    rows: tuple[tuple[Any, ...], ...]
    note: str = ""


@dataclass(frozen=True)
class Figure:
    """A PNG image (bytes) with its caption."""

    id: str
    caption: str
    png: bytes = field(repr=False)


@dataclass(frozen=True)
class Text:
    """Paragraphs of plain text."""

    paragraphs: tuple[str, ...]


@dataclass(frozen=True)
class Section:
    """A titled block with an anchor (``id``)."""

    id: str
    title: str
    blocks: tuple[Table | Figure | Text, ...] = ()


@dataclass(frozen=True)
class Summary:
    """The verdict first: a headline, facts (label, text), one table (e.g. the held-out error),
    flags (dicts with code, severity, joint, message, action) and what to do next."""

    headline: str
    facts: tuple[tuple[str, str], ...] = ()
    table: Table | None = None
    flags: tuple[Mapping[str, Any], ...] = ()
    next_steps: tuple[str, ...] = ()

    @property
    def verdict(self) -> str:
        """"poor" with an error flag, "check" with a warning, else "ok"."""
        severities = {f.get("severity") for f in self.flags}
        return "poor" if "error" in severities else "check" if "warning" in severities else "ok"


@dataclass(frozen=True)
class Page:
    title: str
    subtitle: str
    summary: Summary
    sections: tuple[Section, ...] = ()


_CSS = """
*{box-sizing:border-box}
body{font:15px/1.45 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;color:#1b1f24;margin:0;background:#fff}
header,main{max-width:1500px;margin:0 auto;padding:0 24px}
header{padding-top:14px}
h1{font-size:1.45em;margin:0 0 2px}
.sub{color:#57606a;margin:0 0 8px}
nav{position:sticky;top:0;background:#f6f8fa;border-bottom:1px solid #d0d7de;padding:6px 24px;z-index:1;font-size:.92em;
 display:flex;flex-wrap:wrap;gap:2px 14px}
nav a{color:#0969da;text-decoration:none;white-space:nowrap}
h2{font-size:1.2em;border-bottom:1px solid #d0d7de;padding-bottom:3px;margin:26px 0 10px}
#summary{border:1px solid #d0d7de;border-left:6px solid #1a7f37;border-radius:6px;padding:10px 16px;margin-top:10px}
#summary.check{border-left-color:#bf8700}#summary.poor{border-left-color:#cf222e}
#summary h2{border:0;margin:0 0 6px}
.verdict{font-weight:600;font-size:1.05em;margin:0 0 8px}
.grid{display:grid;grid-template-columns:repeat(auto-fit,minmax(400px,1fr));gap:12px 28px;align-items:start}
dl.facts{display:grid;grid-template-columns:max-content 1fr;gap:2px 14px;margin:0}
dl.facts dt{color:#57606a}dl.facts dd{margin:0}
ul.flags,ol.next{margin:4px 0 0;padding-left:22px}
ul.flags li{margin:2px 0}
.sev{display:inline-block;min-width:5.4em;margin-right:6px;font-size:.78em;font-weight:600;text-transform:uppercase}
.sev.error{color:#cf222e}.sev.warning{color:#9a6700}.sev.info{color:#57606a}
.wrap{overflow-x:auto;max-width:100%}
table{border-collapse:collapse;font-variant-numeric:tabular-nums;margin:4px 0 12px}
caption{text-align:left;font-weight:600;padding:2px 0 4px}
th,td{border-bottom:1px solid #e4e8ec;padding:3px 8px;text-align:right;white-space:nowrap}
th{background:#f6f8fa;cursor:pointer;user-select:none;position:relative}
th.text,td.text{text-align:left}
th[aria-sort=ascending]::after{content:" ▲"}th[aria-sort=descending]::after{content:" ▼"}
td.ok{color:#1a7f37}td.check{background:#fff8c5}td.poor{background:#ffebe9;color:#a40e26;font-weight:600}
td .m{font-size:.85em;margin-left:4px}
p.note{color:#57606a;font-size:.9em;margin:0 0 10px}
.figs{display:grid;grid-template-columns:repeat(auto-fit,minmax(560px,1fr));gap:12px 24px}
figure{margin:0}figure img{max-width:100%;height:auto;display:block}
figcaption{color:#57606a;font-size:.9em}
footer{color:#57606a;font-size:.85em;margin:30px auto 20px;max-width:1500px;padding:0 24px}
@media print{
 nav{display:none}body{font-size:9pt}table{font-size:8pt}header,main{max-width:none;padding:0}
 .wrap{overflow:visible}th{cursor:auto;white-space:normal}td.text{white-space:normal}th,td{padding:1px 4px}
 .grid{grid-template-columns:1fr}
 h2{break-after:avoid}table,figure{break-inside:avoid}thead{display:table-header-group}
 .figs{display:block}figure{margin-bottom:8px}
 td.check,td.poor{background:none}
}
"""

# Click a header to sort its table by the cell's data-sort number (or its text); again: reverse.
_SCRIPT = """
document.querySelectorAll("table.sortable th").forEach(function(th){th.addEventListener("click",function(){
 var tb=th.closest("table").tBodies[0],i=th.cellIndex,asc=th.getAttribute("aria-sort")!=="ascending";
 th.parentNode.querySelectorAll("th").forEach(function(h){h.removeAttribute("aria-sort")});
 th.setAttribute("aria-sort",asc?"ascending":"descending");
 var key=function(r){var c=r.cells[i],v=c.getAttribute("data-sort");return v===null?c.textContent:parseFloat(v)};
 Array.from(tb.rows).sort(function(a,b){var x=key(a),y=key(b),n=typeof x==="number";
  var d=n?((isNaN(x)?Infinity:x)-(isNaN(y)?Infinity:y)):String(x).localeCompare(String(y));return asc?d:-d})
 .forEach(function(r){tb.appendChild(r)})})});
"""


def anchor(text: str) -> str:
    """An id from a title: lower case, words joined by '-'."""
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-") or "section"


def _e(text: Any) -> str:
    return html.escape(str(text), quote=True)


def _cell(column: Column, value: Any) -> str:
    cell = value if isinstance(value, Cell) else Cell(value)
    classes = " ".join(c for c in ("text" if column.text else "", cell.mark) if c)
    key = number(cell.value)
    sort = "" if column.text else f" data-sort='{key if key is not None else 'NaN'}'"
    mark = f"<span class='m'>{MARKS.get(cell.mark, '')}</span>" if cell.mark in ("check", "poor") else ""
    title = f" title='{_e(cell.title)}'" if cell.title else ""
    return f"<td{' class=' + repr(classes) if classes else ''}{sort}{title}>{_e(column.cell(cell.value))}{mark}</td>"


def table_html(table: Table) -> str:
    head = "".join(f"<th scope='col'{' class=text' if c.text else ''}>{_e(c.header())}</th>" for c in table.columns)
    rows = "".join("<tr>" + "".join(_cell(c, v) for c, v in zip(table.columns, row)) + "</tr>"
                   for row in table.rows)
    note = f"<p class='note'>{_e(table.note)}</p>" if table.note else ""
    return (f"<div class='wrap'><table class='sortable' id='{_e(table.id)}'><caption>{_e(table.caption)}</caption>"
            f"<thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table></div>{note}")


def figure_html(figure: Figure) -> str:
    data = base64.b64encode(figure.png).decode("ascii")
    return (f"<figure id='{_e(figure.id)}'><img alt='{_e(figure.caption)}' src='data:image/png;base64,{data}'>"
            f"<figcaption>{_e(figure.caption)}</figcaption></figure>")


def _blocks_html(blocks: Sequence[Table | Figure | Text]) -> str:
    parts, figures = [], []
    for block in blocks:
        if isinstance(block, Figure):
            figures.append(figure_html(block))
            continue
        if figures:
            parts.append(f"<div class='figs'>{''.join(figures)}</div>")
            figures = []
        if isinstance(block, Table):
            parts.append(table_html(block))
        else:
            parts.extend(f"<p>{_e(p)}</p>" for p in block.paragraphs)
    if figures:
        parts.append(f"<div class='figs'>{''.join(figures)}</div>")
    return "".join(parts)


def _flag_html(flag: Mapping[str, Any]) -> str:
    severity = str(flag.get("severity", "info"))
    joint = flag.get("joint")
    where = f"joint {joint}: " if joint not in (None, "") else ""
    action = flag.get("action")
    todo = f" — <em>{_e(action)}</em>" if action else ""
    return (f"<li class='flag' data-code='{_e(flag.get('code', ''))}'><span class='sev {_e(severity)}'>"
            f"{_e(severity)}</span>{_e(where + str(flag.get('message', '')))}{todo}</li>")


def summary_html(summary: Summary) -> str:
    facts = "".join(f"<dt>{_e(k)}</dt><dd>{_e(v)}</dd>" for k, v in summary.facts)
    table = table_html(summary.table) if summary.table is not None else ""
    order = {s: i for i, s in enumerate(SEVERITIES)}
    flags = sorted(summary.flags, key=lambda f: order.get(str(f.get("severity")), len(order)))
    flag_list = ("<h3>Flags</h3><ul class='flags'>" + "".join(_flag_html(f) for f in flags) + "</ul>"
                 if flags else "<p class='noflags'>No flags.</p>")
    steps = ("<h3>What to do next</h3><ol class='next'>" + "".join(f"<li>{_e(s)}</li>" for s in summary.next_steps)
             + "</ol>" if summary.next_steps else "")
    return (f"<section id='summary' class='{summary.verdict}'><h2>Summary</h2>"
            f"<p class='verdict'>{MARKS[summary.verdict]} {_e(summary.headline)}</p>"
            f"<div class='grid'><dl class='facts'>{facts}</dl><div>{table}</div></div>"
            f"<div class='grid'><div>{flag_list}</div><div>{steps}</div></div></section>")


def render(page: Page) -> str:
    """The HTML text of a page (one self-contained file)."""
    nav = "".join(f"<a href='#{_e(s.id)}'>{_e(s.title)}</a>" for s in page.sections)
    body = "".join(f"<section id='{_e(s.id)}'><h2>{_e(s.title)}</h2>{_blocks_html(s.blocks)}</section>"
                   for s in page.sections)
    return ("<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
            "<meta name='viewport' content='width=device-width,initial-scale=1'>"
            f"<title>{_e(page.title)}</title><style>{_CSS}</style></head><body>"
            f"<header><h1>{_e(page.title)}</h1><p class='sub'>{_e(page.subtitle)}</p></header>"
            f"<nav><a href='#summary'>Summary</a>{nav}</nav><main>{summary_html(page.summary)}{body}</main>"
            f"<footer>Written by rx90sym; one self-contained file (no network access needed).</footer>"
            f"<script>{_SCRIPT}</script></body></html>")


def write_page(path: str | os.PathLike, page: Page) -> Path:
    """Write the page atomically (temporary file, then rename): never a half-written file."""
    text = render(page)
    return atomic_write(path, lambda handle: handle.write(text))
