"""``rx90 gains``: drive gains from current recordings and a payload of known mass."""
from __future__ import annotations

import argparse
import dataclasses
import math
from typing import TYPE_CHECKING, Any

from identify.gains.defaults import DEFAULT_METHOD, FLAG_PCT, GAIN_METHODS
from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.signal.defaults import POSITION_TOLERANCE

from ..flags import checked_peaks, flag_lines, settle
from ..common import UsageError, check_output, convention_option, load_robot, progress, robot_option
from .identify_runs import add_block_option

if TYPE_CHECKING:  # annotations only: the method is imported when the command runs
    import numpy as np

    from identify.fitting.plausibility import Flag


def register(sub: Any) -> None:
    desc = ("drive gains (N·m/A) from motor-current recordings run empty and with a payload of known "
            "mass: same-motion (eq. 28: the same trajectory empty and loaded, paired in time) or "
            "global (eq. 29: any motions; the robot's base parameters and current offsets solved too)")
    sp = sub.add_parser("gains", help="drive gains from currents and a payload of known mass", description=desc)
    sp.set_defaults(func=run)
    robot_option(sp, None, "the robot the recordings' '# robot:' line names")
    sp.add_argument("--empty", nargs="+", required=True, help="current recordings without the payload")
    sp.add_argument("--loaded", nargs="+", required=True, help="current recordings with the payload")
    sp.add_argument("--mass", type=float, required=True, help="the payload's weighed mass [kg]")
    sp.add_argument("--mass-std", type=float, default=0.0, help="standard deviation of the weighing [kg] (default 0)")
    sp.add_argument("--method", choices=GAIN_METHODS, default=DEFAULT_METHOD,
                    help=f"default {DEFAULT_METHOD} (chosen on the UR10e pair: docs/drive-gains.md)")
    sp.add_argument("--fix", nargs="+", default=[], metavar="J=VALUE",
                    help="set gain J from a datasheet instead of identifying it [N·m/A]")
    sp.add_argument("--side", choices=("motor", "joint"),
                    help="gains on the motor side (tau = Rt diag(k) i) or the joint side "
                         "(default: motor for a coupled wrist, else joint)")
    sp.add_argument("--no-offsets", action="store_true", help="global: no current offsets (default: identified)")
    sp.add_argument("--no-compare", action="store_true",
                    help="do not run the other method too (default: both methods run when the runs allow it, "
                         "with a per-joint verdict: agree within 2 σ or not)")
    sp.add_argument("--flag-pct", type=float, default=FLAG_PCT,
                    help=f"flag a gain whose relative σ exceeds this [%%] (default {FLAG_PCT:g})")
    sp.add_argument("--position-tol", type=float, default=POSITION_TOLERANCE,
                    help=f"same-motion: largest position gap of paired runs [rad] (default {POSITION_TOLERANCE:g})")
    sp.add_argument("--gains", help="reference gains (K1,...,Kn or a gains JSON) printed beside the result")
    convention_option(sp)
    sp.add_argument("--cutoff", type=float, help="Butterworth cut-off for q [Hz] (default: chosen from the data)")
    sp.add_argument("--decimate-to", type=float, default=DEFAULT_DECIMATE_TO,
                    help=f"rate after parallel filtering [Hz] (default {DEFAULT_DECIMATE_TO:g})")
    add_block_option(sp)
    sp.add_argument("--json", help="the gains as JSON (read by --gains of every command)")
    sp.add_argument("--report", help="self-contained HTML report")


def parse_fix(items: list[str], n: int) -> dict[int, float]:
    """``["1=10.0", ...]`` -> {1: 10.0}; joint numbers 1..n."""
    out: dict[int, float] = {}
    for item in items:
        joint, sep, value = item.partition("=")
        try:
            j, v = int(joint), float(value)
        except ValueError:
            raise UsageError(f"--fix: expected J=VALUE (e.g. 1=10.0), got {item!r}") from None
        if not sep or not (1 <= j <= n) or not math.isfinite(v) or v == 0:
            raise UsageError(f"--fix {item}: joint must be 1..{n} and the gain a finite non-zero number")
        if j in out:
            raise UsageError(f"--fix: joint {j} given twice")
        out[j] = v
    return out


def run(args: argparse.Namespace) -> int:
    from rx90sym.files import file_sha256, write_json
    from identify.fitting.plausibility import PlausibilityError, gain_flags
    from identify.gains.drive_gains import drive_gains
    from identify.io.blocks import block_source
    from identify.io.gains import read_gains

    if args.method == "same-motion" and args.no_offsets and args.no_compare:
        raise UsageError("conflicting options: --no-offsets is for --method global (offsets cancel in same-motion; "
                         "without --no-compare it applies to the global run of the comparison)")
    if args.method == "global" and args.position_tol != POSITION_TOLERANCE and args.no_compare:
        raise UsageError("conflicting options: --position-tol is for --method same-motion (global pairs no runs; "
                         "without --no-compare it applies to the same-motion run of the comparison)")
    check_output(args.json)
    check_output(args.report)
    robot = load_robot(args, recordings=args.empty + args.loaded)
    fix = parse_fix(args.fix, robot.n)
    reference = read_gains(args.gains, robot) if args.gains else None
    progress(f"checking {len(args.empty)} empty and {len(args.loaded)} loaded recording(s) block by block "
             f"({args.block} samples per block)")
    sources = [block_source(p, robot, args.convention) for p in args.empty + args.loaded]
    checked_peaks(sources, robot, args.block, torques=lambda rec: None)
    empty, loaded = list(args.empty), list(args.loaded)
    progress(f"identifying the drive gains ({args.method}) block by block")
    options = dict(fix=fix, mass_std=args.mass_std, side=args.side, offsets=not args.no_offsets,
                   flag_pct=args.flag_pct, position_tol=args.position_tol, cutoff=args.cutoff,
                   decimate_to=args.decimate_to, convention=args.convention, block=args.block)
    try:
        res = drive_gains(robot, empty, loaded, args.mass, method=args.method, **options)
    except PlausibilityError as exc:
        settle(exc.flags)  # the same errors, with the options that address them
        raise
    comparison = None if args.no_compare else _compare(res, robot, empty, loaded, args.mass, options)
    flags = settle(_torque_scale(res.gains, robot, sources, args.block)
                   + gain_flags(res.gains.gains, res.gains.std, res.fixed, res.rel_std_pct, res.flag_pct))
    print(res.table())
    if flags:
        print(flag_lines(flags))
    print(comparison.table() if hasattr(comparison, "table") else
          "methods not compared (--no-compare)" if comparison is None else comparison["line"])
    if reference is not None:
        print(_comparison(res.gains.gains, reference, res.gains.side))
    # The runs the gains were fitted on: a payload identified on the same runs with these gains
    # returns the mass the gains were scaled to (rx90 payload warns: not an independent check).
    fitted_on = [{"role": role, "source": p, "sha256": file_sha256(p)}
                 for role, runs in (("empty", empty), ("loaded", loaded)) for p in runs]
    if args.json:
        compared = (comparison.to_dict() if hasattr(comparison, "to_dict") else
                    None if comparison is None else {k: v for k, v in comparison.items() if k != "line"})
        write_json(args.json, {**res.to_dict(), "fitted_on": fitted_on, "flags": [f.to_json() for f in flags],
                               "comparison": compared})
    if args.report:
        from ..report.writers import write_gains_report

        write_gains_report(args.report, {**res.to_dict(), "flags": [f.to_json() for f in flags],
                                         "data": {"empty": empty, "loaded": loaded}})
    return 0


def _compare(res: Any, robot: Any, empty: list, loaded: list, mass: float, options: dict) -> Any:
    """The other method on the same runs and the per-joint verdict (identify.gains.methods), or,
    when the runs do not allow it, a dict naming the method and why (its ``line`` printed)."""
    from identify.gains.drive_gains import drive_gains
    from identify.gains.methods import compare_methods

    other = "global" if res.method == "same-motion" else "same-motion"
    progress(f"identifying the drive gains ({other}) to compare the methods (--no-compare to skip)")
    try:
        res_other = drive_gains(robot, empty, loaded, mass, method=other, **options)
    except ValueError as exc:  # the runs do not allow it (another motion, a gain not identified): say why
        reason = str(exc).splitlines()[0]
        return {"methods": [res.method, other], "not_compared": reason,
                "line": f"methods not compared: {other} refused the runs: {reason}"}
    return compare_methods(res, res_other)


def _torque_scale(gains: Any, robot: Any, sources: list, block: int) -> list[Flag]:
    """The torque-scale check identify and payload apply, on the torques the fitted gains make of
    the recordings' currents (read block by block): gains scale with --mass, so a mass in g gives
    torques 1000x too large."""
    from identify.fitting.plausibility import torque_scale_flags

    torques = checked_peaks(sources, robot, block, units=False,
                            torques=lambda rec: None if rec.current is None else gains.torques(robot, rec.current))
    return [dataclasses.replace(f, code="gains_scale", action="is --mass in g instead of kg? (the fitted gains "
                                "scale with it)")
            for f in torque_scale_flags(torques, robot, "torques the fitted gains give")]


def _comparison(gains: np.ndarray, reference: Any, side: str) -> str:
    if reference.side != side:
        raise UsageError(f"--gains {reference.source}: {reference.side}-side gains, the result is {side}-side")
    lines = [f"reference gains ({reference.source}): identified / reference"]
    lines += [f"{j:5d} {r:10.5g} {k / r:8.4f}" for j, (k, r) in enumerate(zip(gains, reference.gains), start=1)]
    return "\n".join(lines)
