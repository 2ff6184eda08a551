"""Recordings of joint positions and torques: the file boundary of the toolkit.

A :class:`Recording` holds one motion, always in the model's conventions: time in s, joint
positions in rad in **Khalil** angles, torques in N·m on the **joint side**. Files are read and
written here and nowhere else, so the Stäubli → Khalil angle conversion (DESIGN.md: θ2(Stäubli) =
θ2 + π/2, θ3(Stäubli) = θ3 − π/2) and the motor → joint conversion happen exactly once.

File formats
------------
CSV
    Optional leading comment lines ``# key: value`` (keys ``convention`` and ``robot`` are
    understood, and of a converted log ``stale_rows`` and ``split_gaps``,
    :mod:`identify.io.log_fields`; other comments are ignored), then a header line naming the columns
    ``t, q1..qn``, joint torques ``tau1..taun`` (N·m) and/or motor currents ``i1..in`` (A), and
    optionally recorded velocities ``dq1..dqn`` (rad/s), auxiliary columns ``x:NAME`` (kept,
    never used as torque), ``measured`` (1, or 0 for a sample bridged over lost packets) and
    ``segment`` (0, 1, ...: a log split at gaps too long to bridge), in any order; then one row
    per sample. The time step is regular inside each segment. A file that names no robot
    read as another robot than ``rx90`` gives a :class:`RecordingWarning`.
NPZ
    Arrays ``t`` (N,), ``q`` (N, n), ``tau`` (N, n) and/or ``current`` (N, n), optional ``dq``
    (N, n), ``x:NAME``, ``measured`` and ``segment`` (N,), and optional 0-d strings ``convention``,
    ``robot``, ``stale_rows`` and ``split_gaps`` (the same text as the CSV's comment lines).
Motor files (Stäubli CS8 / TX40)
    Two CSV files with header ``Joint_1..Joint_n``: motor-side positions (rad) and motor torques
    (N·m), no time column (the sampling period is given by the caller).

Validation
----------
Every bad input raises :class:`RecordingError` (a ``ValueError``) whose message names the file,
the column and the 1-based data row; the checks are listed in :mod:`identify.io.checks`.

The work is shared: :mod:`identify.io.csv_tables` parses CSV files, :mod:`identify.io.arrays`
holds the angle conventions and builds validated recordings from arrays,
:mod:`identify.io.motor_files` reads motor files; this module reads and writes CSV/NPZ recordings
and re-exports the public names of all of them.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rx90sym.files import atomic_write
from rx90sym.messages import plain
from rx90sym.recording import Recording, RecordingError  # noqa: F401 (re-exported)

from identify.io.csv_tables import _column_index, _read_table
from identify.io.log_fields import FIELDS, file_fields, layout_fields, read_fields
from identify.io.motor_files import read_motor_recording
from identify.io.arrays import _build, _normalise_convention, _resolve_convention, recording_from_arrays
from identify.io.checks import (JUMP_ATOL, JUMP_SAFETY, TIME_RTOL, RecordingWarning,
                               _check_robot_name, _check_shapes, _default_labels, _warn_no_robot)

if TYPE_CHECKING:  # for annotations only
    import rx90sym

__all__ = [
    "Recording",
    "RecordingError",
    "RecordingWarning",
    "read_recording",
    "write_recording",
    "read_motor_recording",
    "recording_from_arrays",
    "split",
    "layout_summary",
    "TIME_RTOL",
    "JUMP_SAFETY",
    "JUMP_ATOL",
]


def _read_csv(path: Path, robot: rx90sym.Robot, convention: str | None) -> Recording:
    table = _read_table(path)
    # The robot first: a file of another robot has other columns (q7), which would hide the cause.
    _check_robot_name(table.meta.get("robot"), robot, table.source)
    n = robot.n
    names = {p: [f"{p}{j + 1}" for j in range(n)] for p in ("q", "tau", "dq", "i")}
    index = _column_index(table, ["t", *names["q"]], [names["tau"], names["dq"], names["i"], ["measured"],
                                                       ["segment"]], aux=True)
    if "tau1" not in index and "i1" not in index:
        raise RecordingError(f"{table.source}: column 'tau1' is missing (joint torques tau1..tau{n}, or "
                             f"motor currents i1..i{n})")
    _warn_no_robot(table.meta.get("robot"), robot, table.source)
    conv = _resolve_convention(convention, table.meta.get("convention"), table.source)

    def take(prefix: str) -> np.ndarray | None:
        return table.values[:, [index[c] for c in names[prefix]]] if f"{prefix}1" in index else None

    aux = {name[2:]: table.values[:, col] for name, col in index.items() if name.startswith("x:")}
    labels = _default_labels(table.source, n)
    t = table.values[:, index["t"]]
    layout = {k: table.values[:, index[k]] for k in ("measured", "segment") if k in index}
    rec = _build(t, take("q"), take("tau"), take("dq"), robot, labels, table.source, conv, take("i"), aux,
                 **layout)
    log = read_fields(table.meta, table.source)
    if log is not None:
        rec.meta["log"] = log
    return rec


# --------------------------------------------------------------------------------------------
# NPZ
# --------------------------------------------------------------------------------------------

_NPZ_ARRAYS = ("t", "q", "tau", "dq", "current")
_NPZ_LAYOUT = ("measured", "segment")
_NPZ_STRINGS = ("convention", "robot") + FIELDS


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


def _read_npz(path: Path, robot: rx90sym.Robot, convention: str | None) -> Recording:
    source = path.name
    try:
        archive = np.load(path, allow_pickle=False)  # never unpickle data files
    except ValueError as exc:
        raise RecordingError(f"{source}: not a readable NPZ archive ({exc})") from None
    with archive:
        declared_robot = _npz_string(archive, "robot", source)
        _check_robot_name(declared_robot, robot, source)
        for key in archive.files:
            if key not in _NPZ_ARRAYS + _NPZ_STRINGS + _NPZ_LAYOUT and not (key.startswith("x:") and len(key) > 2):
                raise RecordingError(
                    f"{source}: column '{key}' is unknown (expected t, q, tau and/or current, optionally "
                    f"dq, x:NAME, measured, segment, convention, robot, {', '.join(FIELDS)})"
                )
        for key in ("t", "q") + (() if "current" in archive.files else ("tau",)):
            if key not in archive.files:
                raise RecordingError(f"{source}: column '{key}' is missing")
        arrays = {k: _npz_array(archive, k, source) for k in _NPZ_ARRAYS if k in archive.files}
        aux = {k[2:]: _npz_array(archive, k, source) for k in archive.files if k.startswith("x:")}
        layout = {k: _npz_array(archive, k, source) for k in _NPZ_LAYOUT if k in archive.files}
        declared_conv = _npz_string(archive, "convention", source)
        fields = {k: _npz_string(archive, k, source) for k in FIELDS if k in archive.files}
    _warn_no_robot(declared_robot, robot, source)
    conv = _resolve_convention(convention, declared_conv, source)
    _check_shapes({k: v.shape for k, v in arrays.items()}, robot, source)
    for name, v in aux.items():
        if v.shape != arrays["t"].shape:
            raise RecordingError(f"{source}: auxiliary column 'x:{name}' must have shape {arrays['t'].shape}, got {v.shape}")
    labels = _default_labels(source, robot.n)
    for name, v in layout.items():
        if v.shape != arrays["t"].shape:
            raise RecordingError(f"{source}: '{name}' must have shape {arrays['t'].shape}, got {v.shape}")
    rec = _build(arrays["t"], arrays["q"], arrays.get("tau"), arrays.get("dq"), robot, labels, source, conv,
                 arrays.get("current"), aux, **layout)
    log = read_fields(fields, source)
    if log is not None:
        rec.meta["log"] = log
    return rec


# --------------------------------------------------------------------------------------------
# Public readers and writer
# --------------------------------------------------------------------------------------------


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".npz"):
        raise RecordingError(f"{path.name}: unsupported file type '{path.suffix}', expected .csv or .npz")
    return suffix


def declared_robot(path: str | os.PathLike[str]) -> str | None:
    """The robot a recording file names (CSV ``# robot: NAME`` comment, NPZ ``robot`` string), or
    None when it names none. Reads only the CSV's leading comment lines."""
    p = Path(path)
    if _suffix(p) == ".npz":
        with np.load(p, allow_pickle=False) as archive:
            return _npz_string(archive, "robot", p.name)
    with open(p, encoding="utf-8-sig") as fh:
        for line in fh:
            body = line.strip()
            if body and not body.startswith("#"):
                return None
            key, sep, value = body.lstrip("#").partition(":")
            if sep and key.strip().lower() == "robot" and value.strip():
                return value.strip()
    return None


def read_recording(path: str | os.PathLike[str], robot: rx90sym.Robot, convention: str | None = None) -> Recording:
    """Read a recording from a CSV or NPZ file (chosen by the suffix) and validate it.

    Args:
        path: ``.csv`` or ``.npz`` file (formats in the module docstring).
        robot: the ``rx90sym.Robot`` the data belong to; a file declaring another robot is refused.
        convention: angle convention of the file, ``"controller"`` or ``"model"`` (old names
            ``"staubli"``, ``"khalil"``). ``None`` takes the one the file declares, and
            ``"controller"`` when it declares none (controller logs). Giving one
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


def _file_arrays(rec: Recording, robot: rx90sym.Robot, convention: str) -> np.ndarray:
    """Angles in the file's convention (conversion at the file boundary, once)."""
    return np.asarray(robot.to_controller(rec.q), dtype=float) if convention == "controller" else np.asarray(rec.q)


def write_recording(
    path: str | os.PathLike[str], rec: Recording, robot: rx90sym.Robot, convention: str = "controller"
) -> None:
    """Write ``rec`` to a CSV or NPZ file (by suffix), atomically and at full float precision.

    CSV numbers are written with ``%.17g`` (round-trips float64 exactly); the header comments
    record the convention and the robot. With ``convention="controller"`` the Khalil angles are
    shifted by the robot's offsets, so reading back returns ``q`` to within one rounding of
    ``q ± π/2`` (≤ 1e-15 rad); ``"model"`` round-trips bit for bit.

    Args:
        path: target ``.csv`` or ``.npz`` file; its directory must exist.
        rec: the recording (Khalil angles).
        robot: the robot ``rec`` belongs to (checked by name).
        convention: angle convention written to the file, ``"controller"`` (default, like a
            controller's logs) or ``"model"`` (Khalil); old names ``"staubli"``/``"khalil"``.

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
    bad_aux = [k for k in rec.aux if not k or any(c in k for c in ",\n\r")]
    if bad_aux:
        raise RecordingError(f"{p.name}: auxiliary column name {bad_aux[0]!r} cannot be a CSV/NPZ column name")
    q_file = _file_arrays(rec, robot, conv)
    signals = {"tau": rec.tau, "dq": rec.dq, "current": rec.current}
    fields = file_fields(rec.meta.get("log"))  # what the log's reader reported: stale rows, gaps that split
    if suffix == ".npz":
        arrays: dict[str, Any] = {"t": rec.t, "q": q_file, "convention": np.array(conv),
                                  "robot": np.array(robot.name), **{k: np.array(v) for k, v in fields.items()}}
        arrays.update({k: v for k, v in signals.items() if v is not None})
        arrays.update({f"x:{k}": v for k, v in rec.aux.items()})
        arrays.update({k: v for k, v in _layout(rec).items()})
        atomic_write(p, lambda fh: np.savez(fh, **arrays), binary=True)
        return
    n = robot.n
    names = ["t", *[f"q{j + 1}" for j in range(n)]]
    blocks = [rec.t[:, None], q_file]
    for key, prefix in (("tau", "tau"), ("dq", "dq"), ("current", "i")):
        if signals[key] is not None:
            names += [f"{prefix}{j + 1}" for j in range(n)]
            blocks.append(signals[key])
    names += [f"x:{k}" for k in rec.aux]
    blocks += [v[:, None] for v in rec.aux.values()]
    layout = _layout(rec)
    names += list(layout)
    blocks += [v[:, None].astype(float) for v in layout.values()]
    table = np.hstack(blocks)
    header = (f"# convention: {conv}\n# robot: {robot.name}\n" + "".join(f"# {k}: {v}\n" for k, v in fields.items())
              + ",".join(names) + "\n")

    def write_csv(fh: Any) -> None:
        fh.write(header)
        np.savetxt(fh, table, fmt="%.17g", delimiter=",")  # %.17g: float64 round-trips exactly

    atomic_write(p, write_csv, binary=False)


def _layout(rec: Recording) -> dict[str, np.ndarray]:
    """The ``measured`` and ``segment`` columns a recording needs (none when trivial)."""
    out = {}
    if rec.measured is not None:
        out["measured"] = rec.measured.astype(np.int64)
    if rec.segment is not None:
        out["segment"] = rec.segment
    return out


def layout_summary(rec: Recording) -> dict[str, Any]:
    """What a recording holds beyond its samples, for reports and JSON: ``source``, ``samples``,
    ``bridged_samples`` (interpolated over lost packets, never measurements), ``segments``, and of the
    log it was read from (:func:`identify.io.log_fields.layout_fields`; None when not known)
    ``stale_rows`` (dropped when the log was read), ``split_gaps`` (the gaps that split it into the
    segments: ``lines``, ``duration_s`` [s]) and ``split_gaps_total``."""
    return {"source": rec.source, "samples": rec.n_samples, "bridged_samples": int(np.sum(~rec.measured_mask)),
            "segments": rec.n_segments, **layout_fields(rec.meta.get("log"))}


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
        raise ValueError(f"fraction must lie strictly between 0 and 1, got {plain(fraction)}")
    k = int(round(fraction * rec.n_samples))
    if k < 2 or rec.n_samples - k < 2:
        raise ValueError(
            f"{rec.source}: split at {plain(fraction)} of {rec.n_samples} samples leaves a part with fewer than 2 samples"
        )

    return rec.select(slice(0, k), f"{rec.source}[:{k}]"), rec.select(slice(k, None), f"{rec.source}[{k}:]")
