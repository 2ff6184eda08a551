"""``rx90 excite``: an optimised excitation trajectory (CSV at 250 Hz, JSON summary)."""
from __future__ import annotations

import argparse
import contextlib
import sys
from typing import Any

import numpy as np

import rx90sym

from ..common import UsageError, check_output, floats, load_robot, progress, robot_option


def register(sub: Any) -> None:
    import excitation

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
    sp.add_argument("--seed", type=int, default=0, help="seed of the multi-start, >= 0 (default 0)")
    sp.add_argument("--starts", type=int, default=2, help="number of starts (default 2)")
    sp.add_argument("--time-budget", type=float, default=None,
                    help="optional wall-clock budget [s] over all starts (default: none; with a "
                         "budget the result depends on the machine's speed)")
    sp.add_argument("--criterion", choices=excitation.OBJECTIVES, default=None,
                    help=f"what to optimise (default {excitation.DEFAULT_CRITERION}; see docs/excitation.md)")
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
    sp.add_argument("--obstacle", action="append", default=[], metavar="XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX",
                    help="an obstacle box [m, base frame] the link capsules must keep out of (repeatable)")
    sp.add_argument("--no-self-collision", action="store_true",
                    help="do not keep the link capsules apart (default: they are; radii in docs/excitation.md)")
    sp.add_argument("--floor", type=float, default=None,
                    help="floor height z [m, base frame] the wrist centre and tool must stay above")
    sp.add_argument("--controller", choices=("ur", "franka"), default=None,
                    help="write --out at this controller's rate and form (UR 500 Hz; Franka 1 kHz, jerk "
                         "checked); default 250 Hz")
    sp.add_argument("--start-pose", default=None,
                    help="with --controller: prepend an approach move from this pose (controller angles, "
                         "rad, comma-separated)")
    sp.add_argument("--out", required=True, help="trajectory CSV (controller angles, 250 Hz)")
    sp.add_argument("--json", help="coefficients and summary as JSON")


def run(args: argparse.Namespace) -> int:
    import excitation

    check_output(args.out)
    check_output(args.json)
    if args.workers is not None and args.scheduler is not None:
        raise UsageError("give --workers (local cluster) or --scheduler (existing cluster), not both")
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be >= 1, got {args.workers}")
    if args.seed < 0:
        raise UsageError(f"--seed must be >= 0, got {args.seed}")
    robot = load_robot(args)
    params = rx90sym.nominal_parameters(robot, args.params)
    chi = None if params is None else robot.parameter_vector(params)
    if chi is None:
        progress(f"warning: robot {robot.name!r} has no nominal parameters: the trajectory is NOT "
                 f"checked against the torque limits (pass --params FILE)")
    criterion = args.criterion
    if criterion is None:
        criterion = excitation.DEFAULT_CRITERION if chi is not None else excitation.FALLBACK_CRITERION
    elif criterion in ("cond-nominal", "sigma") and chi is None:
        raise UsageError(f"--criterion {criterion} needs nominal parameters: pass --params FILE")
    if args.select is not None and criterion != "sigma":
        raise UsageError("--select is for --criterion sigma")
    if args.harmonics is not None and args.via_points is not None:
        raise UsageError("give --harmonics (Fourier series) or --via-points, not both")
    noise = None if args.noise_std is None else floats(args.noise_std, "--noise-std", robot.n)
    if noise is not None and np.any(noise <= 0.0):
        raise UsageError("--noise-std: values must be > 0 N m")
    if args.start_pose is not None and args.controller is None:
        raise UsageError("--start-pose is for --controller (the approach move is part of the controller export)")
    start_pose = None if args.start_pose is None else floats(args.start_pose, "--start-pose", robot.n)
    try:
        collision = excitation.collision_model(robot, args.obstacle, not args.no_self_collision)
    except ValueError as exc:
        raise UsageError(f"--obstacle: {exc}") from None
    if not args.no_self_collision and not collision.self_collision:
        pairs = collision.capsules.pair_names(collision.capsules.ignored)
        progress(f"warning: self-collision NOT checked: the default link capsules do not fit robot "
                 f"{robot.name!r} ({len(pairs)} pairs touch at the centre of the joint ranges, e.g. "
                 f"{pairs[0]}); obstacle boxes and the floor still are")
    base = rx90sym.base_parameters(robot)
    if args.target == "payload":
        return _payload(args, robot, base, chi, noise, collision, start_pose)
    if args.payload is not None:
        raise UsageError("--payload is for --for payload")
    complement = [_motion(path, robot) for path in args.complement or ()]
    with _client(args) as client:
        traj = excitation.optimise(
            robot, duration=20.0 if args.duration is None else args.duration,
            harmonics=5 if args.harmonics is None else args.harmonics,
            via_points=args.via_points, seed=args.seed, starts=args.starts, time_budget=args.time_budget,
            chi_nominal=chi, base=base, criterion=criterion, noise_std=noise,
            select=None if args.select is None else [s.strip() for s in args.select.split(",")],
            complement=complement, client=client, collision=collision, z_min=args.floor,
            progress=sys.stderr)
    _save(args, traj, robot, start_pose)
    if args.json:
        traj.save_json(args.json)
    skipped = traj.info.skipped_starts
    if skipped:
        progress(f"{len(skipped)} start(s) skipped by the time budget: {', '.join(map(str, skipped))}")
    print(f"cond = {traj.cond:.2f} (base observation matrix at 250 Hz), criterion {criterion} = "
          f"{traj.info.criterion_value:.4g}; written {args.out}")
    return 0


def _save(args: argparse.Namespace, traj: Any, robot: rx90sym.Robot, start_pose: Any) -> None:
    """--out at 250 Hz, or at the controller's rate with its approach move."""
    if args.controller is None:
        traj.save(args.out)
        return
    from excitation.controller_export import export_for_controller

    export_for_controller(traj, args.out, args.controller, robot.limits, start_pose)


def _payload(args: argparse.Namespace, robot: rx90sym.Robot, base: Any, chi: Any, noise: Any,
             collision: Any, start_pose: Any) -> int:
    """--for payload: optimise, save, report the predicted sigma by methods 3 and 4."""
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
                                collision=collision, z_min=args.floor, progress=sys.stderr)
    if noise is None:
        noise = default_noise(robot.limits)
    sigma = payload_sigma(robot, base.regressor, traj, noise)
    _save(args, traj, robot, start_pose)
    if args.json:
        write_json(args.json, {**traj.summary(), "payload_reference": str(payload),
                               "noise_std_nm": np.asarray(noise).tolist(), "payload_sigma": sigma})
    print(f"payload motion {traj.duration:g} s written {args.out}; predicted sigma (same motion empty "
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
