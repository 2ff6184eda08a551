"""Hand-made excitation motions for tests (the paper's 'intuitive' motions): each joint a sum of
sines of different frequencies around a mid-range posture, rest-to-rest through a smooth window."""
from __future__ import annotations

import numpy as np


def multisine(robot, seed: int, duration: float = 20.0, fraction: float = 0.6):
    """Callable t -> (q, qd, qdd) within the robot's limits (Khalil angles)."""
    rng = np.random.default_rng(seed)
    lim = robot.limits
    lo = np.maximum(lim.q_min, -np.pi)
    hi = np.minimum(lim.q_max, np.pi)
    centre = (lo + hi) / 2
    amp_q = fraction * (hi - lo) / 2
    k = 3
    freqs = rng.choice(np.arange(1, 9), size=(k, robot.n)) / duration * 2 * np.pi  # rad/s
    phases = rng.uniform(0, 2 * np.pi, (k, robot.n))
    weights = rng.uniform(0.5, 1.0, (k, robot.n))
    # Velocity limit: sum |a w| <= 0.6 qd_max; acceleration: sum |a w^2| <= 0.6 qdd_max.
    unit = weights / weights.sum(axis=0)
    amp = amp_q * unit
    scale_v = 0.6 * lim.qd_max / np.sum(amp * freqs, axis=0)
    scale_a = 0.6 * lim.qdd_max / np.sum(amp * freqs**2, axis=0)
    amp = amp * np.minimum(1.0, np.minimum(scale_v, scale_a))

    def traj(t):
        t = np.atleast_1d(np.asarray(t, float))[:, None, None]
        s = np.sin(freqs * t + phases) - np.sin(phases)
        c = np.cos(freqs * t + phases)
        q = centre + np.sum(amp * s, axis=1)
        qd = np.sum(amp * freqs * c, axis=1)
        qdd = -np.sum(amp * freqs**2 * np.sin(freqs * t + phases), axis=1)
        return q, qd, qdd

    return traj


def stop_and_go(traj, period: float = 4.0):
    """The motion ``traj`` (callable t -> (q, qd, qdd)) run with rests: its own time advances at the
    speed sin²(2πt/period) during the first half of every period and stands still during the second
    (C¹ time warp, so q̈ stays continuous). Half of the samples are at rest."""
    w = 2 * np.pi / period

    def warped(t):
        t = np.atleast_1d(np.asarray(t, float))
        k, tau = np.divmod(t, period)
        moving = tau < period / 2
        s = k * period / 4 + np.where(moving, tau / 2 - np.sin(2 * w * tau) / (4 * w), period / 4)
        g = np.where(moving, np.sin(w * tau) ** 2, 0.0)             # ds/dt
        dg = np.where(moving, w * np.sin(2 * w * tau), 0.0)          # d²s/dt²
        q, qd, qdd = traj(s)
        return q, qd * g[:, None], qdd * g[:, None] ** 2 + qd * dg[:, None]

    return warped


# Plausible true parameters for a Panda twin (no bundled nominal set yet): link masses close to
# those identified for the Panda in the literature (kg), centres of mass on the z axes, diagonal
# inertias of 0.02 m^2 x mass, rotor inertia 0.05 kg m^2, viscous 0.6 N m s/rad, Coulomb 0.4 N m.
PANDA_MASSES = (4.97, 0.646, 3.228, 3.587, 1.225, 1.666, 0.735)


def panda_truth(robot) -> dict:
    """name -> value of the Panda twin's true standard parameters (SI)."""
    p = {}
    for j, m in enumerate(PANDA_MASSES, start=1):
        p.update({f"{k}{j}": 0.0 for k in ("XY", "XZ", "YZ", "MX", "MY")})
        p.update({f"{k}{j}": 0.02 * m for k in ("XX", "YY", "ZZ", "MZ")})
        p.update({f"M{j}": m, f"IA{j}": 0.05, f"FV{j}": 0.6, f"FS{j}": 0.4})
    assert set(p) == set(robot.parameter_names)
    return p
