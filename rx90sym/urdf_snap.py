"""Joint origins of a URDF as makers write them: right angles and zero lengths made exact.

Makers write pi/2 as ``1.5708``, ``1.571`` or ``1.57`` and leave residues such as 1e-6 m in a
joint's ``xyz``. Kept as written, such an origin tilts a joint axis by a few micro- to milliradians:
the model then has a base parameter that the exact geometry groups away, an almost collinear
column (the regressor's rank depends on the rank threshold) and estimates of +-1e5. So, by
default, each joint origin is snapped (docs/urdf.md):

- an ``rpy`` component within ``snap`` [rad] of a multiple of pi/2 is that multiple, its cosine
  and sine exactly 0 or +-1 (a mixed ``rpy="1.5708 -2.7549 0"`` keeps -2.7549);
- a rotation within ``snap`` (angle of the rotation between them) of an axis-aligned one (the 24
  signed permutations) is that one, for the ``rpy`` of a gimbal lock whose components are not
  near right angles;
- an ``xyz`` component within ``snap_length`` [m] of 0 is 0.

``snap = 0`` turns both off (the file as written). Changes larger than round-off
(:data:`SILENT_RAD`, :data:`SILENT_M`) are listed, joint by joint (written, used).
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

#: Default angle tolerance [rad]. Catches every multiple of pi/2 up to 2 pi written with two
#: decimals or more (1.57: 8.0e-4 off; 3.14: 1.6e-3; 4.71: 2.4e-3; 6.28: 3.2e-3; 1.571: 2.0e-4;
#: 1.5708: 3.7e-6); an axis snapped wrongly moves by at most 4 mrad (0.23 deg). docs/urdf.md.
SNAP_RAD = 4e-3
#: Default length tolerance [m]: residues such as 1e-6 m are zeros; 10 um is below any drawn offset.
SNAP_LENGTH_M = 1e-5
#: Largest accepted angle tolerance [rad] (beyond it a deliberate angle could be snapped).
MAX_SNAP_RAD = 0.01
#: Largest accepted length tolerance [m] (beyond it a drawn offset could be zeroed).
MAX_SNAP_LENGTH_M = 1e-3
#: Changes up to these are round-off of files writing 10+ digits (1.57079632679): not listed.
SILENT_RAD = 1e-9
SILENT_M = 1e-9

_QUARTER = math.pi / 2
# cos, sin of k pi/2 for k mod 4: exact.
_EXACT = ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))



def matrix_rpy(R: np.ndarray) -> tuple[float, float, float]:
    """URDF roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll))."""
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if math.hypot(R[0, 0], R[1, 0]) < 1e-12:  # gimbal lock: yaw 0
        return math.atan2(-R[1, 2], R[1, 1]), pitch, 0.0
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])

def check_tolerances(snap: float, snap_length: float) -> None:
    """ValueError naming the value when a tolerance is negative, not finite or too large."""
    for name, value, top, unit in (("snap", snap, MAX_SNAP_RAD, "rad"),
                                   ("snap_length", snap_length, MAX_SNAP_LENGTH_M, "m")):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ValueError(f"{name} must be a finite number of {unit}, got {value!r}")
        if value < 0 or value > top:
            raise ValueError(f"{name} = {value:g} {unit} is outside [0, {top:g}] {unit}"
                             + (" (0 keeps the file as written)" if name == "snap" else ""))


@dataclass(frozen=True)
class SnappedOrigin:
    """A joint origin as used: rotation R (child frame in parent frame), translation p [m], the
    rpy [rad] and xyz [m] they stand for; rotated, moved: changed beyond round-off (an entry of R
    by more than SILENT_RAD, a length by more than SILENT_M)."""

    R: np.ndarray
    p: np.ndarray
    rpy: tuple[float, float, float]
    xyz: tuple[float, float, float]
    rotated: bool = False
    moved: bool = False

    @property
    def changed(self) -> bool:
        return self.rotated or self.moved


def _quarter_turns(angle: float, snap: float) -> int | None:
    """k when ``angle`` is within ``snap`` of k pi/2 (None otherwise)."""
    k = round(angle / _QUARTER)
    return int(k) if abs(angle - k * _QUARTER) <= snap else None


def _cos_sin(angle: float, k: int | None) -> tuple[float, float]:
    return _EXACT[k % 4] if k is not None else (math.cos(angle), math.sin(angle))


def rpy_rotation(rpy: Sequence[float], turns: Sequence[int | None] = (None, None, None)) -> np.ndarray:
    """URDF fixed-axis roll-pitch-yaw R = Rz(y) Ry(p) Rx(r); a component with a number of quarter
    turns in ``turns`` uses that right angle's exact cosine and sine."""
    (cr, sr), (cp, sp), (cy, sy) = (_cos_sin(a, k) for a, k in zip(rpy, turns))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _axis_aligned() -> list[np.ndarray]:
    """The 24 rotations whose columns are signed unit axes."""
    out = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            A = np.zeros((3, 3))
            A[list(perm), [0, 1, 2]] = signs
            if np.linalg.det(A) > 0:
                out.append(A)
    return out


_AXIS_ALIGNED = _axis_aligned()


def nearest_axis_aligned(R: np.ndarray) -> tuple[np.ndarray, float]:
    """The axis-aligned rotation nearest to R and the angle [rad] of the rotation between them."""
    A = max(_AXIS_ALIGNED, key=lambda A: float(np.trace(A.T @ R)))
    # ||R - A||_F = 2 sqrt(2) sin(angle / 2): accurate for small angles (acos of the trace is not)
    return A, 2.0 * math.asin(min(1.0, float(np.linalg.norm(R - A)) / (2.0 * math.sqrt(2.0))))


def snap_origin(rpy: Sequence[float], xyz: Sequence[float], snap: float = SNAP_RAD,
                snap_length: float = SNAP_LENGTH_M) -> SnappedOrigin:
    """The origin ``rpy`` [rad], ``xyz`` [m] as used (module docstring); ``snap`` 0: as written."""
    rpy, xyz = tuple(float(a) for a in rpy), tuple(float(x) for x in xyz)
    if snap == 0:
        return SnappedOrigin(rpy_rotation(rpy), np.array(xyz), rpy, xyz)
    turns = tuple(_quarter_turns(a, snap) for a in rpy)
    used_rpy = tuple(a if k is None else k * _QUARTER for a, k in zip(rpy, turns))
    R = rpy_rotation(rpy, turns)
    if None in turns:  # a gimbal lock's rpy may be a right-angle rotation with other components
        A, angle = nearest_axis_aligned(rpy_rotation(rpy))
        if angle <= snap:
            R, used_rpy = A, matrix_rpy(A)
    used_xyz = tuple(0.0 if abs(x) <= snap_length else x for x in xyz)
    rotated = float(np.abs(rpy_rotation(rpy) - R).max()) > SILENT_RAD
    moved = max(abs(a - b) for a, b in zip(xyz, used_xyz)) > SILENT_M
    return SnappedOrigin(R, np.array(used_xyz), used_rpy, used_xyz, rotated, moved)


def _angle_text(a: float) -> str:
    k = round(a / _QUARTER)
    if a == k * _QUARTER:
        return {0: "0", 1: "pi/2", -1: "-pi/2", 2: "pi", -2: "-pi", 3: "3pi/2", -3: "-3pi/2"}.get(k, f"{k / 2:g}pi")
    return f"{a:.10g}"


def change_line(joint: str, rpy: Sequence[float], xyz: Sequence[float], used: SnappedOrigin) -> str:
    """'joint NAME: rpy WRITTEN -> USED, xyz WRITTEN -> USED' (the parts that changed)."""
    parts = []
    if used.rotated:
        parts.append(f"rpy {' '.join(f'{a:.10g}' for a in rpy)} -> {' '.join(_angle_text(a) for a in used.rpy)}")
    if used.moved:
        parts.append(f"xyz {' '.join(f'{a:.10g}' for a in xyz)} -> {' '.join(f'{a:.10g}' for a in used.xyz)}")
    return f"joint {joint!r}: " + ", ".join(parts)
