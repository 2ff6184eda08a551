"""What the two trajectory forms share: q(t) = B(t) C, linear in the coefficients C."""
from __future__ import annotations

from typing import Any

import numpy as np


class LinearForm:
    """Mixin for a trajectory form with ``basis(t) -> (Bq, Bqd, Bqdd)`` (each (N, K)),
    ``n_coefficients`` (K) and ``kind`` (for messages)."""

    kind: str = "form"
    n_coefficients: int

    def basis(self, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
        raise NotImplementedError

    def evaluate(self, coefficients: Any, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, qd, qdd), each (N, n) [rad, rad/s, rad/s^2], at times t [s] for coefficients (K, n)."""
        c = np.asarray(coefficients, dtype=float)
        if c.ndim != 2 or c.shape[0] != self.n_coefficients:
            raise ValueError(f"{self.kind} coefficients: expected shape ({self.n_coefficients}, n), "
                             f"got {c.shape}")
        bq, bd, bdd = self.basis(t)
        return bq @ c, bd @ c, bdd @ c
