"""``rx90 simulate``: the twin (closed-loop simulated robot) on a trajectory CSV."""
from __future__ import annotations

import argparse
from typing import Any

from rx90sym.defaults import TWIN_NOISE

from ..common import UsageError, check_output, load_robot, progress, robot_option, spring_notice


def register(sub: Any) -> None:
    sp = sub.add_parser("simulate", help="simulate the robot (twin) on a trajectory",
                        description="simulate the robot (twin) on a trajectory")
    sp.set_defaults(func=run)
    sp.add_argument("trajectory", help="trajectory CSV written by rx90 excite")
    robot_option(sp)
    sp.add_argument("--params", help="the twin's true standard parameters: JSON name -> value, or the "
                    "JSON of 'rx90 identify': its identified model (default: the bundled RX90's twin "
                    "set, else the robot's nominal parameters: its [nominal] table or URDF inertials)")
    sp.add_argument("--payload", help="bundled payload name (tables_4, tables_5) or JSON file")
    sp.add_argument("--noise", choices=("ideal", "realistic"), default=TWIN_NOISE,
                    help=f"the twin's noise profile (default {TWIN_NOISE})")
    sp.add_argument("--seed", type=int, default=0)
    sp.add_argument("--out", required=True, help="recording CSV (controller angles)")


def run(args: argparse.Namespace) -> int:
    import rx90sym
    from excitation import read_trajectory
    from identify.io.recordings import write_recording

    from rx90sym.urdf import acceleration_note

    robot = load_robot(args)
    check_output(args.out)
    note = acceleration_note(robot)
    if note:  # the trajectory is read against the robot's limits
        progress(f"warning: {note}")
    from rx90sym.description_prior import simulation_refusal
    from rx90sym.nominal import twin_parameter_file

    # The description's own bodies as the twin's truth: physical, or every other link named at once.
    refusal = simulation_refusal(robot) if args.params is None and twin_parameter_file(robot) is None else None
    if refusal:
        raise UsageError(f"{refusal}: pass --params FILE (physical parameters, e.g. the JSON of rx90 identify: "
                         f"its identified model)")
    try:  # the twin's truth: the bundled RX90's own set, else the robot's nominal parameters
        params = rx90sym.default_parameters(robot, args.params)
    except ValueError as exc:
        raise UsageError(f"{exc}: pass --params FILE (the names: \"parameters\" of rx90 model --robot "
                         f"{args.robot or robot.name} --json F)") from None
    spring_notice(robot)
    trajectory = read_trajectory(args.trajectory, robot)
    progress(f"simulating {trajectory[0][-1] - trajectory[0][0]:.1f} s ({args.noise})")
    rec = rx90sym.twin.simulate(robot, trajectory, params=params, payload=args.payload,
                                noise=args.noise, seed=args.seed)
    write_recording(args.out, rec, robot, convention="controller")
    print(f"simulated {len(rec.t)} samples at {rec.rate:g} Hz -> {args.out}")
    print(robot.spring.label() if robot.spring is not None else "spring: none")
    return 0
