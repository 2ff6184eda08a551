"""Via-point trajectories: joint positions at chosen times, joined by a quintic spline.

Controllers such as the Stäubli CS8 interpolate between via points themselves, so a trajectory
can also be described by K positions at times t_0 = 0 < t_1 < ... < t_{K-1} = T. Between them
we use the interpolating quintic B-spline with qd = qdd = 0 at both ends (clamped), which is C4
inside and starts and ends at rest. The spline is linear in the via positions, so, exactly as for
the Fourier series, every sample is Q = Bq(t) @ P with P the (K, n) via positions; the basis is
the spline of the identity matrix.

With ``closed=True`` (default) the last via point is the first one, so the motion returns to its
start (as the Fourier form does); the free coefficients then hold K - 1 positions.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.interpolate import make_interp_spline

from .form import LinearForm


@dataclass(frozen=True)
class ViaPointSpline(LinearForm):
    """Quintic spline through via points at ``times`` [s] (strictly increasing, first 0)."""

    times: tuple[float, ...]
    closed: bool = True

    def __post_init__(self) -> None:
        t = np.asarray(self.times, dtype=float)
        if t.ndim != 1 or t.size < 3:
            raise ValueError(f"via points: need at least 3 times, got {t.size}")
        if not np.all(np.isfinite(t)) or t[0] != 0.0 or np.any(np.diff(t) <= 0.0):
            raise ValueError("via points: times must be finite, start at 0 s and strictly increase")
        object.__setattr__(self, "times", tuple(float(x) for x in t))

    @staticmethod
    def uniform(duration: float, count: int, closed: bool = True) -> "ViaPointSpline":
        """``count`` via points equally spaced over ``duration`` [s] (ends included)."""
        if count < 3:
            raise ValueError(f"via points: need at least 3 points, got {count}")
        return ViaPointSpline(tuple(np.linspace(0.0, float(duration), int(count))), closed)

    kind = "via_points"

    @property
    def duration(self) -> float:
        """T [s]."""
        return self.times[-1]

    @property
    def max_frequency_hz(self) -> float:
        """Highest frequency a via sequence can carry: alternate points, period 2 min(dt) [Hz]."""
        return 1.0 / (2.0 * float(np.min(np.diff(self.times))))

    @property
    def n_coefficients(self) -> int:
        """Rows of the coefficient matrix: one per via point."""
        return len(self.times)

    def describe(self) -> dict[str, Any]:
        """JSON-ready description of the parameterisation."""
        return {"form": self.kind, "duration": self.duration, "times_s": list(self.times),
                "closed": self.closed, "interpolation": "quintic spline, qd = qdd = 0 at both ends"}

    def basis(self, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Basis matrices (Bq, Bd, Bdd), each (N, K), at times t [s] in [0, T]."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if np.any(t < -1e-12) or np.any(t > self.duration + 1e-12):
            raise ValueError(f"via points: sample times must lie in [0, {self.duration}] s")
        k = len(self.times)
        zero = np.zeros(k)  # derivative values have the trailing shape of the data (identity rows)
        clamped = ([(1, zero), (2, zero)], [(1, zero), (2, zero)])  # qd = qdd = 0 at both ends
        spline = make_interp_spline(np.asarray(self.times), np.eye(k), k=5, bc_type=clamped)
        t = np.clip(t, 0.0, self.duration)
        return spline(t), spline.derivative(1)(t), spline.derivative(2)(t)

    def rest_basis(self) -> np.ndarray:
        """Matrix N (K, K-1 if closed else K): P = N @ Z; closed ties the last point to the first."""
        k = len(self.times)
        if not self.closed:
            return np.eye(k)
        n = np.eye(k, k - 1)
        n[-1, 0] = 1.0
        return n

    def constant(self, q0: Any) -> np.ndarray:
        """Free coefficients Z of the motionless trajectory q(t) = q0 [rad]."""
        q0 = np.asarray(q0, dtype=float)
        return np.tile(q0, (self.rest_basis().shape[1], 1))

    def random_free(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """Random motion part of the free coefficients: N(0, 1) displacements [rad]."""
        return rng.standard_normal((self.rest_basis().shape[1], n))
