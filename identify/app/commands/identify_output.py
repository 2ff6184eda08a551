"""What ``rx90 identify`` prints and writes besides the fit file: the fit's tables and notes, the
spring's summary, and the HTML report (the recordings read again block by block for its figures)."""
from __future__ import annotations

from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

from ..common import progress
from ..flags import flag_lines

if TYPE_CHECKING:  # annotations only
    from identify.fitting.fit_result import Fit


def split_text(lay: dict) -> str:
    """Where a recording's log was split into segments (``lay``: its layout_summary), or nothing."""
    splits, total = lay.get("split_gaps") or [], lay.get("split_gaps_total")
    where = ", ".join(f"lines {g['lines'][0]}-{g['lines'][1]} ({g['duration_s']:g} s)" for g in splits)
    more = f" and {total - len(splits)} more" if splits and total > len(splits) else ""
    return f" (split by the gap{'s' if total > 1 else ''} at {where}{more})" if splits else ""


def print_choices(f: Fit) -> None:
    """What the fit chose, on stdout (before any refusal): the processing's candidate table (or why
    there is none) and the prior weight's."""
    from identify.observation.processing import rest_label

    if f.choice is not None:
        print(f.choice["table"])
    else:
        p = f.processing
        why = f"--cutoff {p.cutoff:g} given" if p.cutoff is not None else "--no-cross-validate"
        print(f"processing not cross-validated ({why}): rest policy {rest_label(f.rest)}")
    choice = ((f.identified.prior or {}).get("choice") if f.identified is not None else None)
    if choice is not None:
        print(choice["table"])


def print_fit(f: Fit, recs: list, auto_delay: bool) -> None:
    """The fit on stdout (the chosen processing, the estimates, their bootstrap, the identified model
    and its prior's weight, flags, spring, essential parameters, validation); the delay and the
    observation's summary on stderr."""
    from identify.observation.processing import rest_label

    obs, res = f.observation or f.passes, f.result
    progress(f.delay_estimate.summary() + ("" if auto_delay or not f.delay_estimate.found
                                           else " (not compensated: --delay auto does)"))
    progress(obs.summary().replace("\n", "\n  "))
    for lay in f.recordings:
        if lay["bridged_samples"] or lay["segments"] > 1 or lay["stale_rows"]:
            print(f"{lay['source']}: {lay['segments']} segment(s){split_text(lay)}, {lay['bridged_samples']} samples "
                  f"bridged over lost packets (not fitted), {lay['stale_rows'] or 0} stale rows dropped when read")
    if f.model.friction is not None and "velocity_scale" in f.model.friction:
        from identify.friction.scales import VelocityScales

        print(VelocityScales.from_json(f.model.friction).summary())
    if f.model.friction is not None and "presliding_travel" in f.model.friction:
        print("presliding travel [mrad] per joint, chosen on the fit's cost: "
              + " ".join("-" if d is None else f"{1e3 * d:g}" for d in f.model.friction["presliding_travel"]))
    print(f"filtering: cut-off {f.cutoff:.4g} Hz, rate {f.model.rate_hz:.6g} Hz"
          + (f" (decimated to {f.decimate_to:g} Hz)" if f.decimate_to else " (no decimation)")
          + f", torque delay {1e3 * f.delay:.3g} ms compensated")
    for note in obs.notes:
        if note:
            print(f"note: {note}")
    print(res.table())
    if res.method == "consistent":
        print("segment bootstrap of the least-squares estimate (the data's spread, not the model's):")
    print(f.bootstrap.table(res))
    if f.identified is not None:
        print_model(f)
    if f.flags:
        print(flag_lines(f.flags))
    print(f"\n{spring_text(f, recs)}")
    if f.essential is not None:
        print()
        print(f.essential.table())
    if f.validation is not None:
        print()
        print(f.validation.table())
    if f.validation is not None and f.result_validation is not None:
        print(estimates_lines(f.validation, f.result_validation))


def estimates_lines(model: Any, estimates: Any) -> str:
    """The held-out RMS per joint of the fit's (W)LS estimates beside the identified model's [N m]."""
    lines = ["held out, the paper's estimates beside the identified model (RMS [N m], all samples | while moving):",
             "joint  estimates      model  model/est  |  estimates      model  model/est"]
    moving = [v if v is not None else u for v, u in ((estimates.rms_error_moving, estimates.rms_error),
                                                      (model.rms_error_moving, model.rms_error))]
    for j in range(len(model.rms_error)):
        a, b, c, d = estimates.rms_error[j], model.rms_error[j], moving[0][j], moving[1][j]
        lines.append(f"{j + 1:5d}  {a:9.3f}  {b:9.3f}  {b / a if a else float('nan'):9.3f}  |  "
                     f"{c:9.3f}  {d:9.3f}  {d / c if c else float('nan'):9.3f}")
    return "\n".join(lines)


def print_model(f: Fit) -> None:
    """The identified model: the prior weight's choice, the model's estimates with the data's share of
    each (unless they are the fit's result, printed already), its cost, its bodies beside the prior's."""
    import rx90sym

    from identify.estimation.consistency.bodies import bodies_table

    model = f.identified
    print()
    if f.result is not model:
        print(model.table())
    print(f"identified model: {model.split}; weighted RSS {model.cost_increase_pct:+.3f} % of the least squares'")
    print(bodies_table(f.robot.n, model.standard, rx90sym.nominal_parameters(f.robot) if model.prior else None))


def show_choice(choice: Any) -> None:
    """The processing choice's table on stdout (a ProcessingChoice, or the fit file's record; None: nothing):
    what ``rx90 identify`` shows before a refusal that follows the choice."""
    if choice is not None:
        print(choice.table() if hasattr(choice, "table") else choice.get("table", ""), flush=True)


def spring_text(f: Fit, recs: list) -> str:
    from identify.observation.spring_fit import BaseWithSpring, spring_summary

    # The range each joint visited: from the fit's scan (block by block), else from the recordings.
    visited = [SimpleNamespace(q=f.passes.q_range)] if f.passes is not None else recs
    return spring_summary(f.robot, f.base if isinstance(f.base, BaseWithSpring) else None, f.result, visited)[1]


def write_report(path: str, f: Fit, recordings: list, convention: str | None, block: int) -> None:
    """The HTML report from the fit file's content (what --json writes) plus the recordings' extent and
    figures: the recordings (recordings or files) read again block by block, thinned to REPORT_POINTS
    samples (positions), the predictions to as many (torques)."""
    from identify.fitting.validation import log_clock
    from identify.io.blocks import block_source

    from ..report.figures import REPORT_POINTS, thinned as shown
    from ..report.writers import write_identify_report

    sources = [block_source(r, f.robot, convention, f.gains) for r in recordings]
    samples = [lay["samples"] for lay in f.recordings] if len(f.recordings) == len(sources) else None
    thin = [src.thinned(block, -(-(n or 1) // REPORT_POINTS))
            for src, n in zip(sources, samples or [getattr(src, "n_samples", None) for src in sources])]
    clocks = [log_clock(r, src) for r, src in zip(recordings, sources)]

    record = {**f.to_json(), "data": data_record(thin, f.observation or f.passes, f.validation, samples, clocks)}
    held = shown(f.validation) if f.validation is not None else None
    write_identify_report(path, f.robot, record, f.result, thin[0], held, shown(f.predict(recordings[0])),
                          spring_text(f, thin))


def data_record(recs: list, obs: Any, validation: Any = None, samples: list[int] | None = None,
                clocks: list[float] | None = None) -> dict:
    """What was fitted: per recording its source, samples, first and last time [s] (on the log's clock:
    ``clocks`` per recording, default each recording's own), duration [s] and recorded rate [Hz]
    (1 / mean period); the share of samples where each joint moves (after filtering); the held-out
    samples' first and last time [s]. ``samples``: the recordings' sample counts when ``recs`` are
    thinned."""
    from identify.fitting.validation import log_clock

    counts = samples if samples is not None else [len(r.t) for r in recs]
    clocks = clocks if clocks is not None else [log_clock(r) for r in recs]
    # First and last times on the logs' own clocks (a recording starts at 0 s: identify.io.log_rules).
    rows = [{"source": r.source, "samples": int(k), "t_first_s": float(r.t[0]) + c, "t_last_s": float(r.t[-1]) + c,
             "duration_s": float(r.t[-1] - r.t[0]), "rate_hz": float((k - 1) / (r.t[-1] - r.t[0]))}
            for r, k, c in zip(recs, counts, clocks)]
    share = None if obs.moving_fraction is None else [float(v) for v in obs.moving_fraction]
    held = None if validation is None else {"source": validation.source,
                                            "t_first_s": float(validation.t[0]) + validation.t0_s,
                                            "t_last_s": float(validation.t[-1]) + validation.t0_s}
    return {"recordings": rows, "moving_fraction": share, "heldout": held}
