"""Motor files (Stäubli CS8 / TX40): motor-side positions and torques read as joint data.

The format is described in :mod:`identify.io.recordings` (section "Motor files").
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rx90sym.messages import plain
from rx90sym.recording import Recording, RecordingError

from identify.io.csv_tables import _check_same_rows, _column_index, _read_table
from identify.io.arrays import _build, _normalise_convention
from identify.io.checks import _check_finite, _check_robot_name, _Labels

if TYPE_CHECKING:  # for annotations only
    import rx90sym

__all__ = ["read_motor_recording"]


def read_motor_recording(
    pos_csv: str | os.PathLike[str], torque_csv: str | os.PathLike[str], robot: rx90sym.Robot,
    period: float, convention: str = "controller",
) -> Recording:
    """Read motor-side position and torque files (Stäubli CS8 / TX40 format) as joint data.

    The files have header ``Joint_1..Joint_n`` and no time column. The conversion is
    ``q_joint = solve(robot.Rq, q_motor)``, ``tau_joint = robot.Rt @ tau_motor`` (gears and the
    5–6 wrist coupling), ``t = k * period``, then Stäubli → Khalil angles.

    Args:
        pos_csv: motor positions, rad (motor side).
        torque_csv: motor torques, N·m (motor side, drive gains applied).
        robot: the ``rx90sym.Robot``; provides ``Rq``, ``Rt``, offsets and limits.
        period: sampling period, s (0.2e-3 for the TX40 files).
        convention: angle convention of the joint positions after the gear conversion.

    Raises:
        RecordingError: malformed file, files of different lengths (message names file, column, row).
    """
    if not (period > 0.0 and math.isfinite(period)):
        raise ValueError(f"period must be a positive number of seconds, got {plain(period)}")
    conv = _normalise_convention(convention, "read_motor_recording")
    names = [f"Joint_{j + 1}" for j in range(robot.n)]
    tables = []
    for path in (Path(pos_csv), Path(torque_csv)):
        table = _read_table(path)
        index = _column_index(table, names)
        _check_robot_name(table.meta.get("robot"), robot, table.source)
        tables.append((table, table.values[:, [index[c] for c in names]]))
    (pos_table, q_motor), (tau_table, tau_motor) = tables
    _check_same_rows([pos_table, tau_table])
    # Check the raw motor data first: a NaN would otherwise spread over coupled joints.
    _check_finite(q_motor, [(pos_table.source, c) for c in names])
    _check_finite(tau_motor, [(tau_table.source, c) for c in names])
    q = np.linalg.solve(np.asarray(robot.Rq, dtype=float), q_motor.T).T
    tau = (np.asarray(robot.Rt, dtype=float) @ tau_motor.T).T
    t = np.arange(q.shape[0]) * float(period)
    labels = _Labels(
        t=(pos_table.source, "t (from the period)"),
        q=tuple((pos_table.source, c) for c in names),
        tau=tuple((tau_table.source, c) for c in names),
    )
    source = f"{pos_table.source}+{tau_table.source}"
    return _build(t, q, tau, None, robot, labels, source, conv)
