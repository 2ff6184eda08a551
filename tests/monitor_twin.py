"""Twin recordings with injected external-torque pulses, and fits on them, for the contact-monitor tests."""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, Iterable, Sequence

import numpy as np

import rx90sym
from identify import Processing, fit
from motions import multisine, stop_and_go
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


#: The runs the false-alarm tests fit on (three different multisines, 60 s: a fit on twin_fit's one 20 s
#: multisine misses the Panda's joint-1 torque by up to 2.5 N·m on other motions, 0.7 N·m with these),
#: and the contact-free run calibrate() sees.
FREE_FIT_SEEDS = (100, 101, 102)
FREE_CALIBRATION_SEED = 103


@lru_cache(maxsize=None)
def free_fit(name: str):
    """The fit of ``name`` on the three runs FREE_FIT_SEEDS (the processing of twin_fit)."""
    return fit(rx90sym.load_robot(name), [twin_run(name, s) for s in FREE_FIT_SEEDS], PROCESSING)


def toolkit_thresholds(name: str, F: Any, seeds: Sequence[int], calibration_seed: int) -> dict[str, np.ndarray]:
    """The thresholds [N·m] the toolkit makes for ``F`` (fitted on the twin runs ``seeds``): "identify",
    what rx90 identify stores without --validate (the fitted runs' held-out blocks), and "calibrate",
    identify.monitor.log.calibrate on the contact-free run ``calibration_seed``."""
    from identify.monitor.log import calibrate
    from identify.monitor.thresholds import with_contact_thresholds

    own, why = with_contact_thresholds(F, [twin_run(name, s) for s in seeds])
    if why:
        raise ValueError(f"{name}: no thresholds from the fit ({why})")
    return {"identify": own.contact_thresholds, "calibrate": calibrate(F, [twin_run(name, calibration_seed)])}


#: First seed of the contact-free runs (apart from the fits' 100-102, the calibrations' 101 and 103, the pulses' 0-4).
FREE_SEED0 = 1000
#: Every this many-th contact-free run holds rests (motions.stop_and_go: half of its samples at rest).
FREE_REST_EVERY = 3


def free_run(name: str, k: int, duration: float = 20.0) -> Recording:
    """Contact-free run number ``k`` (0, 1, ...) on the realistic twin: a multisine of seed
    FREE_SEED0 + k (its own frequencies, phases, amplitudes and noise draws), run with rests
    (stop_and_go) when k % FREE_REST_EVERY == FREE_REST_EVERY - 1. Not cached (an hour of runs)."""
    robot = rx90sym.load_robot(name)
    seed = FREE_SEED0 + k
    motion = multisine(robot, seed, duration=duration)
    if k % FREE_REST_EVERY == FREE_REST_EVERY - 1:
        motion = stop_and_go(motion)
    return rx90sym.twin.simulate(robot, motion, duration=duration, noise="realistic", seed=seed)


@dataclass
class FreeScan:
    """The monitor over contact-free runs, each monitored on its own (observer reset between runs):
    seconds monitored, events [(run k, ContactEvent, moving)] (moving: some event joint above the fit's
    rest threshold at the event's start), margin (n,) the largest |r_j| / (T_j + d_j) over all samples
    (below 1 everywhere: no joint ever active), and where it was: (run k, t [s], |q̇_j| [rad/s]) per joint."""

    thresholds: np.ndarray
    seconds: float = 0.0
    events: list = field(default_factory=list)
    margin: np.ndarray | None = None
    where: list = field(default_factory=list)

    def add(self, k: int, rec: Recording, res: Any, vmin: float) -> None:
        ratio = np.abs(res.residual) / (self.thresholds + res.slack)
        if self.margin is None:
            self.margin, self.where = np.zeros(ratio.shape[1]), [None] * ratio.shape[1]
        tt = rec.t - rec.t[0]
        qd = rec.dq if rec.dq is not None else np.gradient(rec.q, rec.t, axis=0, edge_order=2)  # as monitor_log
        for j, i in enumerate(np.argmax(ratio, axis=0)):
            if ratio[i, j] > self.margin[j]:
                self.margin[j], self.where[j] = ratio[i, j], (k, float(tt[i]), float(abs(qd[i, j])))
        for e in res.events:
            i = int(np.searchsorted(tt, e.start_s))
            moving = any(abs(qd[i, j - 1]) > vmin for j in e.joints)
            self.events.append((k, e, moving))
        self.seconds += res.duration_s


def scan_free_motion(name: str, fit: Any, thresholds: dict[str, np.ndarray], runs: Iterable[int],
                     duration: float = 20.0) -> dict[str, FreeScan]:
    """Monitor the contact-free runs ``runs`` of robot ``name`` (numbers k of :func:`free_run`) with each set of
    thresholds (label -> T per joint [N·m]); one simulation per run, the observer reset between runs."""
    from identify.monitor.log import monitor_log
    from identify.monitor.observer import observer_model
    from identify.observation.processing import DEFAULT_MIN_VELOCITY

    model = observer_model(fit, "torque")
    vmin = fit.min_velocity or DEFAULT_MIN_VELOCITY
    out = {label: FreeScan(np.asarray(T, dtype=float)) for label, T in thresholds.items()}
    for k in runs:
        rec = free_run(name, k, duration)
        for label, scan in out.items():
            scan.add(k, rec, monitor_log(fit, rec, scan.thresholds, keep=True, model=model), vmin)
    return out
