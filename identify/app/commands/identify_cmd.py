"""``rx90 identify``: base parameters from recordings (WLS, OLS or consistent), validation, report.

One filtering for fit and validation: the cut-off and decimation chosen on the fitted recordings
are printed, stored in the JSON (``cutoff_hz``, ``decimate_to_hz``, and the whole ``model``
record) and reused for ``--validate`` (and by ``rx90 predict``).
"""
from __future__ import annotations

import argparse
from typing import Any

import numpy as np

import rx90sym
from rx90sym.files import write_json
from identify import essential_parameters, predict, read_recording, validate
from identify.estimation.bootstrap import segment_bootstrap_std
from identify.fit_model import FitModel
from identify.io.gains import apply_gains, read_gains
from identify.io.recordings import layout_summary
from identify.observation.matrix import DEFAULT_MIN_VELOCITY, DEFAULT_REST, REST_POLICIES
from identify.real_fit import fit_recordings

from ..common import (UsageError, check_output, convention_option, progress, robot_option, robot_with_spring,
                      spring_options)
from ..spring_output import attach_spring, spring_summary

#: Segment-bootstrap block length, s, and number of draws.
BOOTSTRAP_BLOCK_S = 0.5
BOOTSTRAP_DRAWS = 200


def _delay(text: str) -> str | float:
    if text == "auto":
        return text
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--delay takes 'auto' or a number of seconds, got {text!r}") from None
    if not np.isfinite(value) or abs(value) > 1.0:
        raise argparse.ArgumentTypeError(f"--delay must be a finite number of seconds within ±1, got {text!r}")
    return value


def add_recording_options(sp: argparse.ArgumentParser) -> None:
    """--convention and --gains: how the files are read (shared with ``predict``)."""
    convention_option(sp)
    sp.add_argument("--gains", help="drive gains for current recordings: K1,...,Kn [N m/A, joint side] "
                                    "or the JSON of rx90 gains")


def read_recordings(paths: list[str], robot: rx90sym.Robot, convention: str | None, gains: Any) -> list:
    recs = [read_recording(p, robot, convention=convention) for p in paths]
    if gains is None:
        return recs
    return [apply_gains(r, gains, robot) if r.current is not None else r for r in recs]


def register(sub: Any) -> None:
    sp = sub.add_parser("identify", help="identify the base parameters from recordings",
                        description="identify the base parameters from recordings")
    sp.set_defaults(func=run)
    sp.add_argument("recordings", nargs="+", help="recording CSV files")
    robot_option(sp)
    add_recording_options(sp)
    spring_options(sp)
    sp.add_argument("--offsets", action="store_true", help="add per-joint torque offsets OFF1..OFFn")
    sp.add_argument("--coulomb-sign", choices=("paper", "motor"),
                    help="Coulomb form of the coupled wrist for this run (default: the robot file's)")
    sp.add_argument("--asymmetric-coulomb", metavar="JOINTS",
                    help="FS+ / FS- instead of FS on these joints: 'all', 'none' or e.g. 1,2,3 "
                         "(default: the robot file's [friction]); not with --offsets (collinear)")
    sp.add_argument("--method", choices=("ols", "wls", "consistent"), default="wls")
    sp.add_argument("--essential", action="store_true", help="also compute the essential parameters")
    sp.add_argument("--cutoff", type=float, help="Butterworth cut-off for q [Hz] (default: chosen from the data)")
    sp.add_argument("--decimate-to", type=float, default=50.0,
                    help="rate after parallel filtering [Hz] (default 50; 0: no decimation)")
    sp.add_argument("--no-decimate", action="store_true", help="no decimation (same as --decimate-to 0)")
    sp.add_argument("--min-velocity", type=float, default=DEFAULT_MIN_VELOCITY,
                    help=f"rest threshold: a joint slower than this is at rest [rad/s] "
                         f"(default {DEFAULT_MIN_VELOCITY:g}; 0: no rest handling)")
    sp.add_argument("--rest", choices=REST_POLICIES, default=DEFAULT_REST,
                    help=f"rest samples: drop their rows, keep them with Coulomb = 0, or with the presliding state "
                         f"of the position history (default {DEFAULT_REST})")
    sp.add_argument("--delay", type=_delay, default=0.0,
                    help="torque lag behind the positions: 'auto' (estimated) or seconds (default 0; "
                         "the estimate is always reported)")
    sp.add_argument("--bootstrap-seed", type=int, default=0, help="seed of the segment bootstrap (default 0)")
    sp.add_argument("--validate", help="recording used for cross-validation only")
    sp.add_argument("--json", help="results as JSON")
    sp.add_argument("--report", help="self-contained HTML report")
    sp.add_argument("--urdf-out", help="with --method consistent and a URDF robot: the URDF with the "
                                       "identified inertials (and FILE.actuation.json: IA, FS, FV)")


def _robot(args: argparse.Namespace) -> tuple[rx90sym.Robot, Any]:
    robot, spring_model = robot_with_spring(args)
    if args.coulomb_sign is not None:
        if robot.coupling is None:
            raise UsageError(f"--coulomb-sign: robot {robot.name!r} has no coupled joints")
        robot = robot.with_options(coupling=rx90sym.Coupling(robot.coupling.joints, args.coulomb_sign))
    if args.asymmetric_coulomb is not None:
        robot = with_asymmetric_coulomb(robot, args.asymmetric_coulomb)
    return robot, spring_model


def with_asymmetric_coulomb(robot: rx90sym.Robot, spec: str) -> rx90sym.Robot:
    """The robot with FS+ / FS- on the joints of ``spec`` ('all', 'none' or '1,2,...')."""
    text = spec.strip().lower()
    if text == "all":
        joints = tuple(range(robot.n))
    elif text == "none":
        joints = ()
    else:
        try:
            joints = tuple(int(c) - 1 for c in text.split(","))
        except ValueError:
            raise UsageError(f"--asymmetric-coulomb: expected 'all', 'none' or joint numbers like 1,2,3, "
                             f"got {spec!r}") from None
    try:
        return robot.with_options(asymmetric_coulomb=joints)
    except ValueError as exc:
        raise UsageError(f"--asymmetric-coulomb: {exc}") from None


def run(args: argparse.Namespace) -> int:
    from ..report import Section, identification_sections, write_report

    if args.essential and args.method == "consistent":
        raise UsageError("conflicting options: --essential works on the ols/wls estimate, "
                         "not with --method consistent")
    if args.no_decimate and args.decimate_to not in (50.0, 0.0):
        raise UsageError("conflicting options: --no-decimate and --decimate-to "
                         f"{args.decimate_to:g}")
    if args.min_velocity < 0:
        raise UsageError(f"--min-velocity must be >= 0 rad/s, got {args.min_velocity:g}")
    if args.urdf_out and args.method != "consistent":
        raise UsageError("--urdf-out needs --method consistent (a URDF holds physical bodies only)")
    for out in (args.json, args.report, args.urdf_out):
        check_output(out)
    robot, spring_model = _robot(args)
    if args.urdf_out and robot.urdf is None:
        raise UsageError(f"--urdf-out needs a URDF robot (--robot FILE.urdf), not {args.robot!r}")
    sb = attach_spring(robot, spring_model, args.validate, args.method)
    gains = read_gains(args.gains, robot) if args.gains else None
    progress(f"reading {len(args.recordings)} recording(s)")
    recs = read_recordings(args.recordings, robot, args.convention, gains)
    val_rec = read_recordings([args.validate], robot, args.convention, gains)[0] if args.validate else None
    decimate_to = None if (args.no_decimate or args.decimate_to == 0) else args.decimate_to
    min_velocity = args.min_velocity or None
    base = sb if sb is not None else rx90sym.base_parameters(robot)
    layouts = [layout_summary(r) for r in recs]
    for lay in layouts:
        if lay["bridged_samples"] or lay["segments"] > 1 or lay["stale_rows"]:
            print(f"{lay['source']}: {lay['segments']} segment(s), {lay['bridged_samples']} samples bridged over lost "
                  f"packets (not fitted), {lay['stale_rows'] or 0} stale rows dropped when read")
    progress(f"identifying ({args.method}) on {sum(len(r.t) for r in recs)} samples")
    fit = fit_recordings(robot, recs, method=args.method, base=base, cutoff=args.cutoff,
                         decimate_to=decimate_to, min_velocity=min_velocity, rest=args.rest,
                         delay=args.delay, spring=sb is None, estimate=True)
    obs, res, delay, estimate = fit.observation, fit.result, fit.delay, fit.delay_estimate
    progress(estimate.summary() + ("" if args.delay == "auto" else " (not compensated: --delay auto does)"))
    progress(obs.summary().replace("\n", "\n  "))
    print(f"filtering: cut-off {obs.cutoffs[0]:.4g} Hz, rate {obs.rate:.6g} Hz"
          + (f" (decimated to {decimate_to:g} Hz)" if decimate_to else " (no decimation)")
          + f", torque delay {1e3 * delay:.3g} ms compensated")
    for note in obs.notes:
        if note:
            print(f"note: {note}")
    block = max(1, int(round(BOOTSTRAP_BLOCK_S * obs.rate)))
    boot = segment_bootstrap_std(obs.W, obs.Y, obs.joint, obs.samples, res.weights, block,
                                 BOOTSTRAP_DRAWS, args.bootstrap_seed)
    print(res.table())
    print(bootstrap_table(res, boot))
    spring_entry, spring_text = spring_summary(robot, sb, res, recs)
    print(f"\n{spring_text}")
    ess = essential_parameters(res) if args.essential else None
    if ess is not None:
        print()
        print(ess.table())
    model = FitModel.of(robot, convention=args.convention, gains=gains.to_dict() if gains else None,
                        rest=args.rest, min_velocity=min_velocity, spring=args.spring,
                        cutoff_hz=obs.cutoffs[0], decimate_to_hz=decimate_to, rate_hz=obs.rate,
                        delay_s=delay)
    filt = model.filtering()
    val = validate(robot, ess or res, val_rec, base=base, **filt) if val_rec is not None else None
    if val is not None:
        print()
        print(val.table())
    if args.json:
        out = {"robot": robot.name, "method": args.method, **res.to_dict(), "spring": spring_entry,
               "bootstrap_std": [float(v) for v in boot],
               "bootstrap": {"block_s": block / obs.rate, "draws": BOOTSTRAP_DRAWS, "seed": args.bootstrap_seed},
               "cutoff_hz": obs.cutoffs[0], "decimate_to_hz": decimate_to,
               "delay_estimate_s": estimate.delay, "model": model.to_dict(),
               "essential": ess.to_dict() if ess is not None else {}, "recordings": layouts,
               "validation": val.to_dict() if val is not None else {}}
        write_json(args.json, out)
    if args.report:
        sections = identification_sections(robot, res, recs, validation=val, essential=ess,
                                           fit_prediction=predict(robot, res, recs[0], base=base, **filt),
                                           model=model, extra_tables=[bootstrap_table(res, boot)])
        write_report(args.report, f"Identification of {robot.name}", [*sections, Section("Spring", spring_text)])
    if args.urdf_out:  # last: a refused (non-physical) link must not cost the fit's JSON and report
        from rx90sym import UrdfError, write_urdf

        try:
            written = write_urdf(robot, res.standard, args.urdf_out)
        except UrdfError as exc:
            kept = [p for p in (args.json, args.report) if p]
            raise UrdfError(f"{args.urdf_out} not written: {exc}" +
                            (f" (written: {', '.join(kept)})" if kept else "")) from None
        progress("wrote " + ", ".join(str(p) for p in written))
    return 0


def bootstrap_table(res: Any, boot: np.ndarray) -> str:
    """σ of eq. 13 (white residuals) beside the segment-bootstrap σ, per parameter."""
    width = max([len("Parameter")] + [len(n) for n in res.names])
    lines = [f"{'Parameter':<{width}}  {'σ eq. 13':>10}  {'σ bootstrap':>11}  ratio"]
    for n, s, b in zip(res.names, res.std, boot):
        ratio = b / s if s > 0 else float("nan")
        lines.append(f"{n:<{width}}  {s:10.3g}  {b:11.3g}  {ratio:5.2f}")
    return "\n".join(lines)
