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
