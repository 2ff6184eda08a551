"""``rx90 excite``: an optimised excitation trajectory (CSV at 250 Hz, JSON summary)."""
from __future__ import annotations

import argparse
import contextlib
import dataclasses
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from excitation.defaults import DEFAULT_CRITERION, OBJECTIVES

from ..common import UsageError, check_output, floats, load_robot, progress, robot_option
from .excite_output import controller_rate, save_trajectory
from .excite_poses import check_start_pose, name_frames

if TYPE_CHECKING:  # annotations only: the model is imported when the command runs
    import numpy as np

    import rx90sym


def register(sub: Any) -> None:
    sp = sub.add_parser("excite", help="optimise an excitation trajectory",
                        description="optimise an excitation trajectory (see docs/excitation.md)")
    sp.set_defaults(func=run)
    robot_option(sp)
    sp.add_argument("--duration", type=float, default=None,
                    help="duration [s] (default 20, or 10 with --for payload)")
    sp.add_argument("--for", dest="target", choices=("robot", "payload"), default="robot",
                    help="identify the robot (default) or a payload's ten parameters (a short motion)")
    sp.add_argument("--payload", default=None,
                    help="with --for payload: a typical payload (bundled name or JSON of XXc..Mc) for the "
                         "reference magnitudes and torque limits (default tables_4)")
    sp.add_argument("--harmonics", type=int, default=None,
                    help="Fourier harmonics (default 5; with --for payload the default is 10 via points)")
    sp.add_argument("--via-points", type=int, default=None,
                    help="optimise this many via points (quintic spline) instead of a Fourier series")
    _add_search_options(sp)
    _add_envelope_options(sp)
    _add_limit_options(sp)


def _add_search_options(sp: Any) -> None:
    """Multi-start, criterion and where the starts run."""
    sp.add_argument("--seed", type=int, default=0, help="seed of the multi-start, >= 0 (default 0)")
    sp.add_argument("--starts", type=int, default=2, help="number of starts (default 2)")
    sp.add_argument("--time-budget", type=float, default=None,
                    help="optional wall-clock budget [s] over all starts (default: none; with a "
                         "budget the result depends on the machine's speed)")
    sp.add_argument("--criterion", choices=OBJECTIVES, default=None,
                    help=f"what to optimise (default {DEFAULT_CRITERION}; see docs/excitation.md)")
    sp.add_argument("--select", default=None,
                    help="comma-separated base parameter names the 'sigma' criterion judges (default all)")
    sp.add_argument("--noise-std", default=None,
                    help="expected torque noise per joint [N m], comma-separated (default 1 %% of "
                         "each torque limit)")
    sp.add_argument("--params", default=None,
                    help="nominal standard parameters (JSON) for the torque limits and the criteria's "
                         "reference magnitudes (default: the robot's own, when it has any)")
    sp.add_argument("--complement", nargs="+", default=None, metavar="REC",
                    help="recordings already made: optimise a trajectory that adds to their information")
    sp.add_argument("--workers", type=int, default=None,
                    help="run the starts on a local Dask cluster of N worker processes (default: "
                         "in this process)")
    sp.add_argument("--scheduler", default=None,
                    help="run the starts on an existing Dask cluster (scheduler address, e.g. tcp://host:8786)")


def _add_envelope_options(sp: Any) -> None:
    """Collision, floor, controller output and the safety envelope's limits."""
    sp.add_argument("--obstacle", action="append", default=[], metavar="XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX",
                    help="an obstacle box [m, base frame] the link capsules must keep out of (repeatable)")
    sp.add_argument("--no-self-collision", action="store_true",
                    help="do not keep the link capsules apart (default: they are; the robot's own "
                         "capsules, docs/excitation.md)")
    sp.add_argument("--floor", type=float, default=None,
                    help="floor height [m above the robot's mounting plane] no moving point may go "
                         "below (default: the mounting margin, 0.05 m)")
    sp.add_argument("--controller", choices=("ur", "franka"), default=None,
                    help="write --out at this controller's rate and form (UR e-Series 500 Hz, see "
                         "--controller-rate; Franka 1 kHz, jerk checked); default 250 Hz")
    sp.add_argument("--controller-rate", type=float, default=None,
                    help="with --controller ur: servoj rate [Hz] (500 e-Series, 125 CB3; default: the robot file's [controller] rate_hz)")
    sp.add_argument("--program", default=None,
                    help="with --controller: the program the controller runs (ur: URScript with movej "
                         "and one servoj per sample; franka: 1 kHz joint positions for libfranka)")
    sp.add_argument("--start-pose", default=None,
                    help="with --controller: where the approach move begins (controller angles, rad, "
                         "comma-separated); checked against the safety envelope with its path")
    sp.add_argument("--centre-pose", default=None,
                    help="pose the optimisation starts about (controller angles, rad, comma-separated; "
                         "default: the centre of the ranges, or the nearest pose inside the envelope)")


def _add_limit_options(sp: Any) -> None:
    """Experiment limits (joint ranges, speeds, accelerations, mounting margin) and outputs."""
    sp.add_argument("--position-limits", default=None, metavar="MIN1:MAX1,...",
                    help="experiment joint ranges (controller angles, rad), inside the robot's (default "
                         "90 %% of each range about its centre)")
    sp.add_argument("--velocity-scale", type=float, default=None,
                    help="fraction of the robot's joint velocity limits (default 0.7)")
    sp.add_argument("--acceleration-scale", type=float, default=None,
                    help="fraction of the robot's joint acceleration limits (default 0.5)")
    sp.add_argument("--max-tool-speed", type=float, default=None,
                    help="Cartesian speed limit [m/s] of the tool point and every capsule end (default "
                         "1.0, at most 1.5)")
    sp.add_argument("--mounting-margin", type=float, default=None,
                    help="clearance [m] above the robot's mounting plane (default 0.05)")
    sp.add_argument("--report", default=None,
                    help="HTML report of the envelope: tool path, speeds and accelerations against "
                         "their limits, distances to the floor and between links along time")
    sp.add_argument("--out", required=True, help="trajectory CSV (controller angles; 250 Hz, or the "
                                                 "controller's rate with --controller, approach and return included)")
    sp.add_argument("--json", help="coefficients and summary as JSON")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    import excitation
    import rx90sym

    for path in (args.out, args.json, args.program, args.report):
        check_output(path)
    _check_options(args)
    robot = load_robot(args)
    params = rx90sym.nominal_parameters(robot, args.params)
    chi = None if params is None else robot.parameter_vector(params)
    # Without nominal parameters excitation.optimise says the torque limits are unchecked (once).
    criterion = args.criterion
    if criterion is None:
        criterion = excitation.DEFAULT_CRITERION if chi is not None else excitation.FALLBACK_CRITERION
    elif criterion in ("cond-nominal", "sigma") and chi is None:
        raise UsageError(f"--criterion {criterion} needs nominal parameters: pass --params FILE")
    noise = None if args.noise_std is None else floats(args.noise_std, "--noise-std", robot.n)
    if noise is not None and np.any(noise <= 0.0):
        raise UsageError("--noise-std: values must be > 0 N m")
    start_pose = None if args.start_pose is None else floats(args.start_pose, "--start-pose", robot.n)
    envelope = _envelope(args, robot)
    check_start_pose(robot, None, start_pose)
    collision = _collision(args, robot)
    base = rx90sym.base_parameters(robot)
    try:
        model, described = excitation.safe_model(robot, chi, base, envelope, collision)
    except ValueError as exc:  # a centre pose or a floor the arm cannot hold, naming the point
        if start_pose is None or envelope.centre is not None:
            raise UsageError(name_frames(robot, str(exc))) from None
        # No pose near the centre of the ranges holds the envelope: the search starts from the
        # start pose the user gave (the arm is there; check_start_pose below still checks it).
        envelope = dataclasses.replace(envelope, centre=tuple(float(v) for v in start_pose))
        try:
            model, described = excitation.safe_model(robot, chi, base, envelope, collision)
        except ValueError:
            raise UsageError(name_frames(robot, str(exc))) from None
        progress("envelope: no pose near the centre of the ranges holds it; the motion is planned about "
                 "--start-pose")
    check_start_pose(robot, model, start_pose)
    if args.controller == "ur":
        controller_rate(args, robot)  # refused now, before any optimisation, when no rate is known
    for line in excitation.envelope_lines(described):
        progress(line)
    if args.target == "payload":
        if chi is None:
            from excitation.api import nominal_warning

            progress(nominal_warning(robot))
        return _payload(args, robot, base, chi, noise, collision, start_pose, envelope, (model, described))
    complement = [_motion(path, robot) for path in args.complement or ()]
    with _client(args) as client:
        traj = excitation.optimise(
            robot, duration=20.0 if args.duration is None else args.duration,
            harmonics=5 if args.harmonics is None else args.harmonics,
            via_points=args.via_points, seed=args.seed, starts=args.starts, time_budget=args.time_budget,
            chi_nominal=chi, base=base, criterion=criterion, noise_std=noise,
            select=None if args.select is None else [s.strip() for s in args.select.split(",")],
            complement=complement, client=client, collision=collision, envelope=envelope,
            progress=sys.stderr)
    save_trajectory(args, traj, robot, start_pose, model)
    if args.json:
        traj.save_json(args.json)
    _report(args, robot, model, traj, described)
    skipped = traj.info.skipped_starts
    if skipped:
        progress(f"{len(skipped)} start(s) skipped by the time budget: {', '.join(map(str, skipped))}")
    print(f"cond = {traj.cond:.2f} (base observation matrix at 250 Hz), criterion {criterion} = "
          f"{traj.info.criterion_value:.4g}; written {_written(args)}")
    return 0


def _written(args: argparse.Namespace) -> str:
    """The files this run wrote, in the order of the options (--out first)."""
    return ", ".join(p for p in (args.out, args.program, args.json, args.report) if p is not None)


def _report(args: argparse.Namespace, robot: rx90sym.Robot, model: Any, traj: Any, described: dict) -> None:
    """--report: the envelope as applied, its worst values and figures along time."""
    if args.report is None:
        return
    from excitation import envelope_lines, envelope_report as er
    from excitation.robot_geometry import arm_geometry

    from ..report.excite_page import envelope_table, excite_page
    from ..report.figures import figure
    from ..report.page import Section, Text, write_page

    series = er.along_time(robot, model, traj, arm_geometry(robot).tool_point)
    envelope = Section("envelope", "Safety envelope along the trajectory", (
        Text(tuple(envelope_lines(described))), envelope_table(er.worst(series)),
        *(figure(i, caption, fig) for i, caption, fig in er.figures(series))))
    write_page(args.report, excite_page({**traj.summary(), "robot": robot.name}, (), (envelope,)))


# Bundled robots each controller drives (docs/excitation.md): a bundled robot of another make is
# refused; a robot file or URDF of your own is taken as you name it with --robot.
CONTROLLER_ROBOTS = {"ur": ("ur10e",), "franka": ("panda",)}


def _check_controller_robot(args: argparse.Namespace) -> None:
    """A controller program is written for the robot the user names, and for a robot of that make."""
    if args.controller is None:
        return
    import rx90sym

    if args.program is not None and args.robot is None:
        raise UsageError(f"--program writes a {args.controller} controller's program: name its robot with "
                         f"--robot (the default robot {args.default_robot} is not used for one)")
    spec = args.robot if args.robot is not None else args.default_robot
    allowed = CONTROLLER_ROBOTS[args.controller]
    if spec in rx90sym.bundled_robots() and spec not in allowed:
        raise UsageError(f"--controller {args.controller} drives {', '.join(allowed)} among the bundled robots, "
                         f"not {spec} (its joint limits differ): give --robot {allowed[0]} or your robot's file")


def _check_options(args: argparse.Namespace) -> None:
    """Option combinations refused before anything is computed."""
    if args.workers is not None and args.scheduler is not None:
        raise UsageError("give --workers (local cluster) or --scheduler (existing cluster), not both")
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be >= 1, got {args.workers}")
    if args.seed < 0:
        raise UsageError(f"--seed must be >= 0, got {args.seed}")
    if args.select is not None and args.criterion not in (None, "sigma"):
        raise UsageError("--select is for --criterion sigma")
    if args.harmonics is not None and args.via_points is not None:
        raise UsageError("give --harmonics (Fourier series) or --via-points, not both")
    for option in ("start_pose", "program", "controller_rate"):
        if getattr(args, option) is not None and args.controller is None:
            raise UsageError(f"--{option.replace('_', '-')} is for --controller (the controller's program and rate)")
    _check_controller_robot(args)
    if args.controller_rate is not None and (args.controller != "ur" or args.controller_rate <= 0):
        raise UsageError("--controller-rate is for --controller ur, a rate > 0 Hz (500 e-Series, 125 CB3)")
    if args.payload is not None and args.target != "payload":
        raise UsageError("--payload is for --for payload")
    for path in args.complement or ():  # read after the envelope is built: refused now, not then
        if not Path(path).is_file():
            raise UsageError(f"--complement: {path}: no such file")


def _collision(args: argparse.Namespace, robot: rx90sym.Robot) -> Any:
    import excitation

    try:
        collision = excitation.collision_model(robot, args.obstacle, not args.no_self_collision)
    except ValueError as exc:
        raise UsageError(f"--obstacle: {exc}") from None
    if args.no_self_collision:
        progress("warning: self-collision NOT checked (--no-self-collision); obstacle boxes and the floor still are")
    elif not collision.self_collision:
        pairs = collision.capsules.pair_names(collision.capsules.ignored)
        progress(f"warning: self-collision NOT checked: the default link capsules do not fit robot "
                 f"{robot.name!r} ({len(pairs)} pairs touch at the centre of the joint ranges, e.g. "
                 f"{pairs[0]}); give the robot's [[capsules]] (docs/robot-files.md)")
    return collision


def _envelope(args: argparse.Namespace, robot: rx90sym.Robot) -> Any:
    """The safety envelope from the options (angles in controller angles, as the envelope takes
    them; a refusal names the option and the values the user typed)."""
    import excitation

    limits = None
    if args.position_limits is not None:
        pairs = [p.split(":") for p in args.position_limits.split(",")]
        if len(pairs) != robot.n or any(len(p) != 2 for p in pairs):
            raise UsageError(f"--position-limits: expected {robot.n} MIN:MAX pairs (rad, controller angles), "
                             f"got {args.position_limits!r}")
        values = floats(",".join(v for p in pairs for v in p), "--position-limits").reshape(-1, 2)
        limits = tuple(map(tuple, values))
    centre = None if args.centre_pose is None else floats(args.centre_pose, "--centre-pose", robot.n)
    urdf_default = robot.urdf is not None and getattr(args, "acceleration", None) is None
    if urdf_default:
        from rx90sym.urdf import acceleration_note

        progress(f"warning: {acceleration_note(robot)} (the excitation uses them x the acceleration scale)")
    given = {k: v for k, v in (("margin", args.mounting_margin), ("floor", args.floor),
                               ("max_speed", args.max_tool_speed), ("velocity_scale", args.velocity_scale),
                               ("acceleration_scale", args.acceleration_scale)) if v is not None}
    try:
        envelope = excitation.Envelope(position_limits=limits, centre=None if centre is None else tuple(centre),
                                       urdf_acceleration=urdf_default, **given)
        envelope.joint_limits(robot.limits, robot.controller_offsets)  # refused now, before any work
    except ValueError as exc:
        raise UsageError(name_frames(robot, str(exc))) from None
    return envelope


def _payload(args: argparse.Namespace, robot: rx90sym.Robot, base: Any, chi: Any, noise: Any,
             collision: Any, start_pose: Any, envelope: Any, safe: tuple[Any, dict]) -> int:
    """--for payload: optimise, save, report the predicted sigma by methods 3 and 4 (safe: the
    envelope's model and description)."""
    model, described = safe
    import numpy as np

    from excitation.api import default_noise, optimise_payload
    from excitation.payload_design import payload_sigma
    from rx90sym.files import write_json

    for option in ("criterion", "select", "complement"):
        if getattr(args, option) is not None:
            raise UsageError(f"--{option} is for --for robot (the payload criterion is 'sigma' on XXc..Mc)")
    payload = args.payload or "tables_4"
    via = args.via_points if args.via_points is not None else (None if args.harmonics else 10)
    with _client(args) as client:
        traj = optimise_payload(robot, 10.0 if args.duration is None else args.duration, via,
                                harmonics=args.harmonics or 3, seed=args.seed, chi_nominal=chi,
                                payload=payload, noise_std=noise, starts=args.starts,
                                time_budget=args.time_budget, base=base, client=client,
                                collision=collision, envelope=envelope, progress=sys.stderr)
    if noise is None:
        noise = default_noise(robot.limits)
    sigma = payload_sigma(robot, base.regressor, traj, noise)
    save_trajectory(args, traj, robot, start_pose, model)
    _report(args, robot, model, traj, described)
    if args.json:
        write_json(args.json, {**traj.summary(), "payload_reference": str(payload),
                               "noise_std_nm": np.asarray(noise).tolist(), "payload_sigma": sigma})
    print(f"payload motion {traj.duration:g} s written {_written(args)}; predicted sigma (same motion empty "
          f"and loaded, methods 3 and 4 agree):")
    print("  " + ", ".join(f"{n} {sigma['method_3'][n]:.3g}" for n in ("Mc", "MZc", "XXc", "YYc")))
    return 0


def _motion(path: str, robot: rx90sym.Robot) -> tuple[np.ndarray, ...]:
    """(t, q, qd, qdd) of a recording (positions filtered and differentiated as for identification)."""
    from identify.signal.filtering import derivatives
    from identify.io.recordings import read_recording

    rec = read_recording(path, robot)
    d = derivatives(rec.t, rec.q)
    return d.t, d.q, d.dq, d.ddq


@contextlib.contextmanager
def _client(args: argparse.Namespace) -> Any:
    if args.workers is None and args.scheduler is None:
        yield None
        return
    from excitation import dask_client

    with dask_client(workers=args.workers, scheduler=args.scheduler) as client:
        yield client
