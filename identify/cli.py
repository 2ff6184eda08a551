"""The ``rx90`` command: model, excite, simulate, convert, identify, payload, demo.

Exit codes: 0 success, 2 bad input (one line on stderr naming the problem), 1 a failure that
is not the user's (a solver that did not converge is reported, never returned as a result).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from rx90sym.files import write_json

PROG = "rx90"


class UsageError(ValueError):
    """Conflicting or missing options."""


# ------------------------------------------------------------------------------------------ io
def progress(message: str) -> None:
    """One progress line on stderr (stdout keeps the tables)."""
    print(f"[{PROG}] {message}", file=sys.stderr, flush=True)


def _check_output(path: str | None) -> None:
    """Refuse an output path whose folder does not exist before doing any work."""
    if path is not None and not Path(path).resolve().parent.is_dir():
        raise UsageError(f"output folder of {path} does not exist")


def _robot(args: argparse.Namespace, offsets: bool = False) -> Any:
    import rx90sym

    return rx90sym.load_robot(args.robot, offsets=offsets)


def read_trajectory(path: str, robot: Any) -> tuple[np.ndarray, ...]:
    """A trajectory CSV (header t,q1..qn,dq1..dqn,ddq1..ddqn, Staubli angles) -> (t, q, qd, qdd)
    in Khalil angles."""
    n = robot.n
    expected = ["t"] + [f"{k}{j}" for k in ("q", "dq", "ddq") for j in range(1, n + 1)]
    try:
        with open(path) as fh:
            header = next(line for line in fh if not line.startswith("#")).strip().split(",")
    except (OSError, StopIteration) as exc:
        raise ValueError(f"{path}: cannot read trajectory ({exc or 'empty file'})") from None
    if header != expected:
        missing = [c for c in expected if c not in header]
        raise ValueError(f"{path}: trajectory header must be {','.join(expected)}"
                         + (f" (missing {missing[0]})" if missing else ""))
    try:
        data = np.loadtxt(path, delimiter=",", comments="#", skiprows=1, ndmin=2)
    except ValueError as exc:
        raise ValueError(f"{path}: not a numeric CSV ({exc})") from None
    bad = np.argwhere(~np.isfinite(data))
    if len(bad):
        raise ValueError(f"{path}: column {expected[bad[0, 1]]}, row {bad[0, 0] + 1}: not a finite number")
    t, q, qd, qdd = data[:, 0], data[:, 1:n + 1], data[:, n + 1:2 * n + 1], data[:, 2 * n + 1:]
    return t, robot.to_khalil(q), qd, qdd


# ------------------------------------------------------------------------------------------ commands
def cmd_model(args: argparse.Namespace) -> int:
    import rx90sym

    robot = _robot(args)
    _check_output(args.json)
    lines = [f"robot {robot.name}: {robot.n} joints, {len(robot.parameter_names)} standard parameters",
             " j  sigma  alpha[deg]    d[m]  theta[deg]    r[m]"]
    for j in range(robot.n):
        lines.append(f"{j + 1:2d}  {robot.sigma[j]:5d}  {np.degrees(robot.alpha[j]):10.1f}  {robot.d[j]:6.3f}"
                     f"  {np.degrees(robot.theta[j]):10.1f}  {robot.r[j]:6.3f}")
    print("\n".join(lines))
    out: dict[str, Any] = {"robot": robot.name, "n": robot.n, "parameters": list(robot.parameter_names)}
    if args.base:
        bp = rx90sym.base_parameters(robot)
        print(bp.table())
        out["base"] = {"names": list(bp.names), "expressions": bp.expressions}
    if args.json:
        write_json(args.json, out)
    return 0


def cmd_excite(args: argparse.Namespace) -> int:
    import excitation
    import rx90sym

    robot = _robot(args)
    _check_output(args.out)
    _check_output(args.json)
    chi = rx90sym.twin.default_parameters(robot) if robot.name == "rx90" else None
    traj = excitation.optimise(robot, duration=args.duration, harmonics=args.harmonics, seed=args.seed,
                               starts=args.starts, time_budget=args.time_budget,
                               chi_nominal=None if chi is None else robot.parameter_vector(chi),
                               progress=sys.stderr)
    traj.save(args.out)
    if args.json:
        traj.save_json(args.json)
    print(f"cond = {traj.cond:.2f} (base observation matrix at 250 Hz); written {args.out}")
    return 0


def cmd_simulate(args: argparse.Namespace) -> int:
    import rx90sym
    from .recordings import write_recording

    robot = _robot(args)
    _check_output(args.out)
    trajectory = read_trajectory(args.trajectory, robot)
    progress(f"simulating {trajectory[0][-1] - trajectory[0][0]:.1f} s ({args.noise})")
    rec = rx90sym.twin.simulate(robot, trajectory, payload=args.payload, noise=args.noise, seed=args.seed)
    write_recording(args.out, rec, robot, convention="staubli")
    print(f"simulated {len(rec.t)} samples at {rec.rate:g} Hz -> {args.out}")
    return 0


def cmd_convert(args: argparse.Namespace) -> int:
    from .recordings import read_motor_recording, write_recording

    robot = _robot(args)
    _check_output(args.out)
    progress("reading the motor-side files")
    rec = read_motor_recording(args.motor_positions, args.motor_torques, robot, period=args.period)
    write_recording(args.out, rec, robot, convention="staubli")
    print(f"converted {len(rec.t)} samples at {rec.rate:g} Hz -> {args.out}")
    return 0


def _robot_with_spring(args: argparse.Namespace) -> Any:
    import rx90sym
    from rx90sym.spring import read_spring_table

    robot = _robot(args, offsets=args.offsets)
    if args.spring == "none":
        return robot.with_options(spring=None)
    if args.spring != "default":
        table = read_spring_table(args.spring)
        joint = robot.spring.joint if robot.spring is not None else 1
        return robot.with_options(spring=rx90sym.Spring(joint=joint, table=table))
    return robot


def cmd_identify(args: argparse.Namespace) -> int:
    from . import essential_parameters, identify, predict, read_recording, validate
    from .report import identification_sections, write_report

    if args.essential and args.method == "consistent":
        raise UsageError("conflicting options: --essential works on the ols/wls estimate, "
                         "not with --method consistent")
    for out in (args.json, args.report):
        _check_output(out)
    robot = _robot_with_spring(args)
    progress(f"reading {len(args.recordings)} recording(s)")
    recs = [read_recording(p, robot, convention=args.convention) for p in args.recordings]
    val_rec = read_recording(args.validate, robot, convention=args.convention) if args.validate else None
    filt = {"cutoff": args.cutoff, "decimate_to": args.decimate_to}
    progress(f"identifying ({args.method}) on {sum(len(r.t) for r in recs)} samples")
    res = identify(robot, recs, method=args.method, min_velocity=args.min_velocity, **filt)
    print(res.table())
    ess = essential_parameters(res) if args.essential else None
    if ess is not None:
        print()
        print(ess.table())
    val = validate(robot, ess or res, val_rec, **filt) if val_rec is not None else None
    if val is not None:
        print()
        print(val.table())
    if args.json:
        out = {"robot": robot.name, "method": args.method, **res.to_dict(),
               "essential": list(ess.names) if ess is not None else [],
               "validation": val.to_dict() if val is not None else {}}
        write_json(args.json, out)
    if args.report:
        sections = identification_sections(robot, res, recs, validation=val, essential=ess,
                                           fit_prediction=predict(robot, res, recs[0], **filt))
        write_report(args.report, f"Identification of {robot.name}", sections)
    return 0


def _robot_params(path: str) -> dict[str, float]:
    try:
        with open(path) as fh:
            data = json.load(fh)
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: cannot read robot parameters ({exc})") from None
    try:
        if "parameters" in data and isinstance(data["parameters"], list):
            return {p["name"]: float(p["value"]) for p in data["parameters"]}
        if "parameters" in data and isinstance(data["parameters"], dict):
            return {k: float(v) for k, v in data["parameters"].items()}
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{path}: malformed parameter entry ({exc})") from None
    raise ValueError(f"{path}: no 'parameters' list or table (the output of rx90 identify --json)")


def cmd_payload(args: argparse.Namespace) -> int:
    from . import read_recording
    from .payload import payload

    if args.mass_tol is not None and args.mass is None:
        raise UsageError("conflicting options: --mass-tol needs --mass")
    if args.mass is not None and not args.constrained:
        raise UsageError("conflicting options: --mass is used by the constrained fit; add --constrained")
    if args.method == 1 and not args.robot_params:
        raise UsageError("method 1 needs --robot-params FILE.json (the robot's identified parameters)")
    _check_output(args.json)
    robot = _robot(args)
    empty = [read_recording(p, robot, convention=args.convention) for p in args.empty]
    loaded = [read_recording(p, robot, convention=args.convention) for p in args.loaded]
    params = _robot_params(args.robot_params) if args.robot_params else None
    progress(f"identifying the payload (method {args.method})")
    res = payload(robot, args.method, empty=empty, loaded=loaded, robot_params=params,
                  a_priori=args.a_priori, constrained=args.constrained, mass=args.mass,
                  mass_tol=args.mass_tol if args.mass_tol is not None else 0.05)
    print(res.table())
    if args.json:
        write_json(args.json, res.to_dict())
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    from .demo import run_demo

    return run_demo(args.out, quick=args.quick)


# ------------------------------------------------------------------------------------------ parser
def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=PROG, description="Dynamic identification of serial robots "
                                "(Staubli RX90 and its payload) with CasADi.")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def add(name: str, help_: str, func: Any) -> argparse.ArgumentParser:
        sp = sub.add_parser(name, help=help_, description=help_)
        sp.set_defaults(func=func)
        return sp

    def robot_opt(sp: argparse.ArgumentParser) -> None:
        sp.add_argument("--robot", default="rx90", help="bundled robot name or robot file (default rx90)")

    sp = add("model", "print the robot's model (and base parameters)", cmd_model)
    robot_opt(sp)
    sp.add_argument("--base", action="store_true", help="also print the base parameters (Table 2, eq. 19)")
    sp.add_argument("--json", help="write the model summary as JSON")

    sp = add("excite", "optimise an excitation trajectory", cmd_excite)
    robot_opt(sp)
    sp.add_argument("--duration", type=float, default=20.0, help="duration [s] (default 20)")
    sp.add_argument("--harmonics", type=int, default=5, help="Fourier harmonics (default 5)")
    sp.add_argument("--seed", type=int, default=0, help="seed of the multi-start (default 0)")
    sp.add_argument("--starts", type=int, default=2, help="number of starts (default 2)")
    sp.add_argument("--time-budget", type=float, default=300.0, help="time budget [s] (default 300)")
    sp.add_argument("--out", required=True, help="trajectory CSV (Staubli angles, 250 Hz)")
    sp.add_argument("--json", help="coefficients and summary as JSON")

    sp = add("simulate", "simulate the robot (twin) on a trajectory", cmd_simulate)
    sp.add_argument("trajectory", help="trajectory CSV written by rx90 excite")
    robot_opt(sp)
    sp.add_argument("--payload", help="bundled payload name (tables_4, tables_5) or JSON file")
    sp.add_argument("--noise", choices=("ideal", "realistic"), default="realistic")
    sp.add_argument("--seed", type=int, default=0)
    sp.add_argument("--out", required=True, help="recording CSV (Staubli angles)")

    sp = add("convert", "convert motor-side recordings (TX40 files) to a recording CSV", cmd_convert)
    robot_opt(sp)
    sp.add_argument("--motor-positions", required=True, help="CSV of motor positions [rad]")
    sp.add_argument("--motor-torques", required=True, help="CSV of motor torques [N m]")
    sp.add_argument("--period", type=float, required=True, help="sampling period [s]")
    sp.add_argument("--out", required=True, help="recording CSV")

    sp = add("identify", "identify the base parameters from recordings", cmd_identify)
    sp.add_argument("recordings", nargs="+", help="recording CSV files")
    robot_opt(sp)
    sp.add_argument("--convention", choices=("staubli", "khalil"), default=None,
                    help="joint angles of the files (default: the file's header, else staubli)")
    sp.add_argument("--spring", default="default", help="default | none | FILE.csv (angle, torque)")
    sp.add_argument("--offsets", action="store_true", help="add per-joint torque offsets OFF1..OFFn")
    sp.add_argument("--method", choices=("ols", "wls", "consistent"), default="wls")
    sp.add_argument("--essential", action="store_true", help="also compute the essential parameters")
    sp.add_argument("--cutoff", type=float, help="Butterworth cut-off for q [Hz] (default: chosen from the data)")
    sp.add_argument("--decimate-to", type=float, default=50.0, help="rate after parallel filtering [Hz] (default 50)")
    sp.add_argument("--min-velocity", type=float, help="drop a joint's rows where |qd| is below this [rad/s]")
    sp.add_argument("--validate", help="recording used for cross-validation only")
    sp.add_argument("--json", help="results as JSON")
    sp.add_argument("--report", help="self-contained HTML report")

    sp = add("payload", "identify a payload (paper section IV, methods 1-4)", cmd_payload)
    sp.add_argument("--method", type=int, choices=(1, 2, 3, 4), required=True)
    sp.add_argument("--empty", nargs="*", default=[], help="recordings without the payload")
    sp.add_argument("--loaded", nargs="+", required=True, help="recordings with the payload")
    robot_opt(sp)
    sp.add_argument("--convention", choices=("staubli", "khalil"), default=None)
    sp.add_argument("--robot-params", help="JSON of the robot's parameters (rx90 identify --json)")
    sp.add_argument("--a-priori", help="bundled payload name or JSON file of a priori values")
    sp.add_argument("--mass", type=float, help="weighed mass [kg] (constrained fit)")
    sp.add_argument("--mass-tol", type=float, help="tolerance of the weighed mass [kg] (default 0.05)")
    sp.add_argument("--constrained", action="store_true", help="payload pseudo-inertia PSD (and mass)")
    sp.add_argument("--json", help="results as JSON")

    sp = add("demo", "run the whole mission on the embedded RX90 and write a report", cmd_demo)
    sp.add_argument("--out", default="demo-output", help="output folder (default demo-output)")
    sp.add_argument("--quick", action="store_true", help="shorter motions and one start (for tests)")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    from .consistency import ConsistencyError

    try:
        return int(args.func(args) or 0)
    except ConsistencyError as exc:
        # A solver that failed is not the user's input: reported, exit 1, nothing written.
        print(f"{PROG} {args.command}: solver failed: {str(exc).splitlines()[0]}", file=sys.stderr)
        return 1
    except (ValueError, KeyError, FileNotFoundError, IsADirectoryError, PermissionError) as exc:
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        if isinstance(exc, KeyError):
            msg = msg.strip("\"'")
        print(f"{PROG} {args.command}: error: {msg}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
