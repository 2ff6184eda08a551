"""``rx90 convert``: a controller log (column map) or motor-side files (TX40) to a recording file.

Log form (docs/real-logs.md)::

    rx90 convert LOG.csv --robot R --columns SPEC [--no-header] [--rows FIRST:LAST]
                 [--from S] [--to S] [--resample HZ] [--max-gap S] [--no-segments] [--gains LIST|FILE]
                 [--convention C] [--block LINES] --out REC.csv

ROS bag form (joint_states; ROS 1, ROS 2 sqlite3 or MCAP; needs the ``ros`` extra)::

    rx90 convert BAG --topic /joint_states --robot R [--effort torque|current] [--gains ...]
                 [--resample HZ] [--max-gap S] [--no-segments] --out REC.csv

Joint files form (one file per signal, one column per joint, header or none, no time column;
identify.io.joint_files)::

    rx90 convert --positions Q.csv --torques T.csv [--velocities V.csv] [--currents I.csv --gains G]
                 --period S --robot R [--resample HZ] [--convention C] --out REC.csv

Motor form (Stäubli CS8 / TX40 files)::

    rx90 convert --robot tx40 --motor-positions P.csv --motor-torques T.csv --period S --out REC.csv

``--period S`` also reads a LOG.csv without time column (its column map names no ``t``): sample k
at ``t = k * S``, t = 0 at the first row read; a time column that counts samples (0, 1, 2, ...) is
refused with that fix. ``--torque-signs S1,...,Sn`` (every form) negates the torque and current
columns of the joints given -1 (identify.io.torque_signs).
"""
from __future__ import annotations

import argparse
from typing import Any

from identify.io.defaults import DEFAULT_LOG_BLOCK, DEFAULT_MAX_GAP

from ..common import UsageError, check_output, convention_option, load_robot, progress, robot_option
from .identify_runs import block_option

_LOG_OPTIONS = ("columns", "no_header", "rows", "t_from", "t_to", "resample", "gains", "max_gap", "no_segments")
_MOTOR_OPTIONS = ("motor_positions", "motor_torques")
_FILE_OPTIONS = ("positions", "velocities", "torques", "currents")
_BAG_OPTIONS = ("topic", "effort")
_CSV_ONLY = ("columns", "no_header", "rows", "t_from", "t_to")


def register(sub: Any) -> None:
    text = ("convert a controller log (named columns), one file per signal (positions, torques, ...) or "
            "motor-side recordings (TX40 files) to a recording file")
    sp = sub.add_parser("convert", help=text, description=text + "; see docs/real-logs.md")
    sp.set_defaults(func=run)
    robot_option(sp, None, "")
    sp.add_argument("log", nargs="?", metavar="LOG.csv|BAG",
                    help="controller log (comma separated), or a ROS bag (.bag, ROS 2 directory, .db3, .mcap)")
    sp.add_argument("--topic", help="bag form: the sensor_msgs/JointState topic (e.g. /joint_states)")
    sp.add_argument("--effort", choices=("torque", "current"),
                    help="bag form: what the messages' effort holds (default torque; current needs --gains "
                         "to become torques)")
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
    sp.add_argument("--max-gap", type=float, metavar="S",
                    help=f"longest gap of lost packets bridged by --resample, s (default {DEFAULT_MAX_GAP:g}); "
                         f"a longer gap starts a new segment")
    sp.add_argument("--no-segments", action="store_true",
                    help="refuse a gap longer than --max-gap instead of splitting the log into segments")
    sp.add_argument("--gains", metavar="LIST|FILE",
                    help="drive gains turning currents into joint torques: K1,...,Kn (N m/A, joint "
                         "side) or the JSON of rx90 gains; without them the file keeps currents")
    convention_option(sp)
    sp.add_argument("--positions", metavar="Q.csv",
                    help="joint files form: joint positions [rad], one column per joint, header or none")
    sp.add_argument("--torques", metavar="T.csv", help="joint files form: joint torques [N m], joint side")
    sp.add_argument("--velocities", metavar="V.csv", help="joint files form: recorded joint velocities [rad/s]")
    sp.add_argument("--currents", metavar="I.csv",
                    help="joint files form: motor currents [A] (--gains turns them into joint torques)")
    sp.add_argument("--motor-positions", help="motor form: CSV of motor positions [rad]")
    sp.add_argument("--motor-torques", help="motor form: CSV of motor torques [N m]")
    sp.add_argument("--period", type=float, metavar="S",
                    help="sampling period [s] of files without a time column: the joint files and motor forms, "
                         "or a LOG.csv whose --columns names no t (sample k at t = k S, t = 0 at the first sample)")
    sp.add_argument("--torque-signs", metavar="S1,...,Sn",
                    help="one sign per joint, 1 (as logged) or -1: the torque (and current) columns of the joints "
                         "given -1 are negated (a log whose torques count the other way than the robot's joints)")
    sp.add_argument("--out", required=True, help="recording file (.csv or .npz)")
    sp.add_argument("--block", metavar="LINES",  # checked by run: refused for a bag in one line, not by argparse
                    help=f"LOG.csv form: lines read and checked at a time: memory bounded by the block whatever "
                         f"the log's length for a CSV output (default {DEFAULT_LOG_BLOCK}, at least 1000)")


def _given(args: argparse.Namespace, names: tuple[str, ...]) -> list[str]:
    flags = {"no_header": "--no-header", "t_from": "--from", "t_to": "--to"}
    return [flags.get(n, "--" + n.replace("_", "-")) for n in names if getattr(args, n) not in (None, False)]


def _belong(flags: list[str]) -> str:
    """``--a belongs`` / ``--a, --b belong``: the start of a refusal of options of another form."""
    return f"{', '.join(flags)} {'belongs' if len(flags) == 1 else 'belong'}"


def _block(text: str | None) -> int:
    """``--block`` of the LOG.csv form: lines per block (identify_runs.block_option's rule)."""
    if text is None:
        return DEFAULT_LOG_BLOCK
    try:
        return block_option(text, "lines")
    except argparse.ArgumentTypeError as exc:
        raise UsageError(str(exc)) from None


def _rows(text: str | None) -> tuple[int, int] | None:
    if text is None:
        return None
    try:
        first, last = (int(x) for x in text.split(":"))
    except ValueError:
        raise UsageError(f"--rows {text!r}: expected FIRST:LAST (1-based line numbers)") from None
    return first, last


def _robot(args: argparse.Namespace):
    """The robot of --robot, and --torque-signs checked against it (args.torque_signs: the signs, or None)."""
    from identify.io.torque_signs import parse_torque_signs

    if args.robot is None:
        raise UsageError("convert needs --robot NAME|FILE.toml|FILE.urdf: the robot the log was recorded "
                         "on (its joint count, limits and angle offsets; written into the recording)")
    robot = load_robot(args)
    args.torque_signs = parse_torque_signs(args.torque_signs, robot, "--torque-signs")
    return robot


def run(args: argparse.Namespace) -> int:
    from identify.io.bags import is_bag
    from identify.io.log_blocks import read_log
    from identify.io.recordings import write_recording

    if args.log is None:
        if _given(args, _FILE_OPTIONS):
            return _run_files(args)
        return _run_motor(args)
    bag = is_bag(args.log) or args.topic is not None
    mixed = _given(args, _MOTOR_OPTIONS + (("period",) if bag else ()))
    if mixed:
        raise UsageError(f"{_belong(mixed)} to the motor form, not to {'a bag' if bag else 'a LOG.csv'}")
    files = _given(args, _FILE_OPTIONS)
    if files:
        raise UsageError(f"{_belong(files)} to the joint files form (no LOG.csv), not to {'a bag' if bag else 'a LOG.csv'}")
    if args.max_gap is not None and not args.max_gap > 0:
        raise UsageError(f"--max-gap must be a positive time in s, got {args.max_gap:g}")
    if bag:
        return _run_bag(args)
    block = _block(args.block)
    extra = _given(args, _BAG_OPTIONS)
    if extra:
        raise UsageError(f"{_belong(extra)} to the bag form (a .bag, .db3, .mcap or ROS 2 bag directory)")
    if args.columns is None and args.no_header:
        raise UsageError("a LOG.csv without header needs --columns SPEC (e.g. t,q1..q6,qd1..qd6,i1..i6)")
    robot = _robot(args)
    check_output(args.out)
    if args.period is not None and not args.period > 0:
        raise UsageError(f"--period must be a positive sampling period in s, got {args.period:g}")
    if args.out.lower().endswith(".csv"):
        return _convert_csv(args, robot, block)
    progress(f"reading the log {args.log} ({block} lines per block)")
    rec = read_log(args.log, robot, args.columns, header=not args.no_header, rows=_rows(args.rows),
                   t_from=args.t_from, t_to=args.t_to, resample=args.resample, gains=args.gains,
                   convention=args.convention, max_gap=args.max_gap or DEFAULT_MAX_GAP,
                   segments=not args.no_segments, period=args.period, block=block, torque_signs=args.torque_signs)
    write_recording(args.out, rec, robot, convention="controller")
    print(_print_log(args.log, rec.meta["log"], "torques as logged" if rec.current is None else
                     "no gains: the file keeps currents (give --gains to identify with it)"))
    print(f"converted {rec.n_samples} samples -> {args.out}")
    return 0


def _convert_csv(args: argparse.Namespace, robot: Any, block: int) -> int:
    """A log of any length to a CSV recording, ``block`` lines at a time (identify.io.log_blocks.convert_log:
    the reader of identify.read_log, each part written as it comes)."""
    from identify.io.log_blocks import convert_log

    progress(f"converting the log {args.log} ({block} lines per block)")
    log = convert_log(args.log, robot, args.columns, args.out, header=not args.no_header, rows=_rows(args.rows),
                      t_from=args.t_from, t_to=args.t_to, resample=args.resample, gains=args.gains,
                      convention=args.convention, block=block, max_gap=args.max_gap or DEFAULT_MAX_GAP,
                      segments=not args.no_segments, period=args.period, torque_signs=args.torque_signs)
    print(_print_log(args.log, log, "no gains: the file keeps currents (give --gains to identify with it)"
                     if _holds_currents(log, robot) else "torques as logged"))
    print(f"converted {log['samples']} samples -> {args.out}")
    return 0


def _holds_currents(log: dict, robot: Any) -> bool:
    """Whether the converted log holds motor currents (its ``columns``, the column map read)."""
    from identify.io.columns import parse_columns

    return bool(parse_columns(log["columns"], robot, time="period_s" not in log).i)


def _run_bag(args: argparse.Namespace) -> int:
    from identify.io.bags import MissingExtra, read_bag
    from identify.io.recordings import write_recording

    wrong = _given(args, _CSV_ONLY + ("block",))
    if wrong:
        raise UsageError(f"{_belong(wrong)} to the LOG.csv form, not to a bag (a bag is read whole)")
    if args.topic is None:
        raise UsageError("a bag needs --topic (the sensor_msgs/JointState topic, e.g. /joint_states)")
    robot = _robot(args)
    check_output(args.out)
    progress(f"reading the bag {args.log}, topic {args.topic}")
    try:
        rec = read_bag(args.log, robot, args.topic, effort=args.effort or "torque", gains=args.gains,
                       resample=args.resample, convention=args.convention or "controller",
                       max_gap=args.max_gap or DEFAULT_MAX_GAP, segments=not args.no_segments,
                       torque_signs=args.torque_signs)
    except MissingExtra as exc:
        raise UsageError(str(exc)) from None
    write_recording(args.out, rec, robot, convention="controller")
    log = rec.meta["log"]
    print(f"topic {log['topic']}: {log['messages']} messages, {log['reordered']} out of stamp order (sorted), "
          f"{log['duplicate_stamps']} with a repeated stamp (dropped), {log['incomplete_messages']} missing joints "
          f"(dropped), {log['other_joint_messages']} of other joints (skipped); velocities {log['velocities']}")
    print(_print_log(args.log, log, "torques as logged" if rec.current is None else
                     "no gains: the file keeps currents (give --gains to identify with it)"))
    print(f"converted {rec.n_samples} samples -> {args.out}")
    return 0


def _print_log(name: str, log: dict, what_else: str) -> str:
    """What the reader did, in the user's words: rows, rate, stale rows, gaps, grid, torques."""
    steps = (f"rate {log['rate_hz']:.6g} Hz (1 / mean step without lost packets; median step "
             f"{log['median_step_s']:g} s, {log['irregular_steps']} steps off by more than 1 %)")
    grid = (f"resampled to {log['resampled_hz']:g} Hz: {log['samples']} samples"
            if log["resampled_hz"] else "not resampled")
    what = f"gains {log['gains']}: joint torques from the currents" if log["gains"] else what_else
    if log.get("torque_signs"):
        from identify.io.torque_signs import signs_text

        what += f"; torque signs {signs_text(log['torque_signs'])} (columns of the joints given -1 negated)"
    gaps = log.get("gaps", {"gaps": []})
    lines = [f"read lines {log['lines'][0]}..{log['lines'][1]} of {name}: {log['rows']} rows, {steps}",
             f"largest step {log['largest_gap_s']:g} s (lines {log['largest_gap_lines'][0]}-"
             f"{log['largest_gap_lines'][1]}); {grid}; {what}"]
    if log.get("stale_rows"):
        shown = ", ".join(map(str, log["stale_lines"]))
        lines.append(f"stale rows dropped (exact repeats of the previous row): {log['stale_rows']} (lines "
                     f"{shown}{', ...' if log['stale_rows'] > len(log['stale_lines']) else ''})")
    if gaps["gaps"]:
        lines.append(f"lost packets: {gaps.get('gaps_total', len(gaps['gaps']))} gaps; {gaps['bridged_gaps']} up to {gaps['max_gap_s']:g} s "
                     f"bridged ({log['bridged_samples']} samples interpolated, never used as measurements), "
                     f"{gaps['segments']} segment(s)")
        lines += _gap_lines(gaps)
    if gaps.get("dropped_segments"):
        from identify.io.gaps import MIN_SEGMENT_ROWS

        shown = ", ".join(f"{a}..{b}" for a, b in gaps["dropped_lines"])
        lines.append(f"segments too short to filter dropped: {gaps['dropped_segments']} ({gaps['dropped_rows']} rows, "
                     f"fewer than {MIN_SEGMENT_ROWS} each; lines {shown}"
                     f"{', ...' if gaps['dropped_segments'] > len(gaps['dropped_lines']) else ''})")
    return "\n".join(lines)


def _gap_lines(gaps: dict) -> list[str]:
    """The gaps that split the log into segments, every one listed (up to SPLITS_LISTED), then the first
    bridged ones (``gaps``: :meth:`identify.io.gaps.LogGaps.summary`)."""
    def line(g: dict, what: str) -> str:
        return (f"  gap of {g['duration_s']:g} s ({g['periods']:.3g} steps) between lines {g['lines'][0]} and "
                f"{g['lines'][1]}: {what}")

    out = [line(g, "new segment") for g in gaps["splits"]]
    if gaps["splits_total"] > len(gaps["splits"]):
        out.append(f"  ... and {gaps['splits_total'] - len(gaps['splits'])} more gaps that start a new segment")
    bridged = [g for g in gaps["gaps"] if g["bridged"]][:_GAPS_SHOWN]
    out += [line(g, "bridged") for g in bridged]
    if gaps["bridged_gaps"] > len(bridged):
        out.append(f"  ... and {gaps['bridged_gaps'] - len(bridged)} more bridged gaps")
    return out


#: How many bridged gaps the output lists one by one.
_GAPS_SHOWN = 10


def _run_files(args: argparse.Namespace) -> int:
    """The joint files form: one file per signal (identify.io.joint_files)."""
    from identify.io.joint_files import read_joint_files
    from identify.io.recordings import write_recording

    extra = _given(args, tuple(o for o in _LOG_OPTIONS if o not in ("resample", "gains")) + _BAG_OPTIONS
                   + _MOTOR_OPTIONS + ("block",))
    if extra:
        raise UsageError(f"{_belong(extra)} to the log form (give LOG.csv) or the motor form, not to the joint "
                         f"files form (--positions ...)")
    missing = [f for f, v in (("--positions Q.csv", args.positions), ("--period S", args.period)) if v is None]
    if args.torques is None and args.currents is None:
        missing.append("--torques T.csv (or --currents I.csv with --gains)")
    if missing:
        raise UsageError(f"the joint files form needs {', '.join(missing)}")
    if not args.period > 0:
        raise UsageError(f"--period must be a positive sampling period in s, got {args.period:g}")
    if args.gains is not None and args.currents is None:
        raise UsageError("--gains turns the motor currents of --currents I.csv into joint torques; no --currents given")
    if args.gains is not None and args.torques is not None:
        raise UsageError("--gains with both --torques and --currents: the gains' torques would replace those of "
                         f"{args.torques}; give one of them")
    robot = _robot(args)
    check_output(args.out)
    files = {k: getattr(args, k) for k in _FILE_OPTIONS if getattr(args, k) is not None}
    progress(f"reading {', '.join(files.values())}")
    rec = read_joint_files(robot, files, args.period, gains=args.gains, convention=args.convention,
                           resample=args.resample, torque_signs=args.torque_signs)
    write_recording(args.out, rec, robot, convention="controller")
    print(_print_log(args.positions, rec.meta["log"], "torques as read" if rec.current is None else
                     "torques as read, currents kept" if args.torques else
                     "no gains: the file keeps currents (give --gains to identify with it)"))
    print(f"converted {rec.n_samples} samples ({' + '.join(rec.meta['log']['files'].values())}, period "
          f"{args.period:g} s, t = 0 at the first sample) -> {args.out}")
    return 0


def _run_motor(args: argparse.Namespace) -> int:
    from identify.io.recordings import read_motor_recording, write_recording

    extra = _given(args, _LOG_OPTIONS + _BAG_OPTIONS + ("block",))
    if extra:
        raise UsageError(f"{_belong(extra)} to the log form (give LOG.csv or a bag)")
    missing = [f for f, v in (("--motor-positions", args.motor_positions), ("--motor-torques", args.motor_torques),
                              ("--period", args.period)) if v is None]
    if missing:
        raise UsageError(f"give LOG.csv --columns SPEC, the joint files form (--positions Q.csv --torques T.csv "
                         f"--period S), or the motor form ({', '.join(missing)} missing)")
    robot = _robot(args)
    check_output(args.out)
    progress("reading the motor-side files")
    from identify.io.torque_signs import signs_text, with_torque_signs

    rec = read_motor_recording(args.motor_positions, args.motor_torques, robot, period=args.period,
                               convention=args.convention or "controller")
    rec = with_torque_signs(rec, args.torque_signs)  # joint side, as the other forms' columns
    write_recording(args.out, rec, robot, convention="controller")
    signs = f" (torque signs {signs_text(args.torque_signs)})" if args.torque_signs else ""
    print(f"converted {len(rec.t)} samples at {rec.rate:g} Hz{signs} -> {args.out}")
    return 0
