"""Export at a controller's rate and form, with an approach move from a given start pose.

Controllers stream set-points at a fixed rate: a UR's servoj at 500 Hz, a Franka's joint
position interface at 1 kHz, which also bounds the jerk (libfranka's documented joint jerk
limits, FRANKA_JERK_MAX). The file has the same columns as Trajectory.save (t, q, dq, ddq in
controller angles), sampled at the controller's period, with an approach move first and the
same move back at the end when a start pose is given: a quintic rest-to-rest move s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5, whose
peaks are 1.875 D/T (velocity), 5.7735 D/T^2 (acceleration), 60 D/T^3 (jerk) for a step D over T,
so T is the smallest multiple of the period that keeps every joint within its limits.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .export import write_csv

FRANKA_JERK_MAX = (7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0)  # rad/s^3


@dataclass(frozen=True)
class Controller:
    """Set-point stream of a controller: rate [Hz], jerk limits [rad/s^3] (None: unchecked)."""

    name: str
    rate: float
    jerk_max: tuple[float, ...] | None = None


CONTROLLERS = {"ur": Controller("ur", 500.0), "franka": Controller("franka", 1000.0, FRANKA_JERK_MAX)}


def approach_duration(q_from: np.ndarray, q_to: np.ndarray, qd_max: np.ndarray, qdd_max: np.ndarray,
                      jerk_max: np.ndarray | None, period: float) -> float:
    """Shortest duration [s] (a multiple of period) of the quintic move within the limits."""
    step = np.abs(np.asarray(q_to, float) - np.asarray(q_from, float))
    with np.errstate(divide="ignore", invalid="ignore"):
        bounds = [1.875 * step / qd_max, np.sqrt(5.7735 * step / qdd_max)]
        if jerk_max is not None:
            bounds.append(np.cbrt(60.0 * step / jerk_max))
    t = float(np.nanmax(np.concatenate(bounds))) if step.size else 0.0
    return max(period, float(np.ceil(t / period - 1e-9)) * period)


def approach_samples(q_from: np.ndarray, q_to: np.ndarray, duration: float, rate: float
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(t, q, qd, qdd) of the quintic move at ``rate``, t in [0, duration) [s]."""
    t = np.arange(int(round(duration * rate))) / rate
    tau = (t / duration)[:, None]
    d = (np.asarray(q_to, float) - np.asarray(q_from, float))[None, :]
    s = 10 * tau ** 3 - 15 * tau ** 4 + 6 * tau ** 5
    sd = (30 * tau ** 2 - 60 * tau ** 3 + 30 * tau ** 4) / duration
    sdd = (60 * tau - 180 * tau ** 2 + 120 * tau ** 3) / duration ** 2
    return t, q_from + d * s, d * sd, d * sdd


def controller_samples(trajectory: Any, controller: str | Controller, limits: Any, start_pose: Any = None
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(t, q, qd, qdd) at the controller's rate in controller angles, between an approach move from
    ``start_pose`` and the return to it (controller angles [rad], None: neither; the robot must
    then be at the trajectory's start, where it also ends). limits: qd_max, qdd_max (n,) [rad/s, rad/s^2] for the approach. Raises
    ValueError naming the joint and the time when the controller's jerk limit is exceeded."""
    ctrl = CONTROLLERS[controller] if isinstance(controller, str) else controller
    offsets = trajectory.controller_offsets
    t, q, qd, qdd = trajectory.sample(ctrl.rate, closed=True)
    q = q + offsets
    parts = [(t, q, qd, qdd)]
    if start_pose is not None:
        start = np.asarray(start_pose, dtype=float).reshape(-1)
        if start.shape != (trajectory.n,):
            raise ValueError(f"start pose: {start.size} angles for a {trajectory.n}-joint robot")
        jerk = None if ctrl.jerk_max is None else np.asarray(ctrl.jerk_max[:trajectory.n])
        duration = approach_duration(start, q[0], np.asarray(limits.qd_max), np.asarray(limits.qdd_max),
                                     jerk, 1.0 / ctrl.rate)
        ta, qa, qda, qdda = approach_samples(start, q[0], duration, ctrl.rate)
        # The return: the same quintic back along the same path (the trajectory ends where it
        # starts), its first sample dropped (it is the trajectory's last) and the start pose added.
        tb, qb, qdb, qddb = approach_samples(q[-1], start, duration, ctrl.rate)
        zero = np.zeros((1, trajectory.n))
        back = (np.r_[tb[1:], duration] + duration + t[-1], np.vstack([qb[1:], start]),
                np.vstack([qdb[1:], zero]), np.vstack([qddb[1:], zero]))
        parts = [(ta, qa, qda, qdda), (t + duration, q, qd, qdd), back]
    t, q, qd, qdd = (np.concatenate(x) for x in zip(*parts))
    if ctrl.jerk_max is not None:
        jerk = np.diff(qdd, axis=0) * ctrl.rate
        ratio = np.abs(jerk) / np.asarray(ctrl.jerk_max[:trajectory.n])
        k, j = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
        if ratio[k, j] > 1.0:
            raise ValueError(f"{ctrl.name} export: joint {j + 1} jerk {jerk[k, j]:.6g} rad/s^3 at "
                             f"t = {t[k]:.4g} s exceeds the limit {ctrl.jerk_max[j]:g} rad/s^3")
    return t, q, qd, qdd


def write_samples(path: str | os.PathLike, t: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> Path:
    """CSV t, q1..qn, dq1..dqn, ddq1..ddqn (s, rad, rad/s, rad/s^2), atomically."""
    n = q.shape[1]
    header = (["t"] + [f"q{j}" for j in range(1, n + 1)] + [f"dq{j}" for j in range(1, n + 1)]
              + [f"ddq{j}" for j in range(1, n + 1)])
    return write_csv(path, header, np.hstack([t[:, None], q, qd, qdd]))


def export_for_controller(trajectory: Any, path: str | os.PathLike, controller: str | Controller,
                          limits: Any, start_pose: Any = None) -> Path:
    """Write :func:`controller_samples` as CSV (nothing is written when they are refused)."""
    return write_samples(path, *controller_samples(trajectory, controller, limits, start_pose))
