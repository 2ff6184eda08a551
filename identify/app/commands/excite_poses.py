"""``rx90 excite``: poses the user types (controller angles, as are the envelope's settings,
messages and description: excitation/envelope.py), and the envelope's refusals in the user's terms."""
from __future__ import annotations

import re
from typing import TYPE_CHECKING, Any

from ..common import UsageError

if TYPE_CHECKING:  # annotations only: the model is imported when the command runs
    import rx90sym


def check_start_pose(robot: rx90sym.Robot, model: Any, start_pose: Any) -> None:
    """A --start-pose must lie in the robot's ranges and (model given) inside the envelope,
    naming the point that leaves it."""
    import numpy as np

    from excitation.envelope import pose_violations, range_violations

    if start_pose is None:
        return
    offsets = robot.controller_offsets
    bad = range_violations(np.asarray(start_pose), robot.limits.q_min + offsets, robot.limits.q_max + offsets,
                           "robot's")
    if bad:
        raise UsageError(f"--start-pose: {bad[0]}")
    if model is None:  # the ranges only (the envelope needs the model)
        return
    bad = [v for v in pose_violations(model, np.asarray(start_pose) - robot.controller_offsets)
           if "outside the experiment" not in v]
    if bad:
        typed = ",".join(f"{v:.6g}" for v in start_pose)
        raise UsageError(name_frames(robot, f"--start-pose {typed} is outside the safety envelope: {bad[0]}"))


# The envelope's settings as the library names them in its messages, and the options setting them.
_OPTIONS = (("position limits", "--position-limits"), ("centre pose", "--centre-pose"))


def name_frames(robot: rx90sym.Robot, message: str) -> str:
    """An envelope refusal in the user's terms: the option for the setting it names, a URDF
    robot's "origin of frame j" named with its link ("origin of frame 3 (link forearm_link)": the
    user knows the links, not the model's frame numbers), and heights said to be in frame 0, with
    where the mounting plane lies in it."""
    from excitation.robot_geometry import arm_geometry

    for setting, option in _OPTIONS:
        if message.startswith(setting):
            message = option + message[len(setting):]

    links = robot.urdf.links if robot.urdf is not None else ()

    def named(m: re.Match) -> str:
        j = int(m.group(1))
        return f"{m.group(0)} (link {links[j - 1]})" if 1 <= j <= len(links) else m.group(0)

    if links:
        message = re.sub(r"origin of frame (\d+)", named, message)
    if "lowest allowed z" in message:
        message += f" (z in frame 0, where the mounting plane is z = {arm_geometry(robot).mounting_z:.4g} m)"
    return message
