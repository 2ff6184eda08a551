"""Short twin recordings of ordinary motions: the logs users bring (tests/test_own_choices.py).

The bundled Panda (7 joints, its [nominal] table as the truth) on synchronised trapezoidal
point-to-point moves (tests/twin_logs.py ``point_to_point``, short rests), a few seconds at 100 Hz (a few hundred samples),
the twin's "realistic" noise (tests/twin_logs.py ``COULOMB_SMOOTHING``) and a torque sensor offset per
joint drawn in 0.1-2 N m with a random sign; optionally some joints moving one way only (a speed that
never falls below half its mean: their Coulomb column is +1 on every row, as their offset's), some
never moving, some torque channels not logged (0 on every sample).

:data:`SHORT_CASES` (benchmarks/defaults_vs_yardsticks.py ``--short-twins``): a maker's URDF (the UR5 at
100 Hz, the Panda at 1 kHz) with the description the user holds (exact, 50 % off, not physical), a 3 s
point-to-point motion fitted and another 4 s predicted (:func:`short_logs`).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Sequence

import numpy as np

import rx90sym
from rx90sym.recording import Recording

from twin_logs import COULOMB_SMOOTHING, UR5_DRIVES, URDF_DIR, TwinLogs, logged_pair, maker_urdf, point_to_point

__all__ = ["ShortTwin", "short_twin", "ShortCase", "SHORT_CASES", "SHORT_KINDS", "PANDA_DRIVES", "described_urdf",
           "short_logs"]


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


SHORT_KINDS = ("exact", "off50", "nonphysical")
#: Rotor inertias, viscous and Coulomb friction of the Panda URDF twin (its URDF has none): about the
#: bundled Panda file's [nominal] drives.
PANDA_DRIVES = {"IA": (0.05, 0.05, 0.05, 0.05, 0.02, 0.02, 0.02), "FV": (0.6, 0.6, 0.6, 0.6, 0.3, 0.3, 0.3),
                "FS": (0.8, 0.8, 0.8, 0.8, 0.4, 0.4, 0.4)}


@dataclass(frozen=True)
class ShortCase:
    """A twin of the logs users hold: ``urdf`` ("ur5" at 100 Hz, "panda" at 1 kHz: the maker's URDF),
    a short point-to-point motion fitted (``fit_s`` [s], one or two moves: some joints move one way only)
    and another predicted (``predict_s``), the description the user has: ``kind`` "exact" (the twin's own
    bodies), "off50" (every link's mass, centre of mass and inertia at it scaled by factors drawn in
    0.5..1.5), "nonphysical" (off50, and two links' inertias breaking the triangle inequality)."""

    name: str
    urdf: str
    rate: float
    kind: str
    fit_s: float = 3.0
    predict_s: float = 4.0


SHORT_CASES = tuple(ShortCase(f"{u}-{k}", u, r, k) for u, r in (("ur5", 100.0), ("panda", 1000.0))
                    for k in SHORT_KINDS)
_TIPS = {"ur5": "tool0", "panda": "panda_link8"}
def described_urdf(text: str, kind: str, seed: int) -> str:
    """The URDF ``text`` with its inertials as the description of ``kind`` says (ShortCase); every draw
    seeded. Links with a mass of 0 are kept."""
    if kind == "exact":
        return text
    import xml.etree.ElementTree as ET

    root = ET.fromstring(text)
    inertials = [e for e in root.iter("inertial") if float(e.find("mass").get("value")) > 0]
    rng = np.random.default_rng([seed, 21])
    broken = set(rng.choice(len(inertials), 2, replace=False)) if kind == "nonphysical" else set()
    for k, e in enumerate(inertials):
        f = rng.uniform(0.5, 1.5, 3)
        mass, origin, inertia = e.find("mass"), e.find("origin"), e.find("inertia")
        mass.set("value", f"{float(mass.get('value')) * f[0]:.9g}")
        if origin is not None:
            origin.set("xyz", " ".join(f"{float(v) * f[1]:.9g}" for v in origin.get("xyz", "0 0 0").split()))
        keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
        I = {key: float(inertia.get(key, 0.0)) * f[2] for key in keys}
        if k in broken:  # ixx above iyy + izz: no mass distribution has it
            I["ixx"] = 1.5 * (I["iyy"] + I["izz"]) + 1e-4
        for key in keys:
            inertia.set(key, f"{I[key]:.9g}")
    return ET.tostring(root, encoding="unicode")


def short_logs(case: ShortCase, seed: int, workdir: Path) -> TwinLogs:
    """The two short logs of ``case`` for ``seed``: the twin of the maker's URDF (its inertials, the drives
    of UR5_DRIVES / PANDA_DRIVES) with a torque sensor offset per joint (0.1-2 N m, random sign), logged at
    the case's rate; the robot returned is the one the user loads: the URDF with the described inertials."""
    text = maker_urdf() if case.urdf == "ur5" else (URDF_DIR / "panda.urdf").read_text()
    workdir = Path(workdir)
    true_path, described = workdir / f"{case.urdf}_true.urdf", workdir / f"{case.name}_{seed}.urdf"
    true_path.write_text(text)
    described.write_text(described_urdf(text, case.kind, seed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the snapping report, no acceleration limits, non-physical inertials
        plant = rx90sym.load_robot(str(true_path), tip=_TIPS[case.urdf])
        robot = rx90sym.load_robot(str(described), tip=_TIPS[case.urdf])
    truth = dict(rx90sym.twin.default_parameters(plant))
    for key, values in (UR5_DRIVES if case.urdf == "ur5" else PANDA_DRIVES).items():
        truth.update({f"{key}{j + 1}": v for j, v in enumerate(values)})
    profile = replace(rx90sym.twin.profiles()["realistic"], stribeck=0.0, coulomb_smoothing=COULOMB_SMOOTHING)
    motions = [(label, point_to_point(plant, 1000 * seed + k, duration, rest=(0.3, 0.6)), duration)
               for k, (label, duration) in enumerate((("fit", case.fit_s), ("predict", case.predict_s)))]
    return logged_pair(plant, robot, motions, truth, profile, seed, case.rate, case.name)
