"""What ``rx90 identify`` prints and writes besides the fit file: the fit's tables and notes, the
spring's summary, and the HTML report (of a fit of whole recordings, or of one made block by block)."""
from __future__ import annotations

import argparse
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

from ..common import progress
from ..flags import flag_lines

if TYPE_CHECKING:  # annotations only
    from identify.fitting.record import Fit


def split_text(lay: dict) -> str:
    """Where a recording's log was split into segments (``lay``: its layout_summary), or nothing."""
    splits, total = lay.get("split_gaps") or [], lay.get("split_gaps_total")
    where = ", ".join(f"lines {g['lines'][0]}-{g['lines'][1]} ({g['duration_s']:g} s)" for g in splits)
    more = f" and {total - len(splits)} more" if splits and total > len(splits) else ""
    return f" (split by the gap{'s' if total > 1 else ''} at {where}{more})" if splits else ""


def print_fit(f: Fit, recs: list, auto_delay: bool, prior: Any = None) -> None:
    """The fit on stdout (the chosen processing, the estimates, their bootstrap, flags, spring,
    essential parameters, validation); the delay and the observation's summary on stderr."""
    from identify.observation.processing import rest_label

    obs, res = f.observation or f.streamed, f.result
    progress(f.delay_estimate.summary() + ("" if auto_delay else " (not compensated: --delay auto does)"))
    progress(obs.summary().replace("\n", "\n  "))
    for lay in f.recordings:
        if lay["bridged_samples"] or lay["segments"] > 1 or lay["stale_rows"]:
            print(f"{lay['source']}: {lay['segments']} segment(s){split_text(lay)}, {lay['bridged_samples']} samples "
                  f"bridged over lost packets (not fitted), {lay['stale_rows'] or 0} stale rows dropped when read")
    if f.choice is not None:
        print(f.choice["table"])
    else:
        p = f.processing
        why = f"--cutoff {p.cutoff:g} given" if p.cutoff is not None else "--no-cross-validate"
        print(f"processing not cross-validated ({why}): rest policy {rest_label(f.rest)}")
    if f.model.friction is not None and "velocity_scale" in f.model.friction:
        from identify.estimation.separable import VelocityScales

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
        print("segment bootstrap of the unconstrained WLS estimate (the data's spread, not the consistent one's):")
    print(f.bootstrap.table(res))
    if res.method == "consistent":
        from identify.estimation.consistency.prior import bodies_table

        print(f"\nsplit of the standard parameters: {res.split}")
        print(f"weighted RSS {res.cost:.6g} vs WLS {res.wls_cost:.6g} ({res.cost_increase_pct:+.3f} %)")
        print(bodies_table(f.robot.n, res.standard, prior))
    if f.flags:
        print(flag_lines(f.flags))
    print(f"\n{spring_text(f, recs)}")
    if f.essential is not None:
        print()
        print(f.essential.table())
    if f.validation is not None:
        print()
        print(f.validation.table())


def spring_text(f: Fit, recs: list) -> str:
    from identify.observation.spring_fit import BaseWithSpring, spring_summary

    visited = recs or [SimpleNamespace(q=f.streamed.q_range)]  # a long log: its range, from the scan
    return spring_summary(f.robot, f.base if isinstance(f.base, BaseWithSpring) else None, f.result, visited)[1]


def write_report(path: str, f: Fit, recs: list) -> None:
    """The HTML report from the fit file's content (what --json writes) plus the recordings' extent."""
    from ..report.writers import write_identify_report

    record = {**f.to_json(), "data": data_record(recs, f.observation, f.validation)}
    write_identify_report(path, f.robot, record, f.result, recs[0], f.validation, f.predict(recs[0]),
                          spring_text(f, recs))


#: Points of a long log's figures: its positions and torques are thinned to at most this many.
REPORT_POINTS = 20_000


def write_long_report(args: argparse.Namespace, f: Fit) -> None:
    """The HTML report of a fit made block by block: the figures from the recordings read again block by
    block and thinned to REPORT_POINTS samples (positions) and decimated samples (torques)."""
    from dataclasses import replace

    from identify.io.blocks import block_source

    from ..report.writers import write_identify_report

    progress(f"report: reading {args.recordings[0]} again block by block for the figures")
    samples = [lay["samples"] for lay in f.recordings]
    thin = [block_source(path, f.robot, args.convention, f.gains).thinned(args.block, -(-n // REPORT_POINTS))
            for path, n in zip(args.recordings, samples)]

    def shown(v: Any) -> Any:  # the torques of the figures: every k-th decimated sample
        every = slice(None, None, -(-v.t.size // REPORT_POINTS))
        return replace(v, t=v.t[every], measured=v.measured[every], predicted=v.predicted[every],
                       moving=v.moving[every])

    record = {**f.to_json(), "data": data_record(thin, f.streamed, f.validation, samples)}
    held = shown(f.validation) if f.validation is not None else None
    write_identify_report(args.report, f.robot, record, f.result, thin[0], held, shown(f.predict(args.recordings[0])),
                          spring_text(f, []))


def data_record(recs: list, obs: Any, validation: Any = None, samples: list[int] | None = None) -> dict:
    """What was fitted: per recording its source, samples, first and last time [s], duration [s] and
    recorded rate [Hz] (1 / mean period); the share of samples where each joint moves (after
    filtering); the held-out samples' first and last time [s]. ``samples``: the recordings' sample
    counts when ``recs`` are thinned (a long log)."""
    from identify.fitting.validation import log_clock

    counts = samples if samples is not None else [len(r.t) for r in recs]
    # First and last times on the logs' own clocks (a recording starts at 0 s: identify.io.logs).
    rows = [{"source": src, "samples": int(k), "t_first_s": float(r.t[0]) + log_clock(r),
             "t_last_s": float(r.t[-1]) + log_clock(r),
             "duration_s": float(r.t[-1] - r.t[0]), "rate_hz": float((k - 1) / (r.t[-1] - r.t[0]))}
            for r, src, k in zip(recs, obs.sources, counts)]
    share = None if obs.moving_fraction is None else [float(v) for v in obs.moving_fraction]
    held = None if validation is None else {"source": validation.source,
                                            "t_first_s": float(validation.t[0]) + validation.t0_s,
                                            "t_last_s": float(validation.t[-1]) + validation.t0_s}
    return {"recordings": rows, "moving_fraction": share, "heldout": held}
