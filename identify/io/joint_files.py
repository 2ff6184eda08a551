"""Joint data as research datasets ship it: one file per signal, one column per joint, no time.

A dataset often comes as separate files, ``positions.csv``, ``torques.csv`` (and velocities or
motor currents), each with exactly n columns (n = the robot's joint count), one row per sample,
with or without a header line, and a sampling period given apart. :func:`read_joint_files` reads
them side by side as one log (``rx90 convert --positions Q.csv --torques T.csv --period S``):

* a file has a header when a cell of its first line (after ``#`` comments) is not a number;
  a header's names are not interpreted, only counted (exactly n);
* every file has the same number of rows; row k of each is sample k, at ``t = k * period``
  (t = 0 at the first sample);
* the rows then go through the rules of a one-file log (:func:`identify.io.log_rules.rows_to_recording`):
  degrees, swapped position/velocity columns, positions beyond the limits, jumps, currents
  through drive gains. Two files give exactly the recording of one pasted file whose time column
  is ``k * period`` (no stale rows are dropped: every row is a sample of the period's clock).

Lines named in messages: the data lines of each file; the checks made on the joined rows name
the lines of the positions file.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

import rx90sym
from rx90sym.recording import Recording, RecordingError

from identify.io.arrays import _normalise_convention
from identify.io.checks import _check_finite, _check_robot_name, check_period
from identify.io.columns import parse_columns
from identify.io.csv_tables import _Table, _check_same_rows, _read_table
from identify.io.gains import DriveGains
from identify.io.log_rules import rows_to_recording
from identify.io.torque_signs import parse_torque_signs

__all__ = ["read_joint_files", "SIGNALS"]

#: The signals one file each can hold: keyword -> (column-map prefix, option, what it holds).
SIGNALS = {"positions": ("q", "--positions", "joint positions, rad"),
           "velocities": ("qd", "--velocities", "joint velocities, rad/s"),
           "torques": ("tau", "--torques", "joint torques, N·m (joint side)"),
           "currents": ("i", "--currents", "motor currents, A")}


def _joint_table(path: Path, prefix: str, option: str, robot: rx90sym.Robot) -> _Table:
    """One file of n numeric columns (header or none), its cells finite."""
    names = [f"{prefix}{j + 1}" for j in range(robot.n)]
    table = _read_table(path, header=None, names=names)
    width = len(table.columns)
    if width != robot.n:
        raise RecordingError(f"{table.source} ({option}): {width} columns, robot '{robot.name}' has "
                             f"{robot.n} joints: the file must hold exactly one column per joint (no time column; "
                             f"a log with a time column is read as LOG.csv --columns SPEC)")
    if table.values.shape[0] == 0:
        raise RecordingError(f"{table.source} ({option}): no data rows")
    _check_robot_name(table.meta.get("robot"), robot, table.source)
    _check_finite(table.values, [(table.source, c) for c in table.columns])
    return table


def read_joint_files(
    robot: rx90sym.Robot, files: Mapping[str, str | os.PathLike[str]], period: float,
    gains: DriveGains | str | None = None, convention: str | None = None, resample: float | None = None,
    torque_signs: str | Sequence[float] | None = None,
) -> Recording:
    """Read one file per signal (module docstring) as a recording.

    Args:
        robot: the robot the data belong to (its joint count n, limits, angle offsets).
        files: ``positions`` (required) and ``torques`` and/or ``currents``, optionally
            ``velocities``: each a CSV of n columns (header or none), one row per sample.
        period: sampling period, s (> 0); sample k is at ``t = k * period``.
        gains: drive gains turning the currents into joint torques (:func:`identify.io.gains.read_gains`).
        convention: angles of the positions, ``"controller"`` (default) or ``"model"``.
        resample: rate, Hz, of a uniform grid to put the signals on (None: the period's).
        torque_signs: one sign per joint (1 or -1) for the torques and currents (identify.read_log).

    Returns:
        A recording in model angles; ``meta["log"]`` as :func:`identify.read_log`'s, with
        ``files`` (signal -> file name) and ``period_s``.

    Raises:
        RecordingError: a file with another column count, a cell that is not a finite number (file,
            column, row and line named), files of different lengths (every file's row count named),
            or rows refused by the log rules.
        ValueError: a period <= 0, a bad signal name, gains without currents.
    """
    check_period(period)
    signs = parse_torque_signs(torque_signs, robot)
    unknown = sorted(set(files) - set(SIGNALS))
    if unknown:
        raise ValueError(f"read_joint_files: unknown signal {unknown[0]!r} (expected {', '.join(SIGNALS)})")
    if "positions" not in files:
        raise ValueError("read_joint_files: the joint positions are required (--positions Q.csv)")
    if "torques" not in files and "currents" not in files:
        raise ValueError("read_joint_files: give the joint torques (--torques T.csv) or the motor currents "
                         "(--currents I.csv with --gains)")
    if gains is not None and ("currents" not in files or "torques" in files):
        raise ValueError("read_joint_files: drive gains turn the motor currents (--currents) into joint torques: "
                         + ("no currents given" if "currents" not in files else
                            f"the torques of {Path(files['torques']).name} would be replaced; give one of them"))
    conv = _normalise_convention(convention, "read_joint_files") or "controller"
    order = [s for s in SIGNALS if s in files]
    tables = {s: _joint_table(Path(files[s]), SIGNALS[s][0], SIGNALS[s][1], robot) for s in order}
    _check_same_rows(list(tables.values()))
    first = tables["positions"]
    values = np.column_stack([tables[s].values for s in order]
                             + [np.arange(first.values.shape[0]) * float(period)])
    names = [f"{SIGNALS[s][0]}{j + 1}" for s in order for j in range(robot.n)] + ["t"]
    cmap = parse_columns(names, robot)
    numbers = list(range(first.first_data_line, first.first_data_line + first.values.shape[0]))
    source = "+".join(t.source for t in tables.values())
    rec = rows_to_recording(source, values, numbers, cmap, robot, conv, gains=gains, resample=resample,
                            window=False, stale=False, signs=signs)
    rec.meta["log"].update(files={s: tables[s].source for s in order}, period_s=float(period))
    return rec
