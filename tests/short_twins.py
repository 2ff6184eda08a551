"""Short twin recordings of ordinary motions: the logs users bring (tests/test_own_choices.py).

The bundled Panda (7 joints, its [nominal] table as the truth) on synchronised trapezoidal
point-to-point moves (tests/twin_logs.py ``point_to_point``, short rests), a few seconds at 100 Hz (a few hundred samples),
the twin's "realistic" noise (tests/twin_logs.py ``COULOMB_SMOOTHING``) and a torque sensor offset per
joint drawn in 0.1-2 N m with a random sign; optionally some joints moving one way only (a speed that
never falls below half its mean: their Coulomb column is +1 on every row, as their offset's), some
never moving, some torque channels not logged (0 on every sample).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

import rx90sym
from rx90sym.recording import Recording

from twin_logs import COULOMB_SMOOTHING, point_to_point

__all__ = ["ShortTwin", "short_twin"]


@dataclass(frozen=True, eq=False)
class ShortTwin:
    """The recording, the robot, the true standard parameters and the sensor offsets added [N m]."""

    robot: rx90sym.Robot
    recording: Recording
    truth: dict
    offsets: np.ndarray


def _motion(robot: rx90sym.Robot, seed: int, duration: float, one_way: Sequence[int], still: Sequence[int]):
    base = point_to_point(robot, seed, duration, rest=(0.2, 0.4))
    centre = base(np.array([0.0]))[0][0]
    rng = np.random.default_rng([seed, 99])
    speeds = {j: (0.25 * robot.limits.qd_max[j], 2 * np.pi * rng.uniform(0.5, 1.0), rng.uniform(0, 2 * np.pi))
              for j in one_way}

    def traj(t):
        q, qd, qdd = base(t)
        for j in still:
            q[:, j], qd[:, j], qdd[:, j] = centre[j], 0.0, 0.0
        for j, (v, w, p) in speeds.items():  # v (1 + 0.6 sin(w t + p)) > 0: one way, never at rest
            q[:, j] = centre[j] - 0.5 * v * duration + v * (t - 0.6 / w * (np.cos(w * t + p) - np.cos(p)))
            qd[:, j] = v * (1 + 0.6 * np.sin(w * t + p))
            qdd[:, j] = v * 0.6 * w * np.cos(w * t + p)
        return q, qd, qdd

    return traj


def short_twin(seed: int, duration: float = 4.0, rate: float = 100.0, one_way: Sequence[int] = (),
               still: Sequence[int] = (), not_logged: Sequence[int] = (), offsets: bool = False,
               lag: float = 0.0) -> ShortTwin:
    """The Panda twin's recording (joints 0-based); ``offsets``: the robot with its own torque offsets
    OFFj; ``lag`` [s]: the torques logged that late behind the positions (whole samples)."""
    robot = rx90sym.load_robot("panda", offsets=offsets)
    truth = rx90sym.twin.default_parameters(robot)
    # A 2 kHz servo (stable with this friction slope, 1 kHz is not): half the 4 kHz profile's time.
    profile = replace(rx90sym.twin.profiles()["realistic"], coulomb_smoothing=COULOMB_SMOOTHING, servo_rate_hz=2000.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the ripple's assumed gear ratio
        rec = rx90sym.twin.simulate(robot, _motion(robot, seed, duration, one_way, still), params=truth,
                                    noise=profile, seed=seed, rate=rate, duration=duration)
    rng = np.random.default_rng([seed, 13])
    sensor = rng.uniform(0.1, 2.0, robot.n) * rng.choice((-1.0, 1.0), robot.n)
    tau = rec.tau + sensor
    k = int(round(lag * rate))
    if k:
        tau = np.concatenate([np.repeat(tau[:1], k, axis=0), tau[:-k]])
    tau[:, list(not_logged)] = 0.0
    return ShortTwin(robot, replace(rec, tau=tau, source=f"panda-short:{seed}"), truth, sensor)
