"""Finite Fourier series joint trajectories (Swevers, Ganseman, Tükel, De Schutter, Van Brussel 1997).

Per joint i, with base frequency w_f = 2 pi / T [rad/s] and L harmonics:

    q_i(t)   = q0_i + sum_l  a_il/(l w_f) sin(l w_f t) - b_il/(l w_f) cos(l w_f t)      [rad]
    qd_i(t)  =        sum_l  a_il cos(l w_f t) + b_il sin(l w_f t)                      [rad/s]
    qdd_i(t) =        sum_l -a_il l w_f sin(l w_f t) + b_il l w_f cos(l w_f t)          [rad/s^2]

The coefficients of all joints form one matrix C of shape (2L+1, n) with rows
[q0, a_1..a_L, b_1..b_L], so that every sampled quantity is linear in C: Q = Bq(t) @ C with the
basis matrices of :meth:`FourierSeries.basis`. That linearity is what the optimiser exploits:
position, velocity and acceleration limits become linear constraints.

Rest at both ends: qd(0) = sum_l a_l = 0 and qdd(0) = w_f sum_l l b_l = 0; the series has period
T, so the same holds at t = T and q(T) = q(0). Rather than imposing these as equality constraints,
the optimiser works on free coefficients Z with C = N @ Z where the columns of N span the
coefficients at rest (:meth:`FourierSeries.rest_basis`), so every candidate is rest-to-rest.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import block_diag, null_space

from .form import LinearForm


@dataclass(frozen=True)
class FourierSeries(LinearForm):
    """A periodic finite Fourier series of ``harmonics`` harmonics over ``duration`` seconds."""

    duration: float
    harmonics: int

    def __post_init__(self) -> None:
        if not np.isfinite(self.duration) or self.duration <= 0.0:
            raise ValueError(f"Fourier series: duration must be a positive number of seconds, "
                             f"got {self.duration!r}")
        if int(self.harmonics) != self.harmonics or self.harmonics < 2:
            # One harmonic cannot start at rest: sum a_l = 0 and sum l b_l = 0 force a_1 = b_1 = 0.
            raise ValueError(f"Fourier series: harmonics must be an integer >= 2 (rest-to-rest needs "
                             f"at least two), got {self.harmonics!r}")
        object.__setattr__(self, "harmonics", int(self.harmonics))
        object.__setattr__(self, "duration", float(self.duration))

    # ----------------------------------------------------------------- description
    kind = "fourier"

    @property
    def base_frequency(self) -> float:
        """w_f = 2 pi / T [rad/s]."""
        return 2.0 * np.pi / self.duration

    @property
    def max_frequency_hz(self) -> float:
        """Highest frequency present in q, qd and qdd: L / T [Hz]."""
        return self.harmonics / self.duration

    @property
    def n_coefficients(self) -> int:
        """Rows of the coefficient matrix: 2L + 1."""
        return 2 * self.harmonics + 1

    def describe(self) -> dict[str, Any]:
        """JSON-ready description of the parameterisation."""
        return {"form": self.kind, "duration": self.duration, "harmonics": self.harmonics,
                "base_frequency_rad_s": self.base_frequency}

    # ----------------------------------------------------------------- linear maps
    def basis(self, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Basis matrices (Bq, Bd, Bdd), each (N, 2L+1), at times t [s].

        q = Bq @ C [rad], qd = Bd @ C [rad/s], qdd = Bdd @ C [rad/s^2] for coefficients C (2L+1, n).
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        w = self.base_frequency * np.arange(1, self.harmonics + 1)  # l w_f [rad/s]
        s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
        ones, zeros = np.ones((t.size, 1)), np.zeros((t.size, 1))
        bq = np.hstack([ones, s / w, -c / w])
        bd = np.hstack([zeros, c, s])
        bdd = np.hstack([zeros, -s * w, c * w])
        return bq, bd, bdd

    def rest_basis(self) -> np.ndarray:
        """Matrix N (2L+1, 2L-1) with orthonormal blocks; C = N @ Z is at rest at t = 0 and T.

        Row 0 of Z is the offset q0 itself; the other rows are coordinates in the null spaces of
        [1 ... 1] (velocity) and [1 2 ... L] (acceleration), so that random Z is isotropic.
        """
        L = self.harmonics
        na = null_space(np.ones((1, L)))
        nb = null_space(np.arange(1, L + 1, dtype=float)[None, :])
        return block_diag(np.ones((1, 1)), na, nb)

    def constant(self, q0: Any) -> np.ndarray:
        """Free coefficients Z (2L-1, n) of the motionless trajectory q(t) = q0 [rad]."""
        q0 = np.asarray(q0, dtype=float)
        z = np.zeros((2 * self.harmonics - 1, q0.size))
        z[0] = q0
        return z

    def random_free(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """Random motion part of the free coefficients (offset row zero), isotropic N(0, 1) [rad/s]."""
        z = rng.standard_normal((2 * self.harmonics - 1, n))
        z[0] = 0.0
        return z

    # ----------------------------------------------------------------- evaluation
    def split(self, coefficients: Any) -> dict[str, np.ndarray]:
        """Coefficients as named blocks: q0 (n,) [rad], a and b (n, L) [rad/s]."""
        c = np.asarray(coefficients, dtype=float)
        L = self.harmonics
        return {"q0": c[0], "a": c[1:L + 1].T, "b": c[L + 1:].T}

    def join(self, q0: Any, a: Any, b: Any) -> np.ndarray:
        """Coefficient matrix (2L+1, n) from q0 (n,) [rad], a and b (n, L) [rad/s]."""
        q0 = np.asarray(q0, dtype=float)
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        if a.shape != (q0.size, self.harmonics) or b.shape != a.shape:
            raise ValueError(f"Fourier coefficients: a and b must be (n, {self.harmonics}) for "
                             f"n = {q0.size}, got {a.shape} and {b.shape}")
        return np.vstack([q0[None, :], a.T, b.T])
