"""Samples of one time grid carried onto another by linear interpolation (a decimated prediction onto a
recording's own time stamps, where it is scored against the raw measured torques)."""
from __future__ import annotations

import numpy as np

__all__ = ["onto"]


def onto(t: np.ndarray, t_from: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``values`` (S, ...) at the increasing times ``t_from`` (S,) [s] interpolated linearly at ``t``
    (N,) [s]; (N, ...), every column alike. Outside [t_from[0], t_from[-1]] the end values are held
    (numpy.interp's rule): callers keep the samples inside only."""
    values = np.asarray(values, dtype=float)
    t, t_from = np.asarray(t, dtype=float), np.asarray(t_from, dtype=float)
    if t_from.size == 1:
        return np.repeat(values[:1], t.size, axis=0)
    k = np.clip(np.searchsorted(t_from, t, side="right") - 1, 0, t_from.size - 2)
    w = np.clip((t - t_from[k]) / (t_from[k + 1] - t_from[k]), 0.0, 1.0).reshape((-1,) + (1,) * (values.ndim - 1))
    return values[k] + w * (values[k + 1] - values[k])
