"""Validation of recordings: the checks every reader applies to the arrays it has read.

Every bad input raises :class:`RecordingError` (a ``ValueError``) whose message names the file,
the column and the 1-based data row (row 1 is the first line after the header). The checks:

* missing, duplicated or unknown columns; rows with the wrong number of cells;
* non-numeric cells, NaN or ±inf;
* time not strictly increasing; a time step differing from the median step by more than
  ``TIME_RTOL`` (1 %) of it;
* angles that look like degrees (see :func:`_check_radians` for the rule);
* fewer samples than the robot has standard parameters (the least-squares problem could not be
  over-determined);
* a jump between consecutive samples larger than
  ``JUMP_SAFETY * qd_max * dt + JUMP_ATOL`` (skipped for joints with an infinite ``qd_max``);
* motor files of different lengths.

The column checks of CSV files are in :mod:`identify.io.csv_tables`, the length check of motor
files in :mod:`identify.io.motor_files`; the arrays of every reader end in :func:`_validate`.
"""

from __future__ import annotations

import math
import numbers
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Sequence

import numpy as np

from rx90sym.messages import plain
from rx90sym.recording import RecordingError

if TYPE_CHECKING:  # for annotations only
    import rx90sym

#: Largest accepted deviation of one time step from the median step, relative to the median.
TIME_RTOL = 0.01
#: A joint may move at most ``JUMP_SAFETY * qd_max * dt`` between two samples (plus ``JUMP_ATOL``).
JUMP_SAFETY = 1.5
#: Absolute allowance (rad) in the jump check, so that the quantisation of positions printed with
#: few digits (the TX40 files carry 5 significant digits) is not mistaken for a jump at 5 kHz.
JUMP_ATOL = 1e-3

_DEFAULT_ROBOT = "rx90"  # the CLI's default --robot


class RecordingWarning(UserWarning):
    """A recording that can be read but may not be what the user meant (e.g. names no robot)."""


@dataclass(frozen=True)
class _Labels:
    """Where each array column came from, for error messages: (file, column name) pairs."""

    t: tuple[str, str]
    q: tuple[tuple[str, str], ...]
    tau: tuple[tuple[str, str], ...]
    dq: tuple[tuple[str, str], ...] = field(default=())
    current: tuple[tuple[str, str], ...] = field(default=())


def _where(label: tuple[str, str], row: int | None = None) -> str:
    source, column = label
    text = f"{source}: column '{column}'"
    return text if row is None else f"{text}, row {row}"


def _default_labels(source: str, n: int, with_dq: bool = True) -> _Labels:
    def names(prefix: str) -> tuple[tuple[str, str], ...]:
        return tuple((source, f"{prefix}{j + 1}") for j in range(n))

    return _Labels(t=(source, "t"), q=names("q"), tau=names("tau"), dq=names("dq"), current=names("i"))


def _check_finite(values: np.ndarray, labels: Sequence[tuple[str, str]]) -> None:
    """Refuse NaN/inf, naming the first bad cell of the first bad column."""
    bad = ~np.isfinite(values)
    if not bad.any():
        return
    for j, label in enumerate(labels):
        rows = np.flatnonzero(bad[:, j])
        if rows.size:
            raise RecordingError(f"{_where(label, int(rows[0]) + 1)}: value {values[rows[0], j]:g} is not finite")


def _check_time(t: np.ndarray, label: tuple[str, str], rtol: float = TIME_RTOL, offset: int = 0) -> None:
    """Time must increase strictly with a regular step (within ``rtol`` of the median step);
    ``offset``: index of ``t[0]`` in the file's rows (for the messages)."""
    if t.size < 2:
        return
    dt = np.diff(t)
    not_increasing = np.flatnonzero(dt <= 0.0)
    if not_increasing.size:
        k = int(not_increasing[0]) + 1  # 0-based index of the offending sample
        raise RecordingError(
            f"{_where(label, offset + k + 1)}: time {t[k]:g} s does not increase (previous row: {t[k - 1]:g} s)"
        )
    step = float(np.median(dt))
    irregular = np.flatnonzero(np.abs(dt - step) > rtol * step)
    if irregular.size:
        k = int(irregular[0]) + 1
        raise RecordingError(
            f"{_where(label, offset + k + 1)}: irregular time step {dt[k - 1]:g} s, the median step is {step:g} s "
            f"(tolerance {rtol:.0%}); resample the recording or split it at the gap"
        )


def _check_radians(q: np.ndarray, robot: rx90sym.Robot, labels: Sequence[tuple[str, str]]) -> None:
    """Refuse joint columns that look like degrees.

    Rule, per joint j (Khalil angles): with ``lim = max(|q_min_j|, |q_max_j|)`` when both limits
    are finite, else ``lim = 2π``, a column is refused when some ``|q| > lim + 2π`` (no reading in
    radians is a full turn beyond the joint's travel), or when its range ``max q − min q`` exceeds
    ``4π`` (two full turns in one motion). A motion of a few degrees written in degrees stays
    undetected: it is indistinguishable from a large motion in radians.
    """
    q_min = np.broadcast_to(np.asarray(robot.limits.q_min, dtype=float), (q.shape[1],))
    q_max = np.broadcast_to(np.asarray(robot.limits.q_max, dtype=float), (q.shape[1],))
    for j, label in enumerate(labels):
        finite = np.isfinite(q_min[j]) and np.isfinite(q_max[j])
        lim = max(abs(q_min[j]), abs(q_max[j])) if finite else 2.0 * math.pi
        bound = lim + 2.0 * math.pi
        beyond = np.flatnonzero(np.abs(q[:, j]) > bound)
        if beyond.size:
            k = int(beyond[0])
            raise RecordingError(
                f"{_where(label, k + 1)}: angle {q[k, j]:g} rad is beyond {bound:.4g} rad "
                f"(joint travel + 2π); angles must be in radians, this looks like degrees"
            )
        span = float(q[:, j].max() - q[:, j].min())
        if span > 4.0 * math.pi:
            k = int(np.argmax(q[:, j]))
            raise RecordingError(
                f"{_where(label, k + 1)}: the joint spans {span:.4g} rad (> 4π) in one motion; "
                f"angles must be in radians, this looks like degrees"
            )


def _check_jumps(
    q: np.ndarray, dt: float, robot: rx90sym.Robot, labels: Sequence[tuple[str, str]],
    safety: float = JUMP_SAFETY, atol: float = JUMP_ATOL, offset: int = 0,
) -> None:
    """Refuse a step between consecutive samples faster than ``safety * qd_max`` (glitch, wrap)."""
    if q.shape[0] < 2:
        return
    qd_max = np.broadcast_to(np.asarray(robot.limits.qd_max, dtype=float), (q.shape[1],))
    steps = np.abs(np.diff(q, axis=0))
    for j, label in enumerate(labels):
        if not np.isfinite(qd_max[j]):
            continue  # unknown speed limit: nothing to compare with
        allowed = safety * qd_max[j] * dt + atol
        too_big = np.flatnonzero(steps[:, j] > allowed)
        if too_big.size:
            k = int(too_big[0]) + 1
            raise RecordingError(
                f"{_where(label, offset + k + 1)}: jump of {steps[k - 1, j]:.6g} rad from the previous row "
                f"(allowed {allowed:.3g} rad = {safety:g} x qd_max {qd_max[j]:.4g} rad/s x dt {dt:.4g} s "
                f"+ {atol:g} rad)"
            )


def _validate(
    t: np.ndarray, q: np.ndarray, tau: np.ndarray | None, dq: np.ndarray | None,
    robot: rx90sym.Robot, labels: _Labels, source: str, current: np.ndarray | None = None,
    aux: dict[str, np.ndarray] | None = None, segment: np.ndarray | None = None,
) -> None:
    """All data checks of the module docstring, on arrays already in Khalil angles; time steps
    and jumps are checked inside each segment (``segment``: (N,) segment numbers, or None)."""
    n = int(robot.n)
    if q.shape[1] != n or (tau is not None and tau.shape[1] != n):
        raise RecordingError(
            f"{source}: {q.shape[1]} joint columns, robot {robot.name} has {n} joints"
        )
    if tau is None and current is None:
        raise RecordingError(f"{source}: neither joint torques (tau1..tau{n}) nor motor currents (i1..i{n})")
    _check_finite(t[:, None], [labels.t])
    _check_finite(q, labels.q)
    for values, names in ((tau, labels.tau), (dq, labels.dq), (current, labels.current)):
        if values is not None:
            _check_finite(values, names)
    for name, values in (aux or {}).items():
        _check_finite(np.asarray(values, dtype=float)[:, None], [(source, f"x:{name}")])
    n_min = len(robot.parameter_names)
    if t.size < max(n_min, 2):
        raise RecordingError(
            f"{source}: column '{labels.t[1]}' has {t.size} rows, robot {robot.name} needs at least "
            f"{max(n_min, 2)} samples (one per standard parameter) to be identifiable"
        )
    bounds = [0, t.size] if segment is None else [0, *(np.flatnonzero(np.diff(segment)) + 1), t.size]
    if segment is not None and np.any(np.diff(t) <= 0):
        _check_time(t, labels.t, rtol=np.inf)  # increasing across the segments too
    for a, b in zip(bounds[:-1], bounds[1:]):
        _check_time(t[a:b], labels.t, offset=a)
    _check_radians(q, robot, labels.q)
    for a, b in zip(bounds[:-1], bounds[1:]):
        if b - a > 1:
            _check_jumps(q[a:b], float(np.median(np.diff(t[a:b]))), robot, labels.q, offset=a)


def check_period(period: float) -> None:
    """A sampling period (s) is a positive finite number (ValueError naming ``--period`` otherwise)."""
    if not (isinstance(period, numbers.Real) and math.isfinite(period) and period > 0):
        raise ValueError(f"--period (period= in Python) must be a positive sampling period in s, got {plain(period)}")


def _check_robot_name(declared: str | None, robot: rx90sym.Robot, source: str) -> None:
    if declared is not None and declared.strip() != robot.name:
        raise RecordingError(
            f"{source}: recorded on robot '{declared.strip()}', but robot '{robot.name}' was given"
        )



def _check_shapes(shapes: dict[str, tuple[int, ...]], robot: rx90sym.Robot, source: str) -> None:
    """t (N,), q/tau/dq (N, n): a wrong shape names the array and the offending size."""
    t_shape = shapes["t"]
    if len(t_shape) != 1:
        raise RecordingError(f"{source}: 't' must be 1-D (N,), got shape {t_shape}")
    n_rows = t_shape[0]
    for name, shape in shapes.items():
        if name == "t":
            continue
        if len(shape) != 2 or shape[1] != robot.n:
            raise RecordingError(
                f"{source}: '{name}' must have shape (N, {robot.n}) for robot {robot.name}, got {shape}"
            )
        if shape[0] != n_rows:
            raise RecordingError(
                f"{source}: '{name}' has {shape[0]} rows but 't' has {n_rows} (mismatched lengths), "
                f"row {min(shape[0], n_rows) + 1} is missing in the shorter one"
            )


def _warn_no_robot(declared: str | None, robot: rx90sym.Robot, source: str) -> None:
    """A file that names no robot, read as another robot than the default one: say so (an RX90
    recording read with --robot tx40 would otherwise give wrong parameters without a word)."""
    if declared is None and robot.name != _DEFAULT_ROBOT:
        warnings.warn(f"{source}: the file names no robot (no '# robot: NAME' line); it is read as "
                      f"robot '{robot.name}'", RecordingWarning, stacklevel=3)
