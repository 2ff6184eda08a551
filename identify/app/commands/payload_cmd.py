"""``rx90 payload``: the payload's ten parameters by the paper's methods 1-4 (section IV)."""
from __future__ import annotations

import argparse
import dataclasses
from typing import TYPE_CHECKING, Any

from identify.payloads.defaults import MASS_TOL
from identify.signal.defaults import POSITION_TOLERANCE

from ..flags import checked_peaks, flag_lines, given_gain_flags, settle
from ..common import (UsageError, check_output, convention_option, load_robot, progress, robot_option,
                      robot_params, spring_notice)
from .identify_runs import add_block_option

if TYPE_CHECKING:  # annotations only: the method is imported when the command runs
    import numpy as np


METHOD_NEEDS = """what each method needs:
  1  --loaded and --robot-params (a fit of rx90 identify --json: its columns, torque offsets included,
     and its processing; or a JSON of parameter values); no --empty
  2  --empty and --loaded (any motions; the robot is identified twice, the payload solves eqs. 24-27)
  3  --empty and --loaded, the same trajectory each (paired in time: lag, common part, --position-tol)
  4  --empty and --loaded (any motions; robot and payload in one system, eq. 29)
methods 2-4 identify the robot themselves: --robot-params is refused there."""


def register(sub: Any) -> None:
    sp = sub.add_parser("payload", help="identify a payload (paper section IV, methods 1-4)",
                        description="identify a payload (paper section IV, methods 1-4)", epilog=METHOD_NEEDS,
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    sp.set_defaults(func=run)
    sp.add_argument("--method", type=int, choices=(1, 2, 3, 4), required=True)
    sp.add_argument("--empty", nargs="*", default=[], help="recordings without the payload")
    sp.add_argument("--loaded", nargs="+", required=True, help="recordings with the payload")
    robot_option(sp, None, "the robot the recordings' '# robot:' line names")
    convention_option(sp)
    sp.add_argument("--robot-params", help="method 1: the robot's fit (rx90 identify --json: its columns and "
                                           "processing are used) or a JSON of its parameter values")
    sp.add_argument("--a-priori", help="bundled payload name or JSON file of a priori values")
    sp.add_argument("--mass", type=float, help="weighed mass [kg] (constrained fit)")
    sp.add_argument("--mass-tol", type=float, help=f"tolerance of the weighed mass [kg] (default {MASS_TOL:g})")
    sp.add_argument("--constrained", action="store_true", help="payload pseudo-inertia PSD (and mass)")
    sp.add_argument("--filtering-from", metavar="ID.json",
                    help="reuse the cut-off, decimation and torque delay of an identification (rx90 identify --json)")
    sp.add_argument("--offsets", action="store_true", help="add per-joint torque offsets OFF1..OFFn")
    sp.add_argument("--gains", help="drive gains for current recordings: K1,...,Kn [N m/A, joint side] "
                                    "or the JSON of rx90 gains")
    sp.add_argument("--position-tol", type=float,
                    help=f"method 3: largest position gap of a paired run [rad] (default {POSITION_TOLERANCE:g})")
    add_block_option(sp)
    sp.add_argument("--json", help="results as JSON")
    sp.add_argument("--report", help="self-contained HTML report")


def run(args: argparse.Namespace) -> int:
    from rx90sym.files import write_json
    from rx90sym.flange_payload import flange_payload
    from identify.fitting.plausibility import mass_bound_flags, payload_flags, torque_scale_flags
    from identify.io.blocks import block_source
    from identify.io.gains import read_gains
    from identify.payloads.methods import payload

    _check_options(args)
    check_output(args.json)
    check_output(args.report)
    robot = load_robot(args, offsets=args.offsets, recordings=args.empty + args.loaded)
    spring_notice(robot)
    known = _robot_params(args, robot)
    filt = _filtering(args, robot, known)
    gains = read_gains(args.gains, robot) if args.gains else getattr(known, "gains", None)
    convention = args.convention or getattr(getattr(known, "model", None), "convention", None)
    flags = given_gain_flags(gains) if args.gains else []
    sources = [block_source(p, robot, convention, gains) for p in args.empty + args.loaded]
    if gains is not None and args.gains:
        flags += settle(circular_gain_flags(gains, args.empty + args.loaded))
        if not any(s.holds_current for s in sources):
            raise UsageError(f"--gains {args.gains}: none of the recordings holds motor currents")
    progress(f"checking {len(sources)} recording(s) block by block ({args.block} samples per block)")
    flags += settle(torque_scale_flags(checked_peaks(sources, robot, args.block), robot))
    progress(f"identifying the payload (method {args.method}) block by block")
    res = payload(robot, args.method, empty=args.empty, loaded=args.loaded, robot_params=known, **filt,
                  a_priori=args.a_priori, constrained=args.constrained, mass=args.mass,
                  mass_tol=args.mass_tol if args.mass_tol is not None else MASS_TOL,
                  position_tol=args.position_tol if args.position_tol is not None else POSITION_TOLERANCE,
                  convention=convention, gains=gains, block=args.block)
    std = res.std_headline
    flags += settle(_unconstrained_mass_flags(res, std) + payload_flags(res.names, res.values, std))
    if args.constrained and args.mass is not None:
        flags += settle(mass_bound_flags(res["Mc"], args.mass, args.mass_tol if args.mass_tol is not None else MASS_TOL))
    print(res.table())
    if "Mc" in res.names:
        print(res.headline())
    if flags:
        print(flag_lines(flags))
    spring = robot.spring.describe() if robot.spring is not None else None
    record = {**res.to_dict(), "spring": spring, "flags": [f.to_json() for f in flags], "robot_name": robot.name,
              "mass": args.mass, "data": {"empty": list(args.empty), "loaded": list(args.loaded)},
              # The neutral block: mass, CoG and inertia at the CoG in the maker's flange frame (what
              # a controller takes; rx90 export --ur / --franka writes it in the controller's form).
              "flange": flange_payload(robot, res.as_dict()).to_dict()}
    if args.json:
        write_json(args.json, record)
    if args.report:
        from ..report.writers import write_payload_report

        write_payload_report(args.report, record, res)
    return 0


def _robot_params(args: argparse.Namespace, robot: Any) -> Any:
    """Method 1's --robot-params: a fit file (a Fit: its columns and processing) or parameter values."""
    import json

    from identify.fitting.fit_result import load_fit

    if not args.robot_params:
        return None
    try:
        with open(args.robot_params) as fh:
            is_fit = "model" in json.load(fh)
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"{args.robot_params}: cannot read robot parameters ({exc})") from None
    if not is_fit:
        return robot_params(args.robot_params)
    fit = load_fit(args.robot_params)
    if fit.model.robot != robot.name or fit.robot.n != robot.n:
        raise UsageError(f"--robot-params {args.robot_params}: a fit of robot {fit.model.robot!r} ({fit.robot.n} joints), "
                         f"the payload runs are of {robot.name!r} ({robot.n} joints)")
    if args.offsets:
        raise UsageError(f"conflicting options: --offsets with --robot-params {args.robot_params}: method 1 uses the "
                         f"fit's own columns, its torque offsets included")
    return fit


def _filtering(args: argparse.Namespace, robot: Any, known: Any) -> dict:
    """--filtering-from: the fit's achieved cut-off, decimation and delay (not its rest handling); with a
    fit as --robot-params, the same as that fit's or refused."""
    from identify.fitting.fit_result import Fit, load_fit

    if not args.filtering_from:
        return {}
    f = load_fit(args.filtering_from, robot).filtering()
    filt = {k: f[k] for k in ("cutoff", "decimate_to", "delay")}
    if isinstance(known, Fit):
        own = {k: known.filtering()[k] for k in filt}
        if any(not _same(filt[k], own[k]) for k in filt):
            shown = ", ".join(f"{k} {filt[k]!r} and {own[k]!r}" for k in filt if not _same(filt[k], own[k]))
            raise UsageError(f"conflicting options: --filtering-from {args.filtering_from} and --robot-params "
                             f"{args.robot_params} were processed differently ({shown}): method 1 uses the processing "
                             f"of the fit given as --robot-params; leave --filtering-from out")
        return {}
    return filt


def _same(a: Any, b: Any) -> bool:
    import math

    return a == b or (isinstance(a, float) and isinstance(b, float) and math.isclose(a, b, rel_tol=1e-12))


def _unconstrained_mass_flags(res: Any, std: np.ndarray) -> list:
    """With --constrained, the sign of the unconstrained mass (the constraints would hide swapped
    runs behind a small positive mass): its negative-mass error, named as such."""
    from identify.fitting.plausibility import payload_flags

    if not res.constrained or res.fit is None:
        return []
    free = res.fit.values[[res.fit.names.index(n) for n in res.names]]
    return [dataclasses.replace(f, message=f"{f.message.replace('the payload', 'the unconstrained payload')} "
                                f"(the constrained fit gave {res['Mc']:.4g} kg)")
            for f in payload_flags(res.names, free, std) if f.code == "payload_mass_negative"]


def _check_options(args: argparse.Namespace) -> None:
    """Refuse option combinations a method does not use (UsageError: exit 2)."""
    if args.mass_tol is not None and args.mass is None:
        raise UsageError("conflicting options: --mass-tol needs --mass")
    if args.mass is not None and not args.constrained:
        raise UsageError("conflicting options: --mass is used by the constrained fit; add --constrained")
    if args.method == 1 and not args.robot_params:
        raise UsageError("method 1 needs --robot-params FILE.json (the robot's fit, rx90 identify --json)")
    if args.method == 1 and args.empty:
        raise UsageError("conflicting options: method 1 uses --robot-params, not --empty recordings")
    if args.method != 1 and args.robot_params:
        raise UsageError(f"conflicting options: method {args.method} identifies the robot itself; "
                         "--robot-params is for method 1")
    if args.method != 3 and args.position_tol is not None:
        raise UsageError("conflicting options: --position-tol is for method 3 (paired runs)")


def circular_gain_flags(gains: Any, paths: list[str]) -> list:
    """A warning when a recording of this payload run is one the drive gains were fitted on
    (``fitted_on`` of rx90 gains --json, matched by content): the gains were scaled to the known
    mass on it, so the payload's Mc there returns that mass and checks nothing."""
    from identify.fitting.plausibility import Flag
    from rx90sym.files import file_sha256

    fitted = {d.get("sha256"): d.get("source") for d in gains.extra.get("fitted_on") or () if d.get("sha256")}
    shared = [p for p in paths if file_sha256(p) in fitted]
    if not shared:
        return []
    return [Flag("gains_circular", "warning",
                 f"the drive gains were fitted on {', '.join(shared)}: on the same runs the payload's Mc returns the "
                 f"mass the gains were scaled to and is not an independent check",
                 "fit the gains on some runs and identify the payload on others (docs/drive-gains.md)")]
