"""Drive gains: from motor currents to joint torques (the file format and its application).

Joint torques follow from motor currents through one gain per motor and the robot's transmission::

    τ = Rt · diag(k) · (i − i0)                  (side "motor": k in N·m/A on the motor side)
    τ = diag(k) · (i − i0)                       (side "joint": k in N·m/A on the joint side)

``Rt`` is the robot's motor-to-joint torque map (gear ratios and the coupled wrist of the RX90 and
TX40); ``i0`` are optional current offsets (A). An uncoupled arm without gear data (UR10e) uses
joint-side gains. The estimation of the gains with a payload of known mass lives in
:mod:`identify.gains.drive_gains`; this module only reads, writes and applies them.

JSON format (written by ``rx90 gains --json``, read by every ``--gains``)::

    {"robot": "ur10e", "side": "joint", "gains": [k1, ..., kn],
     "std": [σ1 | null, ...], "rel_std_pct": [...], "flagged": [joint numbers],
     "fixed": [joint numbers], "current_offsets": [A, ...], "method": "global", "mass": 2.805}

Only ``gains`` is required; ``side`` defaults to ``"joint"``, offsets to 0.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from rx90sym.files import read_json
import rx90sym
from rx90sym.recording import Recording, RecordingError, frozen_array

from identify.io.checks import RecordingWarning

__all__ = ["DriveGains", "read_gains", "apply_gains", "warn_negative"]

_SIDES = ("joint", "motor")


@dataclass(frozen=True)
class DriveGains:
    """Per-motor drive gains.

    Attributes:
        gains: (n,) N·m/A, on the side named by ``side``.
        side: ``"joint"`` (τ = diag(k)·(i − i0)) or ``"motor"`` (τ = Rt·diag(k)·(i − i0)).
        current_offsets: (n,) A, subtracted from the currents before the gains.
        std: (n,) standard deviation of each gain, N·m/A (nan where fixed or unknown).
        robot: robot name the gains belong to ("" when not stated).
        source: file or text the gains came from.
        extra: the other JSON fields (method, mass, flagged, ...), kept for reports.
    """

    gains: np.ndarray
    side: str = "joint"
    current_offsets: np.ndarray | None = None
    std: np.ndarray | None = None
    robot: str = ""
    source: str = "<memory>"
    extra: dict = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        k = frozen_array(self.gains).reshape(-1)
        if k.size < 1 or not np.all(np.isfinite(k)) or np.any(k == 0):
            raise ValueError(f"{self.source}: gains must be finite and non-zero, got {k.tolist()}")
        if self.side not in _SIDES:
            raise ValueError(f"{self.source}: side must be one of {_SIDES}, got {self.side!r}")
        object.__setattr__(self, "gains", k)
        i0 = np.zeros(k.size) if self.current_offsets is None else frozen_array(self.current_offsets).reshape(-1)
        if i0.shape != k.shape or not np.all(np.isfinite(i0)):
            raise ValueError(f"{self.source}: current_offsets must be {k.size} finite numbers, got {i0.tolist()}")
        object.__setattr__(self, "current_offsets", frozen_array(i0))
        std = np.full(k.size, np.nan) if self.std is None else frozen_array(self.std).reshape(-1)
        if std.shape != k.shape:
            raise ValueError(f"{self.source}: std must have {k.size} entries, got {std.size}")
        object.__setattr__(self, "std", frozen_array(std))

    def torques(self, robot: rx90sym.Robot, current: np.ndarray) -> np.ndarray:
        """Joint torques (N, n), N·m, from motor currents (N, n), A."""
        i = np.asarray(current, dtype=float)
        if i.ndim != 2 or i.shape[1] != self.gains.size:
            raise ValueError(f"{self.source}: {self.gains.size} gains for currents of shape {i.shape}")
        motor = (i - self.current_offsets) * self.gains
        return motor @ np.asarray(robot.Rt).T if self.side == "motor" else motor

    def to_dict(self) -> dict:
        """The JSON form (module docstring); nan σ become null."""
        return {**self.extra, "robot": self.robot, "side": self.side, "gains": self.gains.tolist(),
                "std": [None if not np.isfinite(s) else float(s) for s in self.std],
                "current_offsets": self.current_offsets.tolist()}


def read_gains(spec: str | Path, robot: rx90sym.Robot) -> DriveGains:
    """Gains from ``"K1,...,Kn"`` (joint side, N·m/A) or from a JSON file (module docstring).

    Raises:
        ValueError: not n numbers, a file that cannot be read, or gains of another robot.
    """
    text = str(spec)
    if text.lower().endswith(".json") or Path(text).is_file():
        data = read_json(text)   # ValueError naming the file (and line, column)
        if not isinstance(data, dict) or "gains" not in data:
            raise ValueError(f"{text}: no 'gains' list (the output of rx90 gains --json)")
        declared = str(data.get("robot") or "")
        if declared and declared != robot.name:
            raise ValueError(f"{text}: gains of robot '{declared}', not of '{robot.name}'")
        extra = {k: v for k, v in data.items() if k not in ("gains", "side", "current_offsets", "std", "robot")}
        std = [np.nan if s is None else s for s in data["std"]] if data.get("std") is not None else None
        try:
            gains = DriveGains(np.asarray(data["gains"], dtype=float), side=str(data.get("side", "joint")),
                               current_offsets=data.get("current_offsets"), std=std, robot=declared,
                               source=text, extra=extra)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{text}: {exc}".replace(f"{text}: {text}: ", f"{text}: ")) from None
    else:
        cells = [c.strip() for c in text.split(",")]
        try:
            values = [float(c) for c in cells]
        except ValueError:
            raise ValueError(f"--gains: expected {robot.n} comma-separated numbers (N·m/A) or a JSON file, "
                             f"got {text!r}") from None
        gains = DriveGains(np.asarray(values), side="joint", robot=robot.name, source="--gains")
    if gains.gains.size != robot.n:
        raise ValueError(f"{gains.source}: {gains.gains.size} gains for robot '{robot.name}' with {robot.n} joints")
    warn_negative(gains)
    return gains


def warn_negative(gains: DriveGains) -> None:
    """A warning naming each negative gain: its torques have the opposite sign of its currents, right
    only when that motor's current is logged with its sign reversed (a sign error otherwise turns
    the joint's friction and inertia negative in every fit made with these gains)."""
    negative = np.flatnonzero(gains.gains < 0)
    if not negative.size:
        return
    what = "motor" if gains.side == "motor" else "joint"
    listed = ", ".join(f"{what} {j + 1}: {gains.gains[j]:g} N·m/A" for j in negative)
    warnings.warn(f"{gains.source}: negative drive gain ({listed}): torques of opposite sign to the currents, "
                  f"right only if the controller logs that current with its sign reversed; otherwise fix the "
                  f"sign (a fit would show negative friction and inertia on that joint)",
                  RecordingWarning, stacklevel=3)


def apply_gains(rec: Recording, gains: DriveGains, robot: rx90sym.Robot) -> Recording:
    """The recording with joint torques computed from its motor currents (currents kept).

    Raises:
        RecordingError: the recording has no currents.
    """
    if rec.current is None:
        raise RecordingError(f"{rec.source}: drive gains given, but the recording holds no motor currents")
    meta = {**rec.meta, "gains": gains.to_dict()}
    return replace(rec, tau=gains.torques(robot, rec.current), meta=meta)
