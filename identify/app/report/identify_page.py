"""The report of ``rx90 identify``, built from its JSON record (what ``--json`` writes) and figures."""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

from identify.observation.processing import rest_label
from identify.fitting.rank_flags import has_rank_flag

from .cells import fixed, fmt, number
from .page import Column, Figure, Page, Section, Summary, Table, Text
from .rollout_page import rollout_blocks
from .summary import (REST_SHARE_CHECK, as_flag, flag, heldout_flags, heldout_table, next_steps,
                      parameter_flags, yardstick_flags)
from .tables import bodies_table, estimates_table, gains_table, key_values, parameter_table, validation_table

#: Largest gap [s] between the end of a fitted recording and the start of the held-out one for the
#: two to count as one run split in two (filtering trims a few samples at the edges).
SPLIT_GAP_S = 1.0


def data_facts(data: Mapping[str, Any] | None, model: Mapping[str, Any]) -> list[tuple[str, str]]:
    """Files, duration, samples, rates, cut-off and rest share, as summary facts."""
    facts = []
    recs = (data or {}).get("recordings") or []
    if recs:
        facts.append(("Recordings", ", ".join(str(r.get("source", "")) for r in recs)))
        duration = sum(number(r.get("duration_s")) or 0 for r in recs)
        samples = sum(int(r.get("samples") or 0) for r in recs)
        rates = ", ".join(fmt(r.get("rate_hz"), 4) for r in recs)
        facts.append(("Data", f"{fmt(duration, 4)} s, {samples} samples at {rates} Hz"))
    decim = model.get("decimate_to_hz")
    facts.append(("Filtering", f"cut-off {fmt(model.get('cutoff_hz'), 3)} Hz, rate {fmt(model.get('rate_hz'), 4)} Hz"
                  + (" after decimation" if decim else " (no decimation)")
                  + f", torque delay {fmt(1e3 * (number(model.get('delay_s')) or 0), 3)} ms"))
    share = (data or {}).get("moving_fraction")
    if share and model.get("min_velocity") is not None:
        rest = " / ".join(fixed(100 * (1 - s), 0) for s in share)
        facts.append(("At rest per joint", f"{rest} % (below {fmt(model.get('min_velocity'))} rad/s, "
                                           f"{rest_label(model.get('rest'))})"))
    return facts


def _flags(record: Mapping[str, Any], data: Mapping[str, Any] | None) -> list[dict]:
    flags = [as_flag(f) for f in record.get("flags") or ()]
    val = record.get("validation") or {}
    if val:
        flags += heldout_flags(val) + yardstick_flags(val)
    else:
        flags.append(flag("no-heldout", "warning", "no held-out data: the fit was not checked on samples it "
                          "did not see", "run again with --validate HELD_OUT.csv (another motion, or the "
                          "end of this one cut off with rx90 convert --rows)"))
    params = record.get("parameters") or []
    flags += parameter_flags([p["name"] for p in params], [p.get("rel_std_pct") for p in params],
                             record.get("bootstrap_std"), [p.get("std") for p in params], record.get("cond"),
                             model_cause=has_rank_flag(record.get("flags") or ()))
    flags += split_flags(data)
    if record.get("method") == "consistent" and not record.get("prior"):
        flags.append(flag("arbitrary-split", "warning", "no prior: how the links share what the data cannot see is "
                          "arbitrary (the bodies are one physical choice among many)",
                          "give the robot's nominal parameters (--prior FILE, or a [nominal] table in its file)"))
    share = (data or {}).get("moving_fraction") or []
    rest = [j for j, s in enumerate(share, start=1) if 1 - s > REST_SHARE_CHECK]
    if rest:
        flags.append(flag("rest-share", "warning", f"joints {', '.join(map(str, rest))} rest more than "
                          f"{100 * REST_SHARE_CHECK:.0f} % of the time: little information on their friction",
                          "record a motion that keeps every joint moving (rx90 excite)"))
    spring = record.get("spring") or {}
    if isinstance(spring, Mapping) and spring.get("placeholder"):
        flags.append(flag("placeholder-spring", "warning", "the spring is the default placeholder model, "
                          "not this robot's", "identify it (--spring identify) or give the maker's table "
                          "(--spring FILE.csv)"))
    return flags


def split_flags(data: Mapping[str, Any] | None) -> list[dict]:
    """A held-out recording that starts where a fitted one ends (within ``SPLIT_GAP_S``) is the same
    run cut at an arbitrary point: it checks the model on the same motion, not on a new one."""
    held = (data or {}).get("heldout") or {}
    start = number(held.get("t_first_s"))
    for rec in (data or {}).get("recordings") or ():
        end = number(rec.get("t_last_s"))
        if start is not None and end is not None and 0 <= start - end <= SPLIT_GAP_S:
            return [flag("heldout-continues-fit", "warning", f"the held-out data ({held.get('source')}) continue "
                         f"{rec.get('source')} (cut at t = {fmt(end, 4)} s): the same motion split at an "
                         "arbitrary point", "validate also on a different motion (another excitation, a "
                         "stop-and-go run)")]
    return []


def _headline(record: Mapping[str, Any], flags: Sequence[Mapping[str, Any]]) -> str:
    val = record.get("validation") or {}
    moving = [m for m in (number(v) for v in val.get("relative_error_pct_moving") or []) if m is not None]
    every = [m for m in (number(v) for v in val.get("relative_error_pct") or []) if m is not None]
    if moving:
        held = f"worst held-out error while moving {max(moving):.1f} %"
    elif every:
        # No joint moves in the held-out data: its error is all rest (static friction), never "0 %".
        held = f"no held-out sample moves (worst error on all samples {max(every):.1f} %, at rest)"
    else:
        held = "no held-out check"
    errors = sum(f.get("severity") == "error" for f in flags)
    warnings = sum(f.get("severity") == "warning" for f in flags)
    if errors:
        return f"Do not trust this model yet: {held}; {errors} error(s), {warnings} warning(s) below."
    if warnings:
        return f"Usable with care: {held}; {warnings} warning(s) below."
    return f"The model predicts held-out torques well: {held}."


def identify_summary(record: Mapping[str, Any]) -> Summary:
    """The verdict of an identification: facts, held-out table, flags, next steps."""
    model = record.get("model") or {}
    data = record.get("data")
    flags = _flags(record, data)
    robot_file = Path(str(model["robot_file"])).name if model.get("robot_file") else "built in memory"
    facts = [("Robot", f"{record.get('robot', '')} (file {robot_file})"),
             ("Method", f"{record.get('method', '')}, {len(record.get('parameters') or [])} parameters"),
             *data_facts(data, model),
             ("Conditioning", f"cond(W) = {fmt(record.get('cond'), 4)} (unweighted {fmt(record.get('cond_unweighted'), 4)})"),
             ("Residual σρ (eq. 12)", fmt(record.get("sigma_rho"), 4))]
    gains = model.get("gains") or {}
    if gains.get("gains"):
        facts.append(("Drive gains", f"{', '.join(fmt(k, 4) for k in gains['gains'])} N·m/A, "
                                     f"{gains.get('side', 'joint')} side"))
    if record.get("cost_increase_pct") is not None:
        facts.append(("Consistent fit", f"cost +{fmt(record.get('cost_increase_pct'), 3)} % over WLS; split "
                                        + (str(record["split"]) if record.get("split") else "–")))
    val = record.get("validation") or {}
    return Summary(_headline(record, flags), tuple(facts), heldout_table(val) if val else None, tuple(flags),
                   next_steps(flags))


def identify_page(record: Mapping[str, Any], figures: Mapping[str, Sequence[Figure]] | None = None,
                  prior: Mapping[str, float] | None = None, spring_text: str = "") -> Page:
    """The identification report. figures: by section ("validation", "rollout", "fit", "parameters",
    "trajectory"); prior: standard parameters shown beside the consistent fit's bodies."""
    figures = figures or {}
    model = record.get("model") or {}
    sections = []
    val = record.get("validation") or {}
    if val:
        beside = (estimates_table(val, record["validation_result"]),) if record.get("validation_result") else ()
        sections.append(Section("validation", "Held-out validation",
                                (validation_table(val), *beside, *figures.get("validation", ()))))
    if val.get("rollout"):
        sections.append(Section("rollout", "Rollout in MuJoCo (held-out)",
                                (*rollout_blocks(val["rollout"]), *figures.get("rollout", ()))))
    boot = record.get("bootstrap_std")
    sections.append(Section("parameters", "Parameters", (
        parameter_table(record.get("parameters") or [], boot), *figures.get("parameters", ()))))
    if (record.get("essential") or {}).get("parameters"):
        sections.append(Section("essential", "Essential parameters", (
            parameter_table(record["essential"]["parameters"], table_id="essential",
                            caption="Essential parameters (largest σr removed while σ stays within 2 %)"),)))
    if record.get("standard"):
        n = sum(1 for k in record["standard"] if k.startswith("M") and k[1:].isdigit())
        sections.append(Section("bodies", "Bodies", (bodies_table(record["standard"], n, prior),)))
    if model.get("gains"):
        sections.append(Section("gains", "Drive gains used", (gains_table(model["gains"], "gains-used"),)))
    if figures.get("fit"):
        sections.append(Section("fit", "Fit: measured and predicted torques", tuple(figures["fit"])))
    sections.append(Section("processing", "Processing record", (processing_table(record), *choice_blocks(record))))
    if spring_text or figures.get("trajectory"):
        sections.append(Section("motion", "Motion and spring", (*_spring_blocks(record.get("spring"), spring_text),
                                                                *figures.get("trajectory", ()))))
    return Page(f"Identification of {record.get('robot', '')}", _subtitle(record), identify_summary(record),
                tuple(sections))


def _spring_blocks(spring: Any, text: str) -> tuple:
    """An identified spring's coefficients as a table; otherwise its one-line description."""
    if isinstance(spring, Mapping) and spring.get("mode") == "identified":
        rows = tuple((name, c.get("value"), c.get("std")) for name, c in (spring.get("coefficients") or {}).items())
        return (Text((f"Spring on joint {spring.get('joint')}, identified ({spring.get('model')}); grouped with "
                      f"the rigid-body parameters: {', '.join(spring.get('grouped') or []) or 'none'}.",)),
                Table("spring", "Spring coefficients", (Column("coefficient", text=True), Column("value"),
                                                         Column("σ", digits=3)), rows))
    return (Text((text.splitlines()[0],)),) if text else ()


def _subtitle(record: Mapping[str, Any]) -> str:
    model = record.get("model") or {}
    return (f"rx90 identify · method {record.get('method', '')} · toolkit {model.get('toolkit_version', '')}"
            + (f" · robot file SHA-256 {str(model.get('robot_file_sha256'))[:12]}…" if model.get("robot_file_sha256")
               else ""))


def choice_blocks(record: Mapping[str, Any]) -> tuple:
    """The cross-validated choices of the fit file's ``processing_choice``: the candidate processings
    and, where chosen, the friction forms, each with its held-back errors per joint and the reason."""
    choice = record.get("processing_choice") or {}
    blocks: list = []
    for key, title, first in ((None, "Processing candidates", "cut-off [Hz]"), ("friction", "Friction forms", "form")):
        part = (choice.get(key) if key else choice) or {}
        # The friction's joint-combined candidate (the per-joint forms scored together) is a row too.
        candidates = [*(part.get("candidates") or []), *([part["combined"]] if key and part.get("combined") else [])]
        if not candidates:  # not cross-validated (a recording too short for the blocks): why, and the defaults used
            blocks += [Text((f"{title}: {part['table']}",))] if part.get("skipped") else []
            continue
        n = max(len(c.get("per_joint_pct") or []) for c in candidates)
        chosen = part.get("chosen")
        rows = tuple((_first_cell(c),
                      "none" if c.get("decimate_to_hz") is None else fmt(c.get("decimate_to_hz"), 4),
                      rest_label(c["rest"]) if c.get("rest") else "no threshold",
                      c.get("score_pct"), *(list(c.get("per_joint_pct") or []) + [None] * n)[:n],
                      "chosen" if _is_chosen(c, chosen) else ("" if key else c.get("label") or ""))
                     for c in candidates)
        columns = (Column(first, text=True), Column("decimated to", "Hz", text=True), Column("rest", text=True),
                   Column("held-back error", "%", digits=3), *(Column(f"j{j + 1}", "%", digits=3) for j in range(n)),
                   Column("", text=True))
        blocks += [Table(f"choice-{key or 'processing'}", f"{title}: {choice.get('blocks', part.get('blocks', ''))}-block "
                         f"cross-validation inside the fitted data", columns, rows), Text((str(part.get("reason", "")),))]
    return tuple(blocks)


def _first_cell(candidate: Mapping[str, Any]) -> str:
    """A processing candidate's cut-off [Hz], or a friction form ("per joint": the forms scored
    together, named in the reason below the table and in the processing record)."""
    form = candidate.get("form")
    if form is None:
        return fmt(candidate.get("cutoff_hz"), 4)
    return form if isinstance(form, str) else "per joint"


def _is_chosen(candidate: Mapping[str, Any], chosen: Any) -> bool:
    if isinstance(chosen, Mapping):  # the processing: the chosen candidate's record
        return all(candidate.get(k) == chosen.get(k) for k in ("cutoff_hz", "decimate_to_hz", "rest"))
    return candidate.get("form") == chosen  # the friction: the chosen form's name (or list)


def processing_table(record: Mapping[str, Any]) -> Any:
    """The processing record (model) as settings with units; absent values named, not 'None'."""
    m = record.get("model") or {}
    boot = record.get("bootstrap") or {}
    items = [("Robot file", "", m.get("robot_file") or "bundled"),
             ("Angle convention of the files", "", m.get("convention") or "the file's own (default: controller)"),
             ("Friction: coupled Coulomb form", "", m.get("coulomb_sign") or "not coupled"),
             ("Friction form per joint", "", _friction_text(m.get("friction"))),
             ("Torque offsets", "", "every joint (robot option)" if m.get("offsets") else
              "joints " + ", ".join(map(str, m["offset_joints"])) + " (cross-validated)" if m.get("offset_joints")
              else "none"),
             ("Spring", "", m.get("spring") or "none"),
             ("Rest threshold", "rad/s", m.get("min_velocity") if m.get("min_velocity") is not None else "off"),
             ("Rest samples", "", rest_label(m["rest"]) if m.get("rest") else "–"),
             ("Cut-off", "Hz", m.get("cutoff_hz")),
             ("Decimated to", "Hz", m.get("decimate_to_hz") if m.get("decimate_to_hz") else "no decimation"),
             ("Rate after filtering", "Hz", m.get("rate_hz")),
             ("Torque delay compensated", "ms", 1e3 * (number(m.get("delay_s")) or 0.0)),
             ("Torque delay estimated", "ms", None if record.get("delay_estimate_s") is None
              else 1e3 * record["delay_estimate_s"]),
             ("Drive gains", "", "given (section Drive gains used)" if m.get("gains") else "torques recorded"),
             ("Bootstrap", "", f"{boot.get('draws', '–')} draws of {fmt(boot.get('block_s'), 3)} s blocks, "
                               f"seed {boot.get('seed', '–')}" if boot else "not run"),
             ("Equations", "", record.get("rows"))]
    return key_values("processing", "How the data were processed (stored in the JSON's model record)", items)


def _friction_text(friction: Mapping[str, Any] | None) -> str:
    """The fit file's ``model.friction``: the form (one or per joint) and the velocity scales [rad/s]."""
    if not friction:
        return "coulomb (sign of the speed)"
    form = friction.get("form")
    text = ", ".join(form) if isinstance(form, list) else str(form)
    scales = friction.get("velocity_scale")
    if scales:
        text += "; velocity scales " + ", ".join("–" if v is None else fmt(v, 3) for v in scales) + " rad/s"
    return text

