"""Figures of docs/robot-files.md (issue 13): the spring from data and the twin's ripple without gears.

    PYTHONPATH=. python benchmarks/spring_and_ripple.py        (about 2 min on one core)

Spring: twin RX90 with a spring unknown to the fit (k 2500 N/m, a 0.12 m, b 0.35 m, L0 0.08 m),
realistic noise, 4 motions of 20 s, WLS with min_velocity 0.1: k for the known geometry with its
sigma, and the held-out RMS torque error of the Fourier-series spring over that of the true one.
Ripple: the RX90 file without [transmission], realistic twin: base parameters within 3 sigma.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import identify  # noqa: E402
import rx90sym  # noqa: E402
from identify.observation.spring_fit import spring_base  # noqa: E402
from motions import multisine  # noqa: E402
from rx90sym.robot_file import ROBOTS_DIR  # noqa: E402
from rx90sym.spring import Spring, SpringBasis, SpringStiffness  # noqa: E402

UNKNOWN = Spring(joint=1, k=2500.0, a=0.12, b=0.35, L0=0.08, angle_offset=np.pi / 2)


def spring(rx90: rx90sym.Robot, chi: np.ndarray, first_seed: int) -> str:
    base = rx90sym.base_parameters(rx90)
    twin_robot, bare = rx90.with_options(spring=UNKNOWN), rx90.with_options(spring=None)
    runs = [rx90sym.twin.simulate(twin_robot, multisine(rx90, s), params=chi, duration=20.0, seed=s)
            for s in range(first_seed, first_seed + 4)]
    held = rx90sym.twin.simulate(twin_robot, multisine(rx90, first_seed + 50), params=chi, duration=20.0,
                                 seed=first_seed + 50)
    known = identify.fit(twin_robot, runs, identify.Processing(min_velocity=0.1, rest="drop", estimate_delay=False), base=base).result
    rms_known = identify.validate(twin_robot, known, held, base=base).rms_error
    sk = spring_base(bare, SpringStiffness(UNKNOWN), base)
    res_k = identify.fit(bare, runs, identify.Processing(min_velocity=0.1, spring=False, rest="drop", estimate_delay=False), base=sk).result
    i = res_k.names.index("KS_2")
    sb = spring_base(bare, SpringBasis(1), base)
    res = identify.fit(bare, runs, identify.Processing(min_velocity=0.1, spring=False, rest="drop", estimate_delay=False), base=sb).result
    ratio = identify.validate(bare, res, held, base=sb, spring=False).rms_error / rms_known
    return (f"spring, seeds {first_seed}-{first_seed + 3}, held-out {first_seed + 50}: k = "
            f"{res_k.values[i]:.1f} +- {res_k.std[i]:.1f} (z {(res_k.values[i] - UNKNOWN.k) / res_k.std[i]:+.2f}); "
            f"held-out RMS Fourier/true spring: {np.round(ratio, 4).tolist()}")


def ripple(chi: np.ndarray, first_seed: int, tmp: Path) -> str:
    text = (ROBOTS_DIR / "rx90.toml").read_text()
    (tmp / "gearless.toml").write_text(text[:text.index("[transmission]")] + text[text.index("[coupling]"):])
    robot = rx90sym.load_robot(tmp / "gearless.toml")
    base = rx90sym.base_parameters(robot)
    runs = [rx90sym.twin.simulate(robot, multisine(robot, s), params=chi, duration=20.0, seed=s)
            for s in range(first_seed, first_seed + 4)]
    res = identify.fit(robot, runs, identify.Processing(min_velocity=0.1, rest="drop", estimate_delay=False), base=base).result
    z = (res.values - base.beta(chi)) / res.std
    return (f"ripple without gears, seeds {first_seed}-{first_seed + 3}: {int(np.sum(np.abs(z) <= 3))}/{len(z)} "
            f"within 3 sigma, max |z| {np.max(np.abs(z)):.1f}")


def main() -> None:
    import tempfile
    import warnings

    rx90 = rx90sym.load_robot("rx90")
    chi = rx90.parameter_vector(rx90sym.default_parameters(rx90))
    for seed in (0, 10, 20):
        print(spring(rx90, chi, seed), flush=True)
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for seed in (0, 10, 20):
            print(ripple(chi, seed, Path(tmp)), flush=True)


if __name__ == "__main__":
    main()
