"""A recording: joint positions and joint-side torques sampled in time (Khalil angles, SI).

Lives in rx90sym so that the simulated robot (rx90sym.twin) produces the same object that
identify reads from files.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

_MEMORY = "<memory>"


class RecordingError(ValueError):
    """A recording (file or arrays) is malformed; the message names file, column and row."""


# --------------------------------------------------------------------------------------------
# The recording
# --------------------------------------------------------------------------------------------


def frozen_array(x: Any) -> np.ndarray:
    """Read-only float64 copy of ``x`` (a Recording must not change under its owner's feet)."""
    a = np.array(x, dtype=float, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Recording:
    """One recorded motion in model conventions.

    Attributes:
        t: (N,) time, s.
        q: (N, n) joint positions, rad, Khalil angles.
        tau: (N, n) joint torques, N·m, joint side (spring not added).
        dq: (N, n) joint velocities, rad/s, or None when not recorded.
        source: file name the data came from, or ``"<memory>"``.
        robot: name of the robot the data belong to.
        meta: provenance (e.g. the simulated robot's true parameters and noise profile).

    Only shapes are checked here; the data checks (finite values, regular time, radians, ...)
    are done by the readers and :func:`recording_from_arrays`.
    """

    t: np.ndarray
    q: np.ndarray
    tau: np.ndarray
    dq: np.ndarray | None = None
    source: str = _MEMORY
    robot: str = ""
    meta: dict = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        t = frozen_array(self.t)
        q = frozen_array(self.q)
        tau = frozen_array(self.tau)
        if t.ndim != 1 or t.size < 1:
            raise RecordingError(f"{self.source}: t must be a non-empty 1-D array, got shape {t.shape}")
        n_samples = t.size
        if q.ndim != 2 or q.shape[0] != n_samples or q.shape[1] < 1:
            raise RecordingError(f"{self.source}: q must have shape ({n_samples}, n), got {q.shape}")
        if tau.shape != q.shape:
            raise RecordingError(f"{self.source}: tau must have shape {q.shape}, got {tau.shape}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "q", q)
        object.__setattr__(self, "tau", tau)
        if self.dq is not None:
            dq = frozen_array(self.dq)
            if dq.shape != q.shape:
                raise RecordingError(f"{self.source}: dq must have shape {q.shape}, got {dq.shape}")
            object.__setattr__(self, "dq", dq)

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.t.size)

    @property
    def n_joints(self) -> int:
        """Number of joints n."""
        return int(self.q.shape[1])

    @property
    def rate(self) -> float:
        """Sampling rate, Hz (from the median time step; nan for a single sample)."""
        if self.t.size < 2:
            return math.nan
        return float(1.0 / np.median(np.diff(self.t)))

    @property
    def duration(self) -> float:
        """Time spanned by the samples, s."""
        return float(self.t[-1] - self.t[0])

    def __repr__(self) -> str:
        return (
            f"Recording(robot={self.robot!r}, source={self.source!r}, samples={self.n_samples}, "
            f"joints={self.n_joints}, rate={self.rate:.6g} Hz, dq={'yes' if self.dq is not None else 'no'})"
        )
