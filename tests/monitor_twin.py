"""Twin recordings with injected external-torque pulses, and fits on them, for the contact-monitor tests."""
from __future__ import annotations

from functools import lru_cache

import numpy as np

import rx90sym
from identify import Processing, fit
from motions import multisine
from rx90sym.recording import Recording

#: The fit's processing in these tests: fixed (no cross-validation), Coulomb friction, zero-Coulomb rest.
PROCESSING = Processing(cutoff=10.0, delay=0.0, estimate_delay=False, friction="coulomb", rest="zero-coulomb")
#: On the ideal twin (friction FS·sign(q̇) at every speed): no rest mask, the model is then exact.
EXACT = Processing(cutoff=10.0, delay=0.0, estimate_delay=False, friction="coulomb", min_velocity=None)


@lru_cache(maxsize=None)
def twin_run(name: str, seed: int, noise: str = "realistic", duration: float = 20.0) -> Recording:
    robot = rx90sym.load_robot(name)
    return rx90sym.twin.simulate(robot, multisine(robot, seed, duration=duration), duration=duration, noise=noise,
                                 seed=seed)


@lru_cache(maxsize=None)
def twin_fit(name: str, noise: str = "realistic", seed: int = 100):
    return fit(rx90sym.load_robot(name), [twin_run(name, seed, noise)], EXACT if noise == "ideal" else PROCESSING)


def pulses(robot: rx90sym.Robot, t: np.ndarray, seed: int, every: float = 1.5) -> tuple[np.ndarray, list]:
    """External torque (S, n) [N·m]: one rectangle per ``every`` seconds on a random joint, of random
    sign, size 5 N·m to 50 % of the joint's rated torque, duration 0.05-1 s; and the list
    (start, end, joint 0-based, size)."""
    rng = np.random.default_rng(seed)
    rated = np.asarray(robot.limits.tau_max, dtype=float)
    t = t - t[0]
    ext = np.zeros((t.size, robot.n))
    out = []
    for s in np.arange(1.0, t[-1] - 1.2, every):
        j = int(rng.integers(robot.n))
        A = rng.uniform(5.0, 0.5 * rated[j]) * rng.choice([-1, 1])
        d = rng.uniform(0.05, 1.0)
        d = min(d, every - 0.3)
        ext[(t >= s) & (t < s + d), j] += A
        out.append((float(s), float(s + d), j, float(A)))
    return ext, out


def with_external(rec: Recording, ext: np.ndarray) -> Recording:
    """The recording with an external torque ``ext`` acting on the arm: the arm follows the same motion
    (perfect tracking), so the motors deliver ext less (M q̈ + C q̇ + g + f = τ_m + τ_ext)."""
    return Recording(t=rec.t, q=rec.q, tau=rec.tau - ext, dq=rec.dq, source=f"{rec.source}+pulses", robot=rec.robot)


def ideal_response(t: np.ndarray, pulse_list: list, n: int, K: np.ndarray) -> np.ndarray:
    """The pulses passed through the observer's ideal response K/(s + K) (exact, continuous time)."""
    t = t - t[0]
    out = np.zeros((t.size, n))
    for s, e, j, A in pulse_list:
        k = K[j]
        rise = 1 - np.exp(-k * np.clip(t - s, 0, None))
        top = 1 - np.exp(-k * (e - s))
        out[:, j] += A * np.where(t < e, rise, top * np.exp(-k * (t - e)))
    return out
