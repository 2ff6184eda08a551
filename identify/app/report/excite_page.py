"""The report of an excitation trajectory (``rx90 excite``), built from its JSON summary.

Verdict first: is the motion safe to run (every limit held on the checking grid, clearances) and
how well does it excite (criterion, cond); then the limit usage per joint and the figures.
"""
from __future__ import annotations

from typing import Any, Mapping, Sequence

from .cells import fmt, number
from .page import Cell, Column, Figure, Page, Section, Summary, Table
from .summary import as_flag, flag, next_steps
from .tables import key_values

#: Limit usage (max |x| / limit) above which a joint is marked "check" (below 1: inside the limit).
USAGE_CHECK = 0.95
_KINDS = ("position", "velocity", "acceleration", "torque")


def _usage_mark(value: Any) -> str:
    x = number(value)
    return "" if x is None else "ok" if x <= USAGE_CHECK else "check" if x <= 1.0 else "poor"


def _of_what(envelope: Mapping[str, Any] | None) -> str:
    """Which limits the usage is a fraction of: the safety envelope's (rx90 excite's JSON
    ``envelope``), narrower than the robot's, or the robot's own."""
    if not envelope:
        return ""
    return (f" Limits are the experiment's (safety envelope): velocity {fmt(envelope.get('velocity_scale'))} x "
            f"and acceleration {fmt(envelope.get('acceleration_scale'))} x the robot's, positions inside the "
            "experiment's ranges; torques the robot's.")


def usage_table(usage: Mapping[str, Any], table_id: str = "limits",
                envelope: Mapping[str, Any] | None = None) -> Table:
    """Per joint: max |x| / limit of position, velocity, acceleration and torque, in % (marked);
    ``envelope`` (the JSON's) says the limits are the experiment's, not the robot's."""
    lists = {k: usage.get(k) if isinstance(usage.get(k), list) else [] for k in _KINDS}
    n = max(len(v) for v in lists.values())
    lists = {k: v or [None] * n for k, v in lists.items()}
    rows = tuple((j + 1, *(Cell(None if lists[k][j] is None else 100 * lists[k][j], _usage_mark(lists[k][j]))
                           for k in _KINDS)) for j in range(n))
    cols = (Column("joint", decimals=0), *(Column(k, "%", decimals=0) for k in _KINDS))
    note = (f"Checked at {fmt(usage.get('checked_at_hz'))} Hz; ✓ ≤ {100 * USAGE_CHECK:.0f} %, ! up to the limit, "
            "✗ beyond. Positions: excursion over half the range about its centre." + _of_what(envelope))
    return Table(table_id, "Limit usage: max |x| / limit", cols, rows, note)


def _flags(record: Mapping[str, Any]) -> list[dict]:
    usage = record.get("limits_usage") or {}
    flags = [as_flag(f) for f in record.get("flags") or ()]
    flags += [flag("limit-violated", "error", v, "do not run it: optimise again (more margin, lower speed)")
              for v in usage.get("violations") or ()]
    if isinstance(usage.get("torque"), str):  # the note saying why torques were not checked
        flags.append(flag("torque-unchecked", "warning", usage["torque"],
                          "give nominal parameters so the torques are checked"))
    scaled = record.get("envelope") or {}  # the experiment's limits: already below the robot's
    for k in _KINDS:
        values = usage.get(k) if isinstance(usage.get(k), list) else []
        close = [j for j, v in enumerate(values, start=1) if _usage_mark(v) == "check"]
        if close and scaled and k != "torque":
            why = (f"the experiment's limit is {fmt(scaled.get(k + '_scale'))} x the robot's" if k != "position"
                   else "the experiment's ranges lie inside the robot's")
            flags.append(flag("limit-close", "info", f"{k} within {100 - 100 * USAGE_CHECK:.0f} % of the experiment's "
                              f"limit on joint(s) {', '.join(map(str, close))} ({why})"))
        elif close:
            flags.append(flag("limit-close", "warning", f"{k} within {100 - 100 * USAGE_CHECK:.0f} % of its limit "
                              f"on joint(s) {', '.join(map(str, close))}", "run it first at reduced speed"))
    return flags


def envelope_table(worst: Sequence[tuple[str, str, Any, Any, str]]) -> Table:
    """The safety envelope's worst values along the trajectory (excitation.envelope_report.worst)."""
    rows = tuple((name, unit, value, t, limit) for name, unit, value, t, limit in worst)
    return Table("envelope", "Safety envelope: worst values along the trajectory", (
        Column("quantity", text=True), Column("unit", text=True), Column("worst"), Column("at t", "s", digits=4),
        Column("limit", text=True)), rows)


def excite_page(record: Mapping[str, Any], figures: Sequence[Figure] = (), more: Sequence[Section] = ()) -> Page:
    """The excitation report from ``Trajectory.summary()`` (what ``rx90 excite --json`` writes);
    figures go with the limit usage, ``more`` sections after it."""
    usage = record.get("limits_usage") or {}
    flags = _flags(record)
    feasible = usage.get("feasible")
    headline = ("Safe to run on the checking grid" if feasible else "Not safe to run: a limit is violated"
                ) + f"; criterion {record.get('criterion', '')}, cond(W) = {fmt(record.get('cond'))}."
    facts = [("Form", f"{record.get('form', '')}, {fmt(record.get('duration'))} s"
                      + (f", {record.get('harmonics')} harmonics" if record.get("harmonics") else "")),
             ("Conditioning", f"cond(W) = {fmt(record.get('cond'))} at {fmt(record.get('cond_rate_hz'))} Hz"),
             ("Base parameters", fmt(record.get("base_parameters")))]
    if usage.get("min_clearance_m") is not None:
        facts.append(("Smallest clearance", f"{fmt(1e3 * usage['min_clearance_m'], 3)} mm"))
    if usage.get("min_height_m") is not None:
        # The lowest of every checked point (frame origins, capsule ends, tool), not only the tool's.
        plane = (record.get("envelope") or {}).get("mounting_plane_z_m")
        above = "" if plane is None else f", {fmt(usage['min_height_m'] - plane, 3)} m above the mounting plane"
        facts.append(("Lowest checked point", f"z = {fmt(usage['min_height_m'], 3)} m in frame 0{above} "
                                              f"(floor z = {fmt(usage.get('z_min_m'))} m)"))
    optimiser = record.get("optimiser") or {}
    envelope = record.get("envelope") or None
    sections = [Section("limits", "Limit usage", (usage_table(usage, envelope=envelope), *figures)), *more]
    items = [(k.replace("_", " "), "", v) for k, v in optimiser.items() if v not in (None, "") and not isinstance(v, dict)]
    if items:
        sections.append(Section("optimiser", "Optimiser", (key_values("optimiser", "How it was optimised", items),)))
    return Page(f"Excitation trajectory{' for ' + str(record['robot']) if record.get('robot') else ''}",
                "rx90 excite", Summary(headline, tuple(facts), usage_table(usage, "summary-limits", envelope), tuple(flags),
                                       next_steps(flags)), tuple(sections))
