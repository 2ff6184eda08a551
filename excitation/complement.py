"""Sequential design: the information of recordings already made, to add to a new trajectory's.

A lab that identified from some recordings and finds a weak parameter group optimises the next
trajectory for the sum of the information matrices (``Objective.prior``): the new motion then
excites what the old ones missed instead of repeating them. Information is counted as in
objective.py, at the objective's ``rate``: a recording of T seconds counts like T seconds of a new
trajectory at that rate, whatever its own sampling rate (its samples are not independent
measurements beyond the controller's bandwidth), so old and new motions weigh by duration.
"""
from __future__ import annotations

from typing import Any, Iterable

import numpy as np

from .criterion import regressor_samples
from .objective import Objective, numeric_information


def prior_information(base_regressor: Any, motions: Iterable[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]],
                      objective: Objective) -> np.ndarray:
    """Sum over motions (t [s] (N,), q, qd, qdd (N, n) Khalil angles) of their information
    matrices (nb, nb) for ``objective`` (its noise and rate; its own prior is not included)."""
    total = None
    plain = Objective("logdet", objective.noise_std, rate=objective.rate)  # no prior, same weights
    for t, q, qd, qdd in motions:
        t = np.asarray(t, dtype=float)
        if t.size < 2 or np.any(np.diff(t) <= 0.0):
            raise ValueError("complement: a recording's time must increase strictly")
        duration = float(t[-1] - t[0]) * t.size / (t.size - 1)
        phi = regressor_samples(base_regressor, np.asarray(q, float), np.asarray(qd, float),
                                np.asarray(qdd, float))
        g = numeric_information(phi, plain, duration)
        total = g if total is None else total + g
    if total is None:
        raise ValueError("complement: no recording given")
    return total
