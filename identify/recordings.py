"""Recordings of joint positions and torques: the file boundary of the toolkit.

A :class:`Recording` holds one motion, always in the model's conventions: time in s, joint
positions in rad in **Khalil** angles, torques in N·m on the **joint side**. Files are read and
written here and nowhere else, so the Stäubli → Khalil angle conversion (DESIGN.md: θ2(Stäubli) =
θ2 + π/2, θ3(Stäubli) = θ3 − π/2) and the motor → joint conversion happen exactly once.

File formats
------------
CSV
    Optional leading comment lines ``# key: value`` (keys ``convention`` and ``robot`` are
    understood, other comments are ignored), then a header line naming the columns
    ``t, q1..qn, tau1..taun`` and optionally ``dq1..dqn`` (any order), then one row per sample.
NPZ
    Arrays ``t`` (N,), ``q`` (N, n), ``tau`` (N, n), optional ``dq`` (N, n), and optional 0-d
    strings ``convention`` and ``robot``.
Motor files (Stäubli CS8 / TX40)
    Two CSV files with header ``Joint_1..Joint_n``: motor-side positions (rad) and motor torques
    (N·m), no time column (the sampling period is given by the caller).

Validation
----------
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
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from rx90sym.files import atomic_write
from rx90sym.recording import Recording, RecordingError  # noqa: F401 (re-exported)

__all__ = [
    "Recording",
    "RecordingError",
    "read_recording",
    "write_recording",
    "read_motor_recording",
    "recording_from_arrays",
    "split",
    "TIME_RTOL",
    "JUMP_SAFETY",
    "JUMP_ATOL",
]

#: Largest accepted deviation of one time step from the median step, relative to the median.
TIME_RTOL = 0.01
#: A joint may move at most ``JUMP_SAFETY * qd_max * dt`` between two samples (plus ``JUMP_ATOL``).
JUMP_SAFETY = 1.5
#: Absolute allowance (rad) in the jump check, so that the quantisation of positions printed with
#: few digits (the TX40 files carry 5 significant digits) is not mistaken for a jump at 5 kHz.
JUMP_ATOL = 1e-3

_CONVENTIONS = ("staubli", "khalil")
_MEMORY = "<memory>"


# --------------------------------------------------------------------------------------------
# Validation of arrays (shared by every reader)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Labels:
    """Where each array column came from, for error messages: (file, column name) pairs."""

    t: tuple[str, str]
    q: tuple[tuple[str, str], ...]
    tau: tuple[tuple[str, str], ...]
    dq: tuple[tuple[str, str], ...] = field(default=())


def _where(label: tuple[str, str], row: int | None = None) -> str:
    source, column = label
    text = f"{source}: column '{column}'"
    return text if row is None else f"{text}, row {row}"


def _default_labels(source: str, n: int, with_dq: bool) -> _Labels:
    return _Labels(
        t=(source, "t"),
        q=tuple((source, f"q{j + 1}") for j in range(n)),
        tau=tuple((source, f"tau{j + 1}") for j in range(n)),
        dq=tuple((source, f"dq{j + 1}") for j in range(n)) if with_dq else (),
    )


def _check_finite(values: np.ndarray, labels: Sequence[tuple[str, str]]) -> None:
    """Refuse NaN/inf, naming the first bad cell of the first bad column."""
    bad = ~np.isfinite(values)
    if not bad.any():
        return
    for j, label in enumerate(labels):
        rows = np.flatnonzero(bad[:, j])
        if rows.size:
            raise RecordingError(f"{_where(label, int(rows[0]) + 1)}: value {values[rows[0], j]!r} is not finite")


def _check_time(t: np.ndarray, label: tuple[str, str], rtol: float = TIME_RTOL) -> None:
    """Time must increase strictly with a regular step (within ``rtol`` of the median step)."""
    if t.size < 2:
        return
    dt = np.diff(t)
    not_increasing = np.flatnonzero(dt <= 0.0)
    if not_increasing.size:
        k = int(not_increasing[0]) + 1  # 0-based index of the offending sample
        raise RecordingError(
            f"{_where(label, k + 1)}: time {t[k]!r} s does not increase (previous row: {t[k - 1]!r} s)"
        )
    step = float(np.median(dt))
    irregular = np.flatnonzero(np.abs(dt - step) > rtol * step)
    if irregular.size:
        k = int(irregular[0]) + 1
        raise RecordingError(
            f"{_where(label, k + 1)}: irregular time step {dt[k - 1]!r} s, the median step is {step!r} s "
            f"(tolerance {rtol:.0%}); resample the recording or split it at the gap"
        )


def _check_radians(q: np.ndarray, robot: Any, labels: Sequence[tuple[str, str]]) -> None:
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
                f"{_where(label, k + 1)}: angle {q[k, j]!r} rad is beyond {bound:.4g} rad "
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
    q: np.ndarray, dt: float, robot: Any, labels: Sequence[tuple[str, str]],
    safety: float = JUMP_SAFETY, atol: float = JUMP_ATOL,
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
                f"{_where(label, k + 1)}: jump of {steps[k - 1, j]:.6g} rad from the previous row "
                f"(allowed {allowed:.3g} rad = {safety:g} x qd_max {qd_max[j]:.4g} rad/s x dt {dt:.4g} s "
                f"+ {atol:g} rad)"
            )


def _validate(
    t: np.ndarray, q: np.ndarray, tau: np.ndarray, dq: np.ndarray | None,
    robot: Any, labels: _Labels, source: str,
) -> None:
    """All data checks of the module docstring, on arrays already in Khalil angles."""
    n = int(robot.n)
    if q.shape[1] != n or tau.shape[1] != n:
        raise RecordingError(
            f"{source}: {q.shape[1]} joint columns, robot {robot.name} has {n} joints"
        )
    _check_finite(t[:, None], [labels.t])
    _check_finite(q, labels.q)
    _check_finite(tau, labels.tau)
    if dq is not None:
        _check_finite(dq, labels.dq)
    n_min = len(robot.parameter_names)
    if t.size < max(n_min, 2):
        raise RecordingError(
            f"{source}: column '{labels.t[1]}' has {t.size} rows, robot {robot.name} needs at least "
            f"{max(n_min, 2)} samples (one per standard parameter) to be identifiable"
        )
    _check_time(t, labels.t)
    _check_radians(q, robot, labels.q)
    _check_jumps(q, float(np.median(np.diff(t))), robot, labels.q)


def _normalise_convention(convention: str | None, what: str) -> str | None:
    if convention is None:
        return None
    c = str(convention).strip().lower().replace("ä", "a")
    if c not in _CONVENTIONS:
        raise RecordingError(f"{what}: unknown angle convention {convention!r}, expected one of {_CONVENTIONS}")
    return c


def _resolve_convention(argument: str | None, declared: str | None, source: str) -> str:
    """Convention from the argument or the file; both given and different is an error."""
    arg = _normalise_convention(argument, f"{source} (argument)")
    dec = _normalise_convention(declared, source)
    if arg is not None and dec is not None and arg != dec:
        raise RecordingError(
            f"{source}: the file declares convention '{dec}' but '{arg}' was requested"
        )
    # DESIGN.md: files from the CS8 controller carry Stäubli angles.
    return arg or dec or "staubli"


def _check_robot_name(declared: str | None, robot: Any, source: str) -> None:
    if declared is not None and declared.strip() != robot.name:
        raise RecordingError(
            f"{source}: recorded on robot '{declared.strip()}', but robot '{robot.name}' was given"
        )


def _to_model(q: np.ndarray, robot: Any, convention: str) -> np.ndarray:
    """File angles -> Khalil angles (the one place the conversion happens on reading)."""
    return np.asarray(robot.to_khalil(q), dtype=float) if convention == "staubli" else q


def _build(
    t: np.ndarray, q: np.ndarray, tau: np.ndarray, dq: np.ndarray | None,
    robot: Any, labels: _Labels, source: str, convention: str,
) -> Recording:
    q_model = _to_model(q, robot, convention)  # the offsets are constant: dq is unchanged
    _validate(t, q_model, tau, dq, robot, labels, source)
    return Recording(t=t, q=q_model, tau=tau, dq=dq, source=source, robot=robot.name)


def recording_from_arrays(
    t: Any, q: Any, tau: Any, robot: Any, dq: Any = None,
    source: str = _MEMORY, convention: str = "khalil",
) -> Recording:
    """Build a validated :class:`Recording` from arrays (simulator, tests, notebooks).

    Args:
        t: (N,) time, s.
        q: (N, n) joint positions, rad, in ``convention`` angles.
        tau: (N, n) joint torques, N·m, joint side.
        robot: the ``rx90sym.Robot`` the data belong to.
        dq: optional (N, n) joint velocities, rad/s.
        source: name used in messages and kept in the recording.
        convention: ``"khalil"`` (default: arrays from the model) or ``"staubli"``.

    Raises:
        RecordingError: on any check of the module docstring.
    """
    conv = _normalise_convention(convention, source)
    t_a = np.asarray(t, dtype=float)
    q_a = np.asarray(q, dtype=float)
    tau_a = np.asarray(tau, dtype=float)
    dq_a = None if dq is None else np.asarray(dq, dtype=float)
    shapes = {"t": t_a.shape, "q": q_a.shape, "tau": tau_a.shape}
    if dq_a is not None:
        shapes["dq"] = dq_a.shape
    _check_shapes(shapes, robot, source)
    labels = _default_labels(source, robot.n, dq_a is not None)
    return _build(t_a, q_a, tau_a, dq_a, robot, labels, source, conv)


def _check_shapes(shapes: dict[str, tuple[int, ...]], robot: Any, source: str) -> None:
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


# --------------------------------------------------------------------------------------------
# CSV parsing
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Table:
    """A parsed CSV file: comment keys, column names, float values (N, ncols)."""

    source: str
    meta: dict[str, str]
    columns: tuple[str, ...]
    values: np.ndarray
    first_data_line: int  # 1-based line number in the file of data row 1


def _parse_cells(rows: list[list[str]], columns: Sequence[str], source: str, first_line: int) -> np.ndarray:
    """Convert cell text to floats; on failure name the first bad cell."""
    n_cols = len(columns)
    for i, cells in enumerate(rows):
        if len(cells) != n_cols:
            raise RecordingError(
                f"{source}: row {i + 1} (line {first_line + i}) has {len(cells)} cells, "
                f"the header has {n_cols} columns"
            )
    if not rows:
        return np.empty((0, n_cols))
    try:
        return np.array(rows, dtype=float)  # fast path: numpy parses all cells at once
    except ValueError:
        pass
    for i, cells in enumerate(rows):  # slow path, only to locate the bad cell
        for j, cell in enumerate(cells):
            try:
                float(cell)
            except ValueError:
                raise RecordingError(
                    f"{source}: column '{columns[j]}', row {i + 1} (line {first_line + i}): "
                    f"cell {cell.strip()!r} is not a number"
                ) from None
    raise RecordingError(f"{source}: unreadable numbers")  # unreachable in practice


def _read_table(path: Path) -> _Table:
    """Read comments ``# key: value``, the header and the numbers of a CSV file."""
    source = path.name
    try:
        text = path.read_text(encoding="utf-8-sig")  # -sig: tolerate the BOM spreadsheets write
    except UnicodeDecodeError as exc:
        raise RecordingError(f"{source}: not a UTF-8 text file ({exc})") from None
    lines = text.splitlines()
    meta: dict[str, str] = {}
    i = 0
    while i < len(lines) and (not lines[i].strip() or lines[i].lstrip().startswith("#")):
        body = lines[i].lstrip().lstrip("#").strip()
        if ":" in body:
            key, value = body.split(":", 1)
            meta[key.strip().lower()] = value.strip()
        i += 1
    if i == len(lines):
        raise RecordingError(f"{source}: no header line (expected column names)")
    columns = tuple(c.strip() for c in lines[i].split(","))
    header_line = i + 1
    data = lines[i + 1:]
    while data and not data[-1].strip():  # tolerate trailing blank lines only
        data.pop()
    rows = [line.split(",") for line in data]
    values = _parse_cells(rows, columns, source, header_line + 1)
    return _Table(source=source, meta=meta, columns=columns, values=values, first_data_line=header_line + 1)


def _column_index(table: _Table, expected: Sequence[str], optional: Sequence[str] = ()) -> dict[str, int]:
    """Map names to column positions; refuse missing, duplicated and unknown columns."""
    positions: dict[str, list[int]] = {}
    for k, name in enumerate(table.columns):
        positions.setdefault(name, []).append(k)
    for name, where in positions.items():
        if len(where) > 1:
            cols = ", ".join(str(k + 1) for k in where)
            raise RecordingError(f"{table.source}: column '{name}' appears more than once (header positions {cols})")
    known = set(expected) | set(optional)
    for name in table.columns:
        if name not in known:
            raise RecordingError(
                f"{table.source}: column '{name}' is unknown (expected {', '.join(expected)}"
                + (f", optionally {', '.join(optional)}" if optional else "") + ")"
            )
    for name in expected:
        if name not in positions:
            raise RecordingError(f"{table.source}: column '{name}' is missing")
    present = [name for name in optional if name in positions]
    if present and len(present) != len(optional):
        missing = next(name for name in optional if name not in positions)
        raise RecordingError(
            f"{table.source}: column '{missing}' is missing (the optional columns "
            f"{optional[0]}..{optional[-1]} come all together or not at all)"
        )
    return {name: positions[name][0] for name in list(expected) + present}


def _read_csv(path: Path, robot: Any, convention: str | None) -> Recording:
    table = _read_table(path)
    n = robot.n
    q_names = [f"q{j + 1}" for j in range(n)]
    tau_names = [f"tau{j + 1}" for j in range(n)]
    dq_names = [f"dq{j + 1}" for j in range(n)]
    index = _column_index(table, ["t", *q_names, *tau_names], dq_names)
    _check_robot_name(table.meta.get("robot"), robot, table.source)
    conv = _resolve_convention(convention, table.meta.get("convention"), table.source)

    def take(names: Sequence[str]) -> np.ndarray:
        return table.values[:, [index[c] for c in names]]

    with_dq = "dq1" in index
    labels = _default_labels(table.source, n, with_dq)
    t = table.values[:, index["t"]]
    dq = take(dq_names) if with_dq else None
    return _build(t, take(q_names), take(tau_names), dq, robot, labels, table.source, conv)


# --------------------------------------------------------------------------------------------
# NPZ
# --------------------------------------------------------------------------------------------

_NPZ_ARRAYS = ("t", "q", "tau", "dq")
_NPZ_STRINGS = ("convention", "robot")


def _npz_string(archive: Any, key: str, source: str) -> str | None:
    if key not in archive.files:
        return None
    value = archive[key]
    if value.shape != () or value.dtype.kind not in "US":
        raise RecordingError(f"{source}: '{key}' must be a 0-d string, got {value.dtype} of shape {value.shape}")
    return str(value[()])


def _npz_array(archive: Any, key: str, source: str) -> np.ndarray:
    value = archive[key]
    if value.dtype.kind not in "fiu":
        raise RecordingError(f"{source}: column '{key}' is not numeric (dtype {value.dtype})")
    return value.astype(float)


def _read_npz(path: Path, robot: Any, convention: str | None) -> Recording:
    source = path.name
    try:
        archive = np.load(path, allow_pickle=False)  # never unpickle data files
    except ValueError as exc:
        raise RecordingError(f"{source}: not a readable NPZ archive ({exc})") from None
    with archive:
        for key in archive.files:
            if key not in _NPZ_ARRAYS + _NPZ_STRINGS:
                raise RecordingError(
                    f"{source}: column '{key}' is unknown (expected t, q, tau, optionally dq, convention, robot)"
                )
        for key in ("t", "q", "tau"):
            if key not in archive.files:
                raise RecordingError(f"{source}: column '{key}' is missing")
        arrays = {k: _npz_array(archive, k, source) for k in _NPZ_ARRAYS if k in archive.files}
        declared_conv = _npz_string(archive, "convention", source)
        declared_robot = _npz_string(archive, "robot", source)
    _check_robot_name(declared_robot, robot, source)
    conv = _resolve_convention(convention, declared_conv, source)
    _check_shapes({k: v.shape for k, v in arrays.items()}, robot, source)
    labels = _default_labels(source, robot.n, "dq" in arrays)
    return _build(arrays["t"], arrays["q"], arrays["tau"], arrays.get("dq"), robot, labels, source, conv)


# --------------------------------------------------------------------------------------------
# Public readers and writer
# --------------------------------------------------------------------------------------------


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".npz"):
        raise RecordingError(f"{path.name}: unsupported file type '{path.suffix}', expected .csv or .npz")
    return suffix


def read_recording(path: str | os.PathLike[str], robot: Any, convention: str | None = None) -> Recording:
    """Read a recording from a CSV or NPZ file (chosen by the suffix) and validate it.

    Args:
        path: ``.csv`` or ``.npz`` file (formats in the module docstring).
        robot: the ``rx90sym.Robot`` the data belong to; a file declaring another robot is refused.
        convention: angle convention of the file, ``"staubli"`` or ``"khalil"``. ``None`` takes the
            one the file declares, and ``"staubli"`` when it declares none (CS8 files). Giving one
            that contradicts the file is an error.

    Returns:
        The recording in Khalil angles (rad), torques N·m joint side.

    Raises:
        RecordingError: malformed file (message names file, column, row).
        FileNotFoundError: no such file.
    """
    p = Path(path)
    suffix = _suffix(p)
    if suffix == ".csv":
        return _read_csv(p, robot, convention)
    return _read_npz(p, robot, convention)


def _file_arrays(rec: Recording, robot: Any, convention: str) -> np.ndarray:
    """Angles in the file's convention (conversion at the file boundary, once)."""
    return np.asarray(robot.to_staubli(rec.q), dtype=float) if convention == "staubli" else np.asarray(rec.q)


def write_recording(
    path: str | os.PathLike[str], rec: Recording, robot: Any, convention: str = "staubli"
) -> None:
    """Write ``rec`` to a CSV or NPZ file (by suffix), atomically and at full float precision.

    CSV numbers are written with ``%.17g`` (round-trips float64 exactly); the header comments
    record the convention and the robot. With ``convention="staubli"`` the Khalil angles are
    shifted by the robot's offsets, so reading back returns ``q`` to within one rounding of
    ``q ± π/2`` (≤ 1e-15 rad); ``"khalil"`` round-trips bit for bit.

    Args:
        path: target ``.csv`` or ``.npz`` file; its directory must exist.
        rec: the recording (Khalil angles).
        robot: the robot ``rec`` belongs to (checked by name).
        convention: angle convention written to the file, ``"staubli"`` (default, like CS8
            files) or ``"khalil"``.

    Raises:
        RecordingError: unsupported suffix, unknown convention, recording of another robot.
        OSError: the file system refused; nothing is left behind.
    """
    p = Path(path)
    suffix = _suffix(p)
    conv = _normalise_convention(convention, p.name)
    if rec.robot != robot.name:
        raise RecordingError(f"{p.name}: the recording belongs to robot '{rec.robot}', not '{robot.name}'")
    if rec.n_joints != robot.n:
        raise RecordingError(f"{p.name}: the recording has {rec.n_joints} joints, robot {robot.name} has {robot.n}")
    q_file = _file_arrays(rec, robot, conv)
    if suffix == ".npz":
        arrays: dict[str, Any] = {"t": rec.t, "q": q_file, "tau": rec.tau,
                                  "convention": np.array(conv), "robot": np.array(robot.name)}
        if rec.dq is not None:
            arrays["dq"] = rec.dq
        atomic_write(p, lambda fh: np.savez(fh, **arrays), binary=True)
        return
    n = robot.n
    names = ["t", *[f"q{j + 1}" for j in range(n)], *[f"tau{j + 1}" for j in range(n)]]
    blocks = [rec.t[:, None], q_file, rec.tau]
    if rec.dq is not None:
        names += [f"dq{j + 1}" for j in range(n)]
        blocks.append(rec.dq)
    table = np.hstack(blocks)
    header = f"# convention: {conv}\n# robot: {robot.name}\n" + ",".join(names) + "\n"

    def write_csv(fh: Any) -> None:
        fh.write(header)
        np.savetxt(fh, table, fmt="%.17g", delimiter=",")  # %.17g: float64 round-trips exactly

    atomic_write(p, write_csv, binary=False)


def read_motor_recording(
    pos_csv: str | os.PathLike[str], torque_csv: str | os.PathLike[str], robot: Any,
    period: float, convention: str = "staubli",
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
        raise ValueError(f"period must be a positive number of seconds, got {period!r}")
    conv = _normalise_convention(convention, "read_motor_recording")
    names = [f"Joint_{j + 1}" for j in range(robot.n)]
    tables = []
    for path in (Path(pos_csv), Path(torque_csv)):
        table = _read_table(path)
        index = _column_index(table, names)
        _check_robot_name(table.meta.get("robot"), robot, table.source)
        tables.append((table, table.values[:, [index[c] for c in names]]))
    (pos_table, q_motor), (tau_table, tau_motor) = tables
    if q_motor.shape[0] != tau_motor.shape[0]:
        short, long_ = sorted(tables, key=lambda tv: tv[1].shape[0])
        raise RecordingError(
            f"{short[0].source}: column '{names[0]}', row {short[1].shape[0] + 1}: missing "
            f"({short[0].source} has {short[1].shape[0]} rows, {long_[0].source} has {long_[1].shape[0]}; "
            f"mismatched lengths)"
        )
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


def split(rec: Recording, fraction: float) -> tuple[Recording, Recording]:
    """Cut a recording in two: the first ``fraction`` of the samples and the rest.

    Used to fit on the beginning of a motion and validate the torque prediction on its end (for
    example ``split(rec, 2/3)`` keeps the last third for validation). Times are kept as recorded.

    Args:
        rec: the recording.
        fraction: share of samples in the first part, 0 < fraction < 1.

    Raises:
        ValueError: fraction out of range, or a part would hold fewer than 2 samples.
    """
    if not (0.0 < fraction < 1.0):
        raise ValueError(f"fraction must lie strictly between 0 and 1, got {fraction!r}")
    k = int(round(fraction * rec.n_samples))
    if k < 2 or rec.n_samples - k < 2:
        raise ValueError(
            f"{rec.source}: split at {fraction!r} of {rec.n_samples} samples leaves a part with fewer than 2 samples"
        )

    def part(s: slice, tag: str) -> Recording:
        dq = None if rec.dq is None else rec.dq[s]
        return Recording(t=rec.t[s], q=rec.q[s], tau=rec.tau[s], dq=dq,
                         source=f"{rec.source}[{tag}]", robot=rec.robot)

    return part(slice(0, k), f":{k}"), part(slice(k, None), f"{k}:")
