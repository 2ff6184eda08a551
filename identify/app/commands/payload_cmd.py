"""``rx90 payload``: the payload's ten parameters by the paper's methods 1-4 (section IV)."""
from __future__ import annotations

import argparse
import dataclasses
from typing import TYPE_CHECKING, Any

from identify.payloads.defaults import MASS_TOL
from identify.signal.defaults import POSITION_TOLERANCE

from ..flags import checked, flag_lines, given_gain_flags, settle
from ..common import (UsageError, check_output, convention_option, load_robot, progress, robot_option,
                      robot_params, spring_notice)

if TYPE_CHECKING:  # annotations only: the method is imported when the command runs
    import numpy as np


METHOD_NEEDS = """what each method needs:
  1  --loaded and --robot-params (the robot's identified parameters); no --empty
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
    sp.add_argument("--robot-params", help="JSON of the robot's parameters (rx90 identify --json)")
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
    sp.add_argument("--json", help="results as JSON")
    sp.add_argument("--report", help="self-contained HTML report")


def run(args: argparse.Namespace) -> int:
    from rx90sym.files import write_json
    from rx90sym.flange_payload import flange_payload
    from identify.fitting.record import load_fit
    from identify.fitting.plausibility import mass_bound_flags, payload_flags, torque_scale_flags
    from identify.io.gains import apply_gains, read_gains
    from identify.io.recordings import read_recording
    from identify.payloads.methods import payload

    _check_options(args)
    check_output(args.json)
    check_output(args.report)
    robot = load_robot(args, offsets=args.offsets, recordings=args.empty + args.loaded)
    spring_notice(robot)
    gains = read_gains(args.gains, robot) if args.gains else None
    flags = given_gain_flags(gains) if gains is not None else []

    def read(path: str) -> Any:
        rec = checked(read_recording(path, robot, convention=args.convention), robot)
        return apply_gains(rec, gains, robot) if gains is not None and rec.current is not None else rec

    empty = [read(p) for p in args.empty]
    loaded = [read(p) for p in args.loaded]
    if gains is not None:
        flags += settle(circular_gain_flags(gains, args.empty + args.loaded))
    if gains is not None and all(r.current is None for r in empty + loaded):
        raise UsageError(f"--gains {args.gains}: none of the recordings holds motor currents")
    flags += settle(torque_scale_flags([r.tau for r in empty + loaded if r.tau is not None], robot))
    params = robot_params(args.robot_params) if args.robot_params else None
    progress(f"identifying the payload (method {args.method})")
    filt = {}
    if args.filtering_from:  # the fit's achieved cut-off, decimation and delay (not its rest handling)
        f = load_fit(args.filtering_from, robot).filtering()
        filt = {k: f[k] for k in ("cutoff", "decimate_to", "delay")}
    res = payload(robot, args.method, empty=empty, loaded=loaded, robot_params=params, **filt,
                  a_priori=args.a_priori, constrained=args.constrained, mass=args.mass,
                  mass_tol=args.mass_tol if args.mass_tol is not None else MASS_TOL,
                  position_tol=args.position_tol if args.position_tol is not None else POSITION_TOLERANCE)
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
              "mass": args.mass, "data": {"empty": [r.source for r in empty], "loaded": [r.source for r in loaded]},
              # The neutral block: mass, CoG and inertia at the CoG in the maker's flange frame (what
              # a controller takes; rx90 export --ur / --franka writes it in the controller's form).
              "flange": flange_payload(robot, res.as_dict()).to_dict()}
    if args.json:
        write_json(args.json, record)
    if args.report:
        from ..report.writers import write_payload_report

        write_payload_report(args.report, record, res)
    return 0


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
        raise UsageError("method 1 needs --robot-params FILE.json (the robot's identified parameters)")
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
