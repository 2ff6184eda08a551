"""``rx90 monitor``: contact events on a recording with the momentum observer of an identification.

Imports nothing heavy at import time (NumPy, SciPy, CasADi and the model load when it runs).
"""
from __future__ import annotations

import argparse
from typing import Any


def register(sub: Any) -> None:
    from identify.monitor.defaults import DEFAULT_GAIN, DEFAULT_MONITOR_BLOCK  # standard library only

    sp = sub.add_parser("monitor", help="contact events and external torques on a recording (momentum observer)",
                        description="run the generalised-momentum observer of an identification over a recording: "
                                    "contact events (start, end, joints, peak external torque), residual CSV, report "
                                    "(docs/contact-monitor.md)")
    sp.set_defaults(func=run)
    sp.add_argument("recording", help="recording (CSV or NPZ of the toolkit; ROS bags and raw logs through rx90 convert)")
    sp.add_argument("--identification", required=True, help="JSON written by rx90 identify --json")
    sp.add_argument("--json", help="events JSON: events (start_s, end_s, joints 1-based, peak_nm), thresholds_nm, "
                                   "gain, fit_sha256")
    sp.add_argument("--out", help="residual CSV: t [s from the first sample], r1..rn, threshold1..n [N·m], contact")
    sp.add_argument("--report", help="HTML report: residuals against thresholds, events shaded")
    sp.add_argument("--calibrate", action="append", metavar="CONTACT_FREE",
                    help="contact-free recording(s) to compute the thresholds on (repeatable); needed when the "
                         "identification has no contact_thresholds_nm")
    sp.add_argument("--threshold", help="T or T1,..,Tn [N·m]: thresholds (override the file's and --calibrate)")
    sp.add_argument("--gain", help=f"K or K1,..,Kn [rad/s]: observer gain (default {DEFAULT_GAIN:g} on every joint)")
    sp.add_argument("--convention", choices=("controller", "model", "staubli", "khalil"), default=None,
                    help="joint angles of the file (default: the identification's, else the file's header)")
    sp.add_argument("--block", type=int, default=DEFAULT_MONITOR_BLOCK,
                    help=f"samples per block (default {DEFAULT_MONITOR_BLOCK})")


def _numbers(text: str | None, what: str, n: int) -> Any:
    from ..common import UsageError, floats

    if text is None:
        return None
    values = floats(text, what)
    if values.size not in (1, n):
        raise UsageError(f"{what}: expected 1 or {n} numbers, got {values.size}")
    if (values <= 0).any():
        raise UsageError(f"{what}: values must be positive, got {text!r}")
    return values


def run(args: argparse.Namespace) -> int:
    import hashlib
    from dataclasses import replace
    from pathlib import Path

    from rx90sym.files import write_json

    from identify import load_fit
    from identify.monitor.defaults import DEFAULT_GAIN
    from identify.monitor.log import MonitorInputError, calibrate, check_fit, monitor_log

    from ..common import UsageError, check_output, progress

    for out in (args.out, args.json, args.report):
        check_output(out)
    block = args.block
    if block < 3:
        raise UsageError(f"--block must be at least 3 samples, got {block}")
    f = load_fit(args.identification)
    if args.convention:
        f = replace(f, model=replace(f.model, convention=args.convention))
    n = f.robot.n
    check_fit(f)
    gain = _numbers(args.gain, "--gain", n)
    thresholds = _numbers(args.threshold, "--threshold", n)
    source = "--threshold"
    if thresholds is None and args.calibrate:
        thresholds = calibrate(f, args.calibrate, gain, block=block)
        source = "--calibrate " + ", ".join(Path(p).name for p in args.calibrate)
        progress("thresholds calibrated: " + " ".join(f"{v:.3g}" for v in thresholds) + " N·m")
    elif thresholds is None:
        thresholds = getattr(f, "contact_thresholds", None)
        source = "the identification file"
        if gain is not None:
            progress(f"warning: the identification's thresholds were computed at the default gain ({DEFAULT_GAIN:g} "
                     f"rad/s); with --gain, --calibrate gives thresholds for that gain")
        if thresholds is None:
            raise MonitorInputError(f"{args.identification}: no contact thresholds (contact_thresholds_nm; a file "
                                    f"written before they were stored): give --calibrate CONTACT_FREE.csv or --threshold")
    if args.threshold and args.calibrate:
        progress("warning: --threshold given: --calibrate not used")
    res = monitor_log(f, args.recording, thresholds, gain, block=block, residual_csv=args.out,
                      envelope=bool(args.report))
    print(res.table())
    sha = hashlib.sha256(Path(args.identification).read_bytes()).hexdigest()
    record = {**res.to_json(sha), "identification": str(args.identification), "thresholds_from": source}
    if args.json:
        write_json(args.json, record)
    if args.report:
        from ..report.monitor_page import write_monitor_report

        write_monitor_report(args.report, record, res.envelope)
    return 0
