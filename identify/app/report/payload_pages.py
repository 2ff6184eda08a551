"""The reports of ``rx90 payload`` and ``rx90 gains``, built from their JSON records."""
from __future__ import annotations

from typing import Any, Mapping, Sequence

from .cells import fmt, number
from .page import Cell, Column, Figure, Page, Section, Summary, Table
from .summary import as_flag, flag, next_steps
from .tables import gains_table, parameter_table

#: A payload mass more than this far from the a priori (weighed or CAD) value is flagged, %.
MASS_CHECK_PCT = 5.0
#: A payload mass with a relative σ above this is flagged, %.
MASS_REL_STD_PCT = 5.0


def _recording_facts(record: Mapping[str, Any]) -> list[tuple[str, str]]:
    data = record.get("data") or {}
    facts = []
    for key, label in (("empty", "Empty runs"), ("loaded", "Loaded runs")):
        if data.get(key):
            facts.append((label, ", ".join(data[key])))
    return facts


def _payload_flags(record: Mapping[str, Any], mass: float | None, std: float | None,
                   prior: float | None) -> list[dict]:
    flags = [as_flag(f) for f in record.get("flags") or ()]
    if mass is not None and prior:
        dev = 100 * (mass - prior) / prior
        if abs(dev) > MASS_CHECK_PCT:
            flags.append(flag("mass-off", "error", f"Mc = {mass:.4g} kg is {dev:+.1f} % from the a priori "
                              f"{prior:.4g} kg", "check the drive gains (rx90 gains) and the robot's parameters; "
                              "a wrong gain scales the mass"))
    if mass is not None and std is not None and mass and 100 * std / abs(mass) > MASS_REL_STD_PCT:
        flags.append(flag("mass-sigma", "warning", f"σ(Mc) is {100 * std / abs(mass):.1f} % of Mc",
                          "a longer or richer loaded motion (rx90 excite --for payload)"))
    if (record.get("spring") or {}).get("placeholder"):
        flags.append(flag("placeholder-spring", "warning", "the spring is the default placeholder model",
                          "give the maker's spring table (--spring FILE.csv) in the robot file"))
    return flags


def payload_page(record: Mapping[str, Any], figures: Sequence[Figure] = ()) -> Page:
    """The payload report: Mc and its centre of mass first, then the parameter and pairing tables."""
    payload = list(record.get("payload") or [])
    if record.get("constrained"):
        # A constrained estimate has no σ of its own: eq. 13's and the bootstrap's belong to the
        # unconstrained fit, so the page shows none (as the command line does).
        payload = [dict(p, std=None, rel_std_pct=None, bootstrap_std=None, std_headline=None) for p in payload]
    params = {p["name"]: p for p in payload}
    a_priori = record.get("a_priori") or None
    mass = number(params.get("Mc", {}).get("value"))
    mc = params.get("Mc", {})
    # ±1σ of the larger of eq. 13's and the bootstrap's (files before std_headline: eq. 13's)
    std = number(mc.get("std_headline", mc.get("std")))
    label = ("" if std is None else " (±1σ, bootstrap)" if number(mc.get("bootstrap_std")) is not None
             and number(mc.get("bootstrap_std")) >= number(mc.get("std") or 0) else " (±1σ, eq. 13)")
    prior = number(record.get("mass")) or (number(a_priori.get("Mc")) if a_priori else None)
    flags = _payload_flags(record, mass, std, prior)
    com = [None if not mass else (number(params.get(f"M{a}c", {}).get("value")) or 0) / mass for a in "XYZ"]
    rows = [("Mc", "kg", prior, mass, std)]
    rows += [(f"CoG {a.lower()}", "m", None if not a_priori or not a_priori.get("Mc") else
              (number(a_priori.get(f"M{a}c")) or 0) / a_priori["Mc"], c, None) for a, c in zip("XYZ", com)]
    table = Table("summary-payload", "Mass and centre of mass (frame of the last link)",
                  (Column("quantity", text=True), Column("unit", text=True), Column("a priori"),
                   Column("identified"), Column("σ", digits=3)), tuple(rows))
    spread = f" ± {fmt(std, 2)}" if std is not None else ""
    headline = (f"Payload mass {fmt(mass)}{spread} kg{label}" + (" (constrained: no σ of its own)" if record.get("constrained")
                                                          else "") + (f" (a priori {fmt(prior)} kg)" if prior else "")
                + ("; see the flags." if any(f["severity"] in ("error", "warning") for f in flags) else "."))
    facts = [("Robot", str(record.get("robot_name", ""))),
             ("Method", f"{record.get('method')} (paper §IV)" + (", constrained" if record.get("constrained") else "")),
             *_recording_facts(record)]
    summary = Summary(headline, tuple(facts), table, tuple(flags), next_steps(flags))
    sections = [Section("payload", "Payload parameters", (
        parameter_table(payload, a_priori=a_priori or None, table_id="payload",
                        caption="Payload parameters (frame of the last link, about its origin)"), *figures))]
    robot = record.get("robot")  # the robot's base parameters identified with the payload (methods 2, 4)
    if isinstance(robot, Mapping):
        sections.append(Section("robot", "Robot parameters identified with the payload",
                                (parameter_table(robot.get("parameters") or [], table_id="robot-parameters"),)))
    pairing = record.get("pairing") or []
    if pairing:
        sections.append(Section("pairing", "Paired runs (method 3)", (_pairing_table(pairing),)))
    return Page(f"Payload on {record.get('robot_name', '')}", f"rx90 payload · method {record.get('method')}",
                summary, tuple(sections))


def _pairing_table(pairing: Sequence[Mapping[str, Any]]) -> Table:
    cols = (Column("empty", text=True), Column("loaded", text=True), Column("lag", "s", digits=4),
            Column("largest position gap", "rad", digits=3), Column("at joint", decimals=0),
            Column("common samples", decimals=0))
    rows = tuple((p.get("empty"), p.get("loaded"), p.get("lag_s"), p.get("position_gap_rad"),
                  p.get("position_gap_joint"), p.get("common_samples")) for p in pairing)
    return Table("pairing", "Runs paired in time", cols, rows)


def gains_page(record: Mapping[str, Any], figures: Sequence[Figure] = ()) -> Page:
    """The drive-gain report: flagged gains first, the gains table, the weighing's share of σ."""
    flags = [as_flag(f) for f in record.get("flags") or ()]
    told = {f["joint"] for f in flags}  # the library's own flag on a gain wins over this one
    for j in (j for j in record.get("flagged") or () if j not in told):
        rel = (record.get("rel_std_pct") or [None] * j)[j - 1]
        flags.append(flag("gain-flagged", "warning", f"gain σr {fmt(rel, 3)} % above {fmt(record.get('flag_pct'))} %",
                          "set this gain from the datasheet (--fix J=VALUE) or use a motion that moves the "
                          "payload against gravity on this joint", j))
    mass, mass_std = number(record.get("mass")), number(record.get("mass_std")) or 0.0
    k = record.get("gains") or []
    headline = (f"{len(k)} drive gains from a {fmt(mass)} kg payload; "
                + (f"{len(record.get('flagged') or [])} flagged." if record.get("flagged") else "none flagged."))
    facts = [("Robot", str(record.get("robot", ""))), ("Method", str(record.get("method", ""))),
             ("Payload mass", f"{fmt(mass)} ± {fmt(mass_std, 2)} kg (weighed; common to every gain)"),
             *_recording_facts(record),
             ("Flag threshold", f"σr > {fmt(record.get('flag_pct'))} %")]
    rel = record.get("rel_std_pct") or [None] * len(k)
    flagged = set(record.get("flagged") or ())
    side = "motor" if record.get("side") == "motor" else "joint"
    table = Table("summary-gains", "Gains", (Column(side, decimals=0), Column("gain", "N·m/A", digits=5),
                                             Column("σr", "%", decimals=2)),
                  tuple((j, g, Cell(r, "poor" if j in flagged else "ok")) for j, (g, r) in enumerate(zip(k, rel), 1)))
    summary = Summary(headline, tuple(facts), table, tuple(flags), next_steps(flags))
    return Page(f"Drive gains of {record.get('robot', '')}", f"rx90 gains · {record.get('method', '')}",
                summary, (Section("gains", "Drive gains", (gains_table(record), *figures)),))
