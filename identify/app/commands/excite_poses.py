"""``rx90 excite``: joint ranges and poses the user types, checked in controller angles (the
envelope works in model angles; a message quotes what the user typed)."""
from __future__ import annotations

import re
from typing import Any

import numpy as np

import rx90sym

from ..common import UsageError


def check_ranges(robot: rx90sym.Robot, values: np.ndarray) -> None:
    """--position-limits (n, 2) [rad, controller angles]: positive width, inside the robot's ranges."""
    lo, hi = robot.limits.q_min + robot.controller_offsets, robot.limits.q_max + robot.controller_offsets
    for j, (a, b) in enumerate(values):
        if not b > a:
            raise UsageError(f"--position-limits: joint {j + 1}: max {b:.6g} rad is not above min {a:.6g} rad "
                             f"(zero or negative width)")
        if a < lo[j] - 1e-12 or b > hi[j] + 1e-12:
            raise UsageError(f"--position-limits: joint {j + 1}: [{a:.6g}, {b:.6g}] rad leave the robot's range "
                             f"[{lo[j]:.6g}, {hi[j]:.6g}] rad (controller angles)")


def check_pose(what: str, robot: rx90sym.Robot, pose: np.ndarray, q_min: np.ndarray, q_max: np.ndarray,
                whose: str) -> None:
    """A pose [rad, controller angles] inside ranges given in model angles, the message in controller angles."""
    lo, hi = q_min + robot.controller_offsets, q_max + robot.controller_offsets
    for j in range(robot.n):
        if not lo[j] <= pose[j] <= hi[j]:
            raise UsageError(f"{what}: joint {j + 1} at {pose[j]:.6g} rad is outside the {whose} range "
                             f"[{lo[j]:.6g}, {hi[j]:.6g}] rad (controller angles)")


def check_start_pose(robot: rx90sym.Robot, model: Any, start_pose: Any) -> None:
    """A --start-pose must lie in the robot's ranges and (model given) inside the envelope,
    naming the point that leaves it."""
    from excitation.envelope import pose_violations

    if start_pose is None:
        return
    check_pose("--start-pose", robot, np.asarray(start_pose), robot.limits.q_min, robot.limits.q_max, "robot's")
    if model is None:  # the ranges only (the envelope needs the model)
        return
    bad = [v for v in pose_violations(model, np.asarray(start_pose) - robot.controller_offsets)
           if "outside the experiment" not in v]
    if bad:
        raise UsageError(name_frames(robot, f"--start-pose is outside the safety envelope: {bad[0]}"))


def envelope_lines(robot: rx90sym.Robot, described: dict[str, Any]) -> list[str]:
    """The envelope's printed lines with its joint ranges and centre pose in controller angles,
    the angles of --position-limits, --centre-pose and --start-pose (the description, as in the
    JSON, stays in model angles)."""
    import excitation

    offsets = robot.controller_offsets
    shown = dict(described)
    shown["position_limits_rad"] = (np.asarray(described["position_limits_rad"]) + offsets[:, None]).tolist()
    if described.get("centre_pose_rad") is not None:
        shown["centre_pose_rad"] = (np.round(np.asarray(described["centre_pose_rad"]) + offsets, 9) + 0.0).tolist()
    return [line.replace(" [deg]:", " [deg, controller angles]:") for line in excitation.envelope_lines(shown)]


def name_frames(robot: rx90sym.Robot, message: str) -> str:
    """An envelope refusal in the user's terms: a URDF robot's "origin of frame j" named with its
    link ("origin of frame 3 (link forearm_link)": the user knows the links, not the model's frame
    numbers), and heights said to be in frame 0, with where the mounting plane lies in it."""
    from excitation.robot_geometry import arm_geometry

    links = robot.urdf.links if robot.urdf is not None else ()

    def named(m: re.Match) -> str:
        j = int(m.group(1))
        return f"{m.group(0)} (link {links[j - 1]})" if 1 <= j <= len(links) else m.group(0)

    if links:
        message = re.sub(r"origin of frame (\d+)", named, message)
    if "lowest allowed z" in message:
        message += f" (z in frame 0, where the mounting plane is z = {arm_geometry(robot).mounting_z:.4g} m)"
    return message
