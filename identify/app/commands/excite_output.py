"""``rx90 excite``'s output at a controller's rate: the UR stream rate, the samples with their
approach and return, the controller's program (imported by excite only when it runs)."""
from __future__ import annotations

import argparse
import dataclasses
from typing import TYPE_CHECKING, Any

from ..common import UsageError

if TYPE_CHECKING:
    import rx90sym

__all__ = ["controller_rate", "save_trajectory"]


def save_trajectory(args: argparse.Namespace, traj: Any, robot: rx90sym.Robot, start_pose: Any, model: Any) -> None:
    """--out at 250 Hz, or at the controller's rate with its approach move and --program; every
    check (approach and return paths, the controller's limits) passes before anything is written."""
    if args.controller is None:
        traj.save(args.out)
        return
    import numpy as np

    from excitation import controller_export as ce, controller_programs as cp
    from excitation.constraints import evaluate_torque
    from excitation.envelope import path_violations

    if start_pose is not None:  # the approach's path; the return (movej) retraces it
        bad = path_violations(model, np.asarray(start_pose) - robot.controller_offsets, traj.start_position(),
                              what="approach and return path from --start-pose")
        if bad:
            raise ValueError(f"{bad[0]}: choose another --start-pose")
    rate = controller_rate(args, robot) if args.controller == "ur" else cp.FRANKA_RATE
    controller = dataclasses.replace(ce.CONTROLLERS[args.controller], rate=rate)
    t, q, qd, qdd = ce.controller_samples(traj, controller, model.limits, start_pose)
    if args.controller == "franka":
        tau = evaluate_torque(model, q - robot.controller_offsets, qd, qdd) if model.torque is not None else None
        problems = cp.franka_check(q, tau, rate, qd)
        if problems:
            raise ValueError(f"Franka export refused: {problems[0]}")
    if args.program is not None:
        if args.controller == "ur":  # the approach and the return: done by movej
            n_traj = len(traj.sample(rate, closed=True)[0])
            n_lead = (len(q) - n_traj) // 2
            cp.write_urscript(args.program, q[n_lead:n_lead + n_traj], rate, start_pose)
        else:
            cp.write_franka(args.program, q)
    ce.write_samples(args.out, t, q, qd, qdd)


def controller_rate(args: argparse.Namespace, robot: rx90sym.Robot) -> float:
    """The UR stream rate [Hz]: --controller-rate, else the robot file's [controller] rate_hz; a
    robot of unknown controller (a URDF) exits 2 naming the two UR rates (never a guess)."""
    from excitation import controller_programs as cp

    if args.controller_rate is not None:
        return float(args.controller_rate)
    if robot.controller_rate is not None:
        return float(robot.controller_rate)
    rates = ", ".join(f"{r:g} Hz for {name}" for name, r in cp.UR_RATES.items())
    raise UsageError(f"--controller ur: robot {robot.name!r} does not say its controller's rate ({rates}): "
                     f"give --controller-rate")
