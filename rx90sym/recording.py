"""A recording: joint positions and joint-side torques sampled in time (Khalil angles, SI)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def _frozen(a: np.ndarray | None) -> np.ndarray | None:
    if a is None:
        return None
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Recording:
    """Samples of one motion.

    t: (N,) time [s], uniform step; q: (N, n) joint positions [rad or m], Khalil angles;
    tau: (N, n) joint-side torques [N m] as measured (spring not added); dq: optional (N, n)
    joint velocities; source: file or origin; robot: robot name; meta: free-form provenance.
    """

    t: np.ndarray
    q: np.ndarray
    tau: np.ndarray
    dq: np.ndarray | None = None
    source: str = "<memory>"
    robot: str = ""
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("t", "q", "tau", "dq"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        N = self.t.shape[0]
        if self.t.ndim != 1:
            raise ValueError(f"{self.source}: t must be 1-D, got shape {self.t.shape}")
        for name in ("q", "tau", "dq"):
            a = getattr(self, name)
            if a is not None and (a.ndim != 2 or a.shape[0] != N or a.shape[1] != self.q.shape[1]):
                raise ValueError(f"{self.source}: {name} must have shape ({N}, {self.q.shape[1]}), "
                                 f"got {a.shape}")

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.q.shape[1]

    @property
    def rate(self) -> float:
        """Sampling rate [Hz] from the median time step."""
        return float(1.0 / np.median(np.diff(self.t)))

    def __len__(self) -> int:
        return self.t.shape[0]
