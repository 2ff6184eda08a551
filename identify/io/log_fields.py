"""What a recording file keeps of the log it was converted from: the stale rows dropped and the gaps
that split it into segments.

A recording converted from a log (:func:`identify.read_log`, :func:`identify.read_bag`, the block
converter) carries two text fields, the same in both formats: CSV comment lines ``# key: value``
and NPZ 0-d strings ``key``:

``stale_rows``
    the count of stale rows dropped when the log was read, e.g. ``357``;
``split_gaps``
    the gaps longer than ``max_gap`` that split the log: their count, then the first
    :data:`SPLITS_LISTED`, each as the lines (or bag messages) before and after it and its duration
    in s, e.g. ``1; 3916-3917 0.200732``;
``t0_s``
    the log's own clock at the first sample [s] (a recording starts at 0 s), e.g. ``838.7``.

:func:`read_fields` turns them back into the recording's ``meta["log"]`` (``stale_rows`` and
``gaps["splits"]``, ``gaps["splits_total"]`` as :meth:`identify.io.gaps.LogGaps.summary` gives
them), and :func:`layout_fields` into the ``recordings`` entry of ``rx90 identify``'s JSON.
"""
from __future__ import annotations

from typing import Any, Mapping, Sequence

from rx90sym.recording import RecordingError

from identify.io.gaps import SPLITS_LISTED

__all__ = ["FIELDS", "SPLITS_LISTED", "file_fields", "format_splits", "read_fields", "layout_fields"]

#: The field names, in the order they are written.
FIELDS = ("stale_rows", "split_gaps", "t0_s")


def format_splits(splits: Sequence[Mapping[str, Any]], total: int) -> str:
    """The ``split_gaps`` field: ``total``, then ``; A-B DURATION`` for each of ``splits`` (dicts of
    :meth:`identify.io.gaps.Gap.to_dict`: ``lines``, ``duration_s`` in s; at most SPLITS_LISTED)."""
    return f"{int(total)}" + "".join(f"; {int(g['lines'][0])}-{int(g['lines'][1])} {float(g['duration_s'])!r}"
                                     for g in splits[:SPLITS_LISTED])


def file_fields(log: Mapping[str, Any] | None) -> dict[str, str]:
    """The fields of a recording whose ``meta["log"]`` is ``log`` (none when it came from no log)."""
    if not log or log.get("stale_rows") is None:
        return {}
    out = {"stale_rows": str(int(log["stale_rows"]))}
    gaps = log.get("gaps") or {}
    if "splits" in gaps:
        out["split_gaps"] = format_splits(gaps["splits"], gaps["splits_total"])
    if log.get("t0_s"):
        out["t0_s"] = repr(float(log["t0_s"]))
    return out


def _count(text: str, key: str, source: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise RecordingError(f"{source}: '# {key}: {text}' is not a whole number")
    return value


def _splits(text: str, source: str) -> dict[str, Any]:
    """``split_gaps`` read back: ``{"splits": [{"lines", "duration_s"}], "splits_total"}``."""
    parts = [p.strip() for p in text.split(";")]
    total = _count(parts[0], "split_gaps", source)
    splits = []
    for part in parts[1:]:
        try:
            lines, duration = part.split()
            a, b = (int(x) for x in lines.split("-"))
            splits.append({"lines": [a, b], "duration_s": float(duration)})
        except ValueError:
            raise RecordingError(f"{source}: '# split_gaps: {text}': {part!r} is not 'LINE-LINE SECONDS'") from None
    if len(splits) > total:
        raise RecordingError(f"{source}: '# split_gaps: {text}' lists {len(splits)} gaps, more than its count {total}")
    return {"splits": splits, "splits_total": total}


def read_fields(meta: Mapping[str, str], source: str) -> dict[str, Any] | None:
    """The ``meta["log"]`` of a recording read from a file with the fields ``meta`` (key -> text; None
    when it has none of them).

    Raises:
        RecordingError: a field that does not read (the message names the file and the field).
    """
    present = {k: meta[k].strip() for k in FIELDS if k in meta and meta[k].strip()}
    if not present:
        return None
    log: dict[str, Any] = {}
    if "stale_rows" in present:
        log["stale_rows"] = _count(present["stale_rows"], "stale_rows", source)
    if "split_gaps" in present:
        log["gaps"] = _splits(present["split_gaps"], source)
    if "t0_s" in present:
        try:
            log["t0_s"] = float(present["t0_s"])
        except ValueError:
            raise RecordingError(f"{source}: '# t0_s: {present['t0_s']}' is not a number of seconds") from None
    return log


def layout_fields(log: Mapping[str, Any] | None) -> dict[str, Any]:
    """What a recording's ``meta["log"]`` tells of its log for reports and JSON: ``stale_rows`` (dropped
    when it was read), ``split_gaps`` (the first SPLITS_LISTED gaps that split it: ``lines``,
    ``duration_s`` [s]) and ``split_gaps_total``; None when not known."""
    log = log or {}
    gaps = log.get("gaps") or {}
    splits = gaps.get("splits")
    return {"stale_rows": log.get("stale_rows"),
            "split_gaps": None if splits is None else [{"lines": list(g["lines"]), "duration_s": g["duration_s"]}
                                                       for g in splits],
            "split_gaps_total": gaps.get("splits_total")}
