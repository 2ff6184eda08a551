"""Twin logs of the unseen-robot trial: a chirp fitted, a trapezoidal point-to-point motion predicted.

The trial of issue 29 ("a small 6-joint arm with its maker's URDF, positions and joint torques
logged at 100 Hz, a chirp motion fitted, a second trapezoidal motion predicted") on twins, shared by
tests/end_to_end/test_defaults_beat_baseline.py and benchmarks/defaults_vs_yardsticks.py (``--twins``):

- ``ur5``: the UR5 URDF of example-robot-data (tests/data/urdf/ur5.urdf) rewritten as makers write
  it (pi/2 as 1.5708 and -1.5708, 1e-6 m residues; :func:`maker_urdf`), loaded with the defaults
  (the loader snaps it back to the exact model), its URDF inertials plus rotor inertias and friction
  (:data:`UR5_DRIVES`), logged at 100 Hz;
- ``panda``: the bundled Panda (its [nominal] table: inertials, rotor inertias and friction), 1 kHz;

each with a torque sensor offset per joint drawn uniformly in 0.1-2 N m with a random sign (added
to the recorded torques of both motions), and the plant's friction with or without a static part
(Stribeck: ``stribeck`` x FSj extra at zero speed, :class:`rx90sym.twin.NoiseProfile`; 0: Coulomb
and viscous only). The rest of the noise is the twin's "realistic" profile: closed-loop tracking,
motor torque ripple, 2^19-count encoders, torque noise of 1.5 % of each joint's RMS.

Motions (Khalil angles, within 0.5 x the velocity and acceleration limits): :func:`chirp`, each
joint a sine swept in frequency (its own range and phase) with an amplitude capped by the limits
and ramped in and out; :func:`point_to_point`, synchronised trapezoidal velocity moves between random
waypoints with rests between them (a rest at both ends).
"""
from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Sequence

import numpy as np

import rx90sym
from rx90sym.recording import Recording

__all__ = ["TwinCase", "CASES", "TwinLogs", "twin_logs", "chirp", "point_to_point", "maker_urdf", "case_robot",
           "UR5_DRIVES", "STATIC_PART"]

URDF_DIR = Path(__file__).resolve().parent / "data" / "urdf"
#: Rotor inertias [kg m²], viscous [N m s/rad] and Coulomb [N m] friction of the UR5 twin (the URDF has
#: none): about those identified on UR5s in the literature (large joints 1-3, wrist 4-6).
UR5_DRIVES = {"IA": (0.25, 0.25, 0.12, 0.04, 0.04, 0.04), "FV": (4.0, 4.0, 2.5, 0.8, 0.8, 0.8),
              "FS": (5.0, 5.0, 3.5, 1.2, 1.2, 1.2)}
#: The static part of the friction where a case has one: Stribeck peak, fraction of FSj (the
#: "realistic" profile has 0.1), over about 0.05 rad/s.
STATIC_PART = 0.5
#: The plant's Coulomb friction FS tanh(qd / this) [rad/s] (the "realistic" profile's 0.002 rad/s is too
#: steep for the 4 kHz servo step on the UR5's light wrist with its Coulomb friction and Stribeck peak).
COULOMB_SMOOTHING = 0.006


@dataclass(frozen=True)
class TwinCase:
    """One twin: robot ("ur5": the maker's URDF; "panda": bundled), log rate [Hz], Stribeck static
    part (fraction of FSj; 0: none), durations of the fitted chirp and of the predicted
    point-to-point motion [s]."""

    name: str
    robot: str
    rate: float
    stribeck: float
    fit_s: float = 25.0
    predict_s: float = 18.0


CASES = (TwinCase("ur5-100Hz-static", "ur5", 100.0, STATIC_PART), TwinCase("ur5-100Hz-no-static", "ur5", 100.0, 0.0),
         TwinCase("panda-1kHz-static", "panda", 1000.0, STATIC_PART),
         TwinCase("panda-1kHz-no-static", "panda", 1000.0, 0.0))


def maker_urdf(path: Path = URDF_DIR / "ur5.urdf") -> str:
    """The URDF text of ``path`` as makers write it: every origin angle of ±pi/2 written 1.5708
    (4 decimals), and 1e-6 m residues on two joint origins (shoulder lift, elbow)."""
    text = path.read_text()
    text = re.sub(r"(-?)1\.57079632679489\d*", r"\g<1>1.5708", text)
    for old, new in (('<origin xyz="0 0.13585 0" rpy="0 1.5708 0"/>', '<origin xyz="1e-06 0.13585 0" rpy="0 1.5708 0"/>'),
                     ('<origin xyz="0 -0.1197 0.425" rpy="0 0 0"/>', '<origin xyz="0 -0.1197 0.425001" rpy="0 0 0"/>')):
        if text.count(old) != 1:
            raise ValueError(f"{path}: expected the origin {old!r} once")
        text = text.replace(old, new)
    return text


def case_robot(case: TwinCase, workdir: Path) -> tuple[rx90sym.Robot, dict[str, float]]:
    """(robot loaded with the defaults, its true standard parameters). The UR5's URDF is written as
    a maker's into ``workdir``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the snapping report and the URDF's missing acceleration limits
        if case.robot == "panda":
            robot = rx90sym.load_robot("panda")
            return robot, rx90sym.twin.default_parameters(robot)
        path = Path(workdir) / "ur5_maker.urdf"
        path.write_text(maker_urdf())
        robot = rx90sym.load_robot(str(path), tip="tool0")
    truth = dict(rx90sym.twin.default_parameters(robot))
    for key, values in UR5_DRIVES.items():
        truth.update({f"{key}{j + 1}": v for j, v in enumerate(values)})
    return robot, truth


def _numeric(q_of_t, h1: float = 1e-5, h2: float = 1e-3):
    """t -> (q, qd, qdd) from t -> q by central differences (errors ~1e-9 relative on these motions)."""
    def traj(t):
        t = np.atleast_1d(np.asarray(t, float))
        q = q_of_t(t)
        qd = (q_of_t(t + h1) - q_of_t(t - h1)) / (2 * h1)
        qdd = (q_of_t(t + h2) - 2 * q + q_of_t(t - h2)) / h2**2
        return q, qd, qdd
    return traj


def _span(robot: rx90sym.Robot) -> tuple[np.ndarray, np.ndarray]:
    """(centre, half range) of each joint [rad] (ranges capped at ±pi)."""
    lo, hi = np.maximum(robot.limits.q_min, -np.pi), np.minimum(robot.limits.q_max, np.pi)
    return (lo + hi) / 2, (hi - lo) / 2


def chirp(robot: rx90sym.Robot, seed: int, duration: float = 25.0, ramp: float = 1.5):
    """t -> (q, qd, qdd): each joint c + A(f) w(t) sin(phi(t)), its frequency f swept linearly from
    f0 in [0.05, 0.12] Hz to f1 in [0.6, 1.0] Hz (drawn per joint), a random phase, the amplitude
    A(f) = min(0.6 x half range, 0.5 qd_max / 2 pi f, 0.5 qdd_max / (2 pi f)²), and a raised-cosine
    window w of ``ramp`` seconds at both ends (rest to rest)."""
    rng = np.random.default_rng([seed, 11])
    n = robot.n
    f0, f1 = rng.uniform(0.05, 0.12, n), rng.uniform(0.6, 1.0, n)
    phase = rng.uniform(0, 2 * np.pi, n)
    centre, half = _span(robot)
    lim = robot.limits

    def q_of_t(t):
        t = t[:, None]
        f = f0 + (f1 - f0) * np.clip(t, 0, duration) / duration
        phi = 2 * np.pi * (f0 * t + (f1 - f0) * t**2 / (2 * duration)) + phase
        w = 2 * np.pi * f
        amp = np.minimum(np.minimum(0.6 * half, 0.5 * lim.qd_max / w), 0.5 * lim.qdd_max / w**2)
        edge = np.clip(np.minimum(t, duration - t) / ramp, 0, 1)
        window = 0.5 - 0.5 * np.cos(np.pi * edge)
        return centre + amp * window * (np.sin(phi) - np.sin(phase))

    return _numeric(q_of_t)


def point_to_point(robot: rx90sym.Robot, seed: int, duration: float = 18.0, rest: tuple[float, float] = (0.6, 1.5)):
    """t -> (q, qd, qdd): synchronised trapezoidal velocity moves (0.5 x the velocity and acceleration
    limits, every joint starting and stopping together) between waypoints drawn within 0.5 x each
    joint's half range of its centre, from the chirp's start (the centre), a rest of ``rest`` seconds
    (drawn) before each move and at the end; moves until ``duration`` [s]."""
    rng = np.random.default_rng([seed, 12])
    centre, half = _span(robot)
    vmax, amax = 0.5 * robot.limits.qd_max, 0.5 * robot.limits.qdd_max
    segments = []  # (start time, q start, q end, move duration, accel time)
    t, here = 0.0, centre.copy()
    while True:
        t += rng.uniform(*rest)
        target = centre + rng.uniform(-0.5, 0.5, robot.n) * half
        d = np.abs(target - here)
        # the slowest joint sets the move: T = d/v + v/a when the cruise is reached, else 2 sqrt(d/a)
        times = np.where(d > vmax**2 / amax, d / vmax + vmax / amax, 2 * np.sqrt(d / amax))
        T = float(np.max(times))
        ta = T / 2 - math.sqrt(max(T**2 / 4 - float(np.max(d / amax)), 0.0))  # accel time fitting every joint
        if t + T + rest[0] > duration:
            break
        segments.append((t, here, target, T, max(ta, 1e-3)))
        t, here = t + T, target

    def q_of_t(tt):
        q = np.tile(centre, (tt.size, 1))
        for start, a, b, T, ta in segments:
            s = np.clip(tt - start, 0, T)
            # unit trapezoid of duration T, accel time ta: position fraction 0..1
            v = 1.0 / (T - ta)
            frac = np.where(s < ta, 0.5 * v / ta * s**2,
                            np.where(s < T - ta, v * (s - ta / 2), 1 - 0.5 * v / ta * (T - s) ** 2))
            q = np.where((tt >= start)[:, None], a + np.outer(frac, b - a), q)
        return q

    return _numeric(q_of_t, h2=1e-4)


@dataclass(frozen=True, eq=False)
class TwinLogs:
    """The fitted and the predicted recording of one case and seed, the robot, the true standard
    parameters and the torque sensor offsets added [N m]."""

    robot: rx90sym.Robot
    fitted: Recording
    predicted: Recording
    truth: dict
    offsets: np.ndarray


def twin_logs(case: TwinCase, seed: int, workdir: Path, robot: rx90sym.Robot | None = None) -> TwinLogs:
    """The two logs of ``case`` for ``seed`` (every draw seeded: motions, offsets, noise)."""
    loaded, truth = case_robot(case, workdir)
    robot = robot or loaded
    profile = replace(rx90sym.twin.profiles()["realistic"], stribeck=case.stribeck, coulomb_smoothing=COULOMB_SMOOTHING)
    motions = (("chirp", chirp(robot, seed, case.fit_s), case.fit_s),
               ("p2p", point_to_point(robot, seed, case.predict_s), case.predict_s))
    return logged_pair(robot, robot, motions, truth, profile, seed, case.rate, case.name)


def logged_pair(plant: rx90sym.Robot, robot: rx90sym.Robot, motions: Sequence[tuple], truth: dict, profile: Any,
                seed: int, rate: float, name: str) -> TwinLogs:
    """The fitted and the predicted log of ``plant`` under ``truth``: ``motions`` (label, motion, duration [s])
    simulated with ``profile`` at ``rate`` [Hz], a torque sensor offset per joint (0.1-2 N m, random sign,
    the same on both) added; ``robot``: the one the user loads."""
    rng = np.random.default_rng([seed, 13])
    offsets = rng.uniform(0.1, 2.0, plant.n) * rng.choice((-1.0, 1.0), plant.n)
    out = []
    for k, (label, motion, duration) in enumerate(motions):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the ripple's assumed gear ratio (the URDF gives none)
            rec = rx90sym.twin.simulate(plant, motion, params=truth, noise=profile, seed=2 * seed + k,
                                        rate=rate, duration=duration)
        out.append(replace(rec, tau=rec.tau + offsets, source=f"{name}:{label}:{seed}"))
    return TwinLogs(robot, out[0], out[1], truth, offsets)
