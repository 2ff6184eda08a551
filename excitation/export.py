"""Trajectory CSV files: written atomically through rx90sym.files (whole file or nothing), read back
as samples for the twin."""
from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

import numpy as np

from rx90sym.files import atomic_write

if TYPE_CHECKING:  # for annotations only
    import rx90sym


def write_csv(path: str | os.PathLike, header: list[str], rows: np.ndarray, fmt: str = "%.10g") -> Path:
    """CSV with one header line and ``rows`` (N, len(header)); refuses NaN/inf."""
    rows = np.asarray(rows, dtype=float)
    if rows.ndim != 2 or rows.shape[1] != len(header):
        raise ValueError(f"{path}: {rows.shape} data for {len(header)} columns")
    if not np.all(np.isfinite(rows)):
        raise ValueError(f"{path}: refusing to write non-finite values")

    def write(handle: TextIO) -> None:
        handle.write(",".join(header) + "\n")
        np.savetxt(handle, rows, fmt=fmt, delimiter=",")

    return atomic_write(path, write)


def read_trajectory(path: str | os.PathLike, robot: rx90sym.Robot) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A trajectory CSV (``Trajectory.save``: header t,q1..qn,dq1..dqn,ddq1..ddqn, controller
    angles) -> (t [s], q [rad, model angles], qd [rad/s], qdd [rad/s^2]), the tuple
    ``rx90sym.twin.simulate`` takes. Lines starting with '#' are comments. Errors name the file,
    the column and the row."""
    n = robot.n
    expected = ["t"] + [f"{k}{j}" for k in ("q", "dq", "ddq") for j in range(1, n + 1)]
    try:
        with open(path) as fh:
            header = next(line for line in fh if not line.startswith("#")).strip().split(",")
    except (OSError, StopIteration) as exc:
        raise ValueError(f"{path}: cannot read trajectory ({exc or 'empty file'})") from None
    if header != expected:
        missing = [c for c in expected if c not in header]
        raise ValueError(f"{path}: trajectory header must be {','.join(expected)} for robot "
                         f"{robot.name!r} ({n} joints)" + (f" (missing {missing[0]})" if missing else ""))
    try:
        data = np.loadtxt(path, delimiter=",", comments="#", skiprows=1, ndmin=2)
    except ValueError as exc:
        raise ValueError(f"{path}: not a numeric CSV ({exc})") from None
    bad = np.argwhere(~np.isfinite(data))
    if len(bad):
        raise ValueError(f"{path}: column {expected[bad[0, 1]]}, row {bad[0, 0] + 1}: not a finite number")
    t, q, qd, qdd = data[:, 0], data[:, 1:n + 1], data[:, n + 1:2 * n + 1], data[:, 2 * n + 1:]
    return t, robot.to_model(q), qd, qdd
