"""The rx90 command as a user runs it: the installed script in a subprocess, and a trajectory file to feed it."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

from motions import multisine

RX90 = str(Path(sys.executable).parent / "rx90")


def run(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([RX90, *args], capture_output=True, text=True, cwd=cwd, timeout=900)


def write_trajectory(path: Path, robot, seed: int, duration: float = 12.0) -> None:
    t = np.arange(0, duration, 1 / 250)
    q, qd, qdd = multisine(robot, seed, duration)(t)
    header = ",".join(["t"] + [f"{k}{j}" for k in ("q", "dq", "ddq") for j in range(1, 7)])
    np.savetxt(path, np.c_[t, robot.to_controller(q), qd, qdd], delimiter=",", header=header, comments="")
