"""Checks of sampled signals shared by the filtering modules (samples on axis 0, rates in Hz)."""
from __future__ import annotations

import math

import numpy as np


def _as_samples(x: np.ndarray, name: str, min_rows: int = 1) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim == 0 or a.shape[0] < min_rows:
        raise ValueError(f"{name}: need at least {min_rows} samples along axis 0, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or inf")
    return a


def _check_rate(rate: float) -> float:
    rate = float(rate)
    if not (rate > 0.0 and math.isfinite(rate)):
        raise ValueError(f"rate must be a positive number of Hz, got {rate!r}")
    return rate
