"""``rx90 convert``: a controller log (column map) or motor-side files (TX40) to a recording file.

Log form (docs/real-logs.md)::

    rx90 convert LOG.csv --robot R --columns SPEC [--no-header] [--rows FIRST:LAST]
                 [--from S] [--to S] [--resample HZ] [--gains LIST|FILE] [--convention C] --out REC.csv

Motor form (Stäubli CS8 / TX40 files)::

    rx90 convert --robot tx40 --motor-positions P.csv --motor-torques T.csv --period S --out REC.csv
"""
from __future__ import annotations

import argparse
from typing import Any


from identify.io.blocks import DEFAULT_LOG_BLOCK, count_rows

from ..common import UsageError, check_output, convention_option, load_robot, progress, robot_option
from .identify_runs import block_option

_LOG_OPTIONS = ("columns", "no_header", "rows", "t_from", "t_to", "resample", "gains")
_MOTOR_OPTIONS = ("motor_positions", "motor_torques", "period")


def register(sub: Any) -> None:
    text = ("convert a controller log (named columns) or motor-side recordings (TX40 files) to a "
            "recording file")
    sp = sub.add_parser("convert", help=text, description=text + "; see docs/real-logs.md")
    sp.set_defaults(func=run)
    robot_option(sp, None, "")
    sp.add_argument("log", nargs="?", metavar="LOG.csv", help="controller log (comma separated)")
    sp.add_argument("--columns", metavar="SPEC",
                    help="what each column of the log holds, in order: t, q1..qn, qd1..qdn (recorded "
                         "velocities), tau1..taun, i1..in (motor currents, A), _ (ignored), x:NAME "
                         "(kept, never a torque); ranges q1..q6 and _*3")
    sp.add_argument("--no-header", action="store_true", help="the log has no header line")
    sp.add_argument("--rows", metavar="FIRST:LAST",
                    help="keep lines FIRST..LAST of the file (1-based line numbers, inclusive)")
    sp.add_argument("--from", dest="t_from", type=float, metavar="S",
                    help="keep rows from this time of the log's clock, s")
    sp.add_argument("--to", dest="t_to", type=float, metavar="S", help="keep rows up to this time, s")
    sp.add_argument("--resample", type=float, metavar="HZ",
                    help="put every signal on a uniform grid at HZ (needed for irregular time stamps)")
    sp.add_argument("--gains", metavar="LIST|FILE",
                    help="drive gains turning currents into joint torques: K1,...,Kn (N m/A, joint "
                         "side) or the JSON of rx90 gains; without them the file keeps currents")
    convention_option(sp)
    sp.add_argument("--motor-positions", help="motor form: CSV of motor positions [rad]")
    sp.add_argument("--motor-torques", help="motor form: CSV of motor torques [N m]")
    sp.add_argument("--period", type=float, help="motor form: sampling period [s]")
    sp.add_argument("--out", required=True, help="recording file (.csv or .npz)")
    sp.add_argument("--block", type=block_option, default=DEFAULT_LOG_BLOCK,
                    help=f"lines per block: a longer log is converted block by block, memory bounded by the "
                         f"block (default {DEFAULT_LOG_BLOCK}; output CSV)")


def _given(args: argparse.Namespace, names: tuple[str, ...]) -> list[str]:
    flags = {"no_header": "--no-header", "t_from": "--from", "t_to": "--to"}
    return [flags.get(n, "--" + n.replace("_", "-")) for n in names if getattr(args, n) not in (None, False)]


def _rows(text: str | None) -> tuple[int, int] | None:
    if text is None:
        return None
    try:
        first, last = (int(x) for x in text.split(":"))
    except ValueError:
        raise UsageError(f"--rows {text!r}: expected FIRST:LAST (1-based line numbers)") from None
    return first, last


def _robot(args: argparse.Namespace):
    if args.robot is None:
        raise UsageError("convert needs --robot NAME|FILE.toml|FILE.urdf: the robot the log was recorded "
                         "on (its joint count, limits and angle offsets; written into the recording)")
    return load_robot(args)


def run(args: argparse.Namespace) -> int:
    from identify.io.logs import read_log
    from identify.io.recordings import write_recording

    if args.log is None:
        return _run_motor(args)
    mixed = _given(args, _MOTOR_OPTIONS)
    if mixed:
        raise UsageError(f"{', '.join(mixed)} belong to the motor form, not to a LOG.csv")
    if args.columns is None:
        raise UsageError("a LOG.csv needs --columns SPEC (e.g. t,q1..q6,qd1..qd6,i1..i6)")
    robot = _robot(args)
    check_output(args.out)
    if count_rows(args.log) > args.block:
        return _run_long(args, robot)
    progress(f"reading the log {args.log}")
    rec = read_log(args.log, robot, args.columns, header=not args.no_header, rows=_rows(args.rows),
                   t_from=args.t_from, t_to=args.t_to, resample=args.resample, gains=args.gains,
                   convention=args.convention)
    write_recording(args.out, rec, robot, convention="controller")
    _print_report(args, rec.meta["log"], "torques as logged" if rec.current is None else "no gains: the file keeps "
                  "currents (give --gains to identify with it)")
    return 0


def _run_long(args: argparse.Namespace, robot: Any) -> int:
    """A log longer than --block: converted block by block (identify.io.log_blocks)."""
    if not args.out.lower().endswith(".csv"):
        raise UsageError(f"--out {args.out}: a log longer than --block ({args.block} lines) is converted block by "
                         f"block into a CSV recording")
    from identify.io.columns import parse_columns
    from identify.io.log_blocks import convert_log

    progress(f"converting the log {args.log} block by block ({args.block} lines per block)")
    log = convert_log(args.log, robot, args.columns, args.out, header=not args.no_header, rows=_rows(args.rows),
                      t_from=args.t_from, t_to=args.t_to, resample=args.resample, gains=args.gains,
                      convention=args.convention, block=args.block)
    currents = bool(parse_columns(args.columns, robot).i)
    _print_report(args, log, "no gains: the file keeps currents (give --gains to identify with it)" if currents
                  else "torques as logged")
    return 0


def _print_report(args: argparse.Namespace, log: dict, what_else: str) -> None:
    steps = (f"rate {log['rate_hz']:.6g} Hz (1 / mean step; median step {log['median_step_s']:g} s, "
             f"{log['irregular_steps']} steps off by more than 1 %)")
    grid = (f"resampled to {log['resampled_hz']:g} Hz: {log['samples']} samples"
            if log["resampled_hz"] else "not resampled")
    what = f"gains {log['gains']}: joint torques from the currents" if log["gains"] else what_else
    print(f"read lines {log['lines'][0]}..{log['lines'][1]} of {args.log}: {log['rows']} rows, {steps}")
    print(f"largest step {log['largest_gap_s']:g} s (lines {log['largest_gap_lines'][0]}-"
          f"{log['largest_gap_lines'][1]}); {grid}; {what}")
    print(f"converted {log['samples']} samples -> {args.out}")


def _run_motor(args: argparse.Namespace) -> int:
    from identify.io.recordings import read_motor_recording, write_recording

    extra = _given(args, _LOG_OPTIONS) + (["--block"] if args.block != DEFAULT_LOG_BLOCK else [])
    if extra:
        raise UsageError(f"{', '.join(extra)} belong to the log form (give LOG.csv)")
    missing = [f for f, v in (("--motor-positions", args.motor_positions), ("--motor-torques", args.motor_torques),
                              ("--period", args.period)) if v is None]
    if missing:
        raise UsageError(f"give LOG.csv --columns SPEC, or the motor form ({', '.join(missing)} missing)")
    robot = _robot(args)
    check_output(args.out)
    progress("reading the motor-side files")
    rec = read_motor_recording(args.motor_positions, args.motor_torques, robot, period=args.period,
                               convention=args.convention or "controller")
    write_recording(args.out, rec, robot, convention="controller")
    print(f"converted {len(rec.t)} samples at {rec.rate:g} Hz -> {args.out}")
    return 0
