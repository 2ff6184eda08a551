"""Samples of one time grid carried onto another by linear interpolation (a decimated prediction onto a
recording's own time stamps, where it is scored against the raw measured torques)."""
from __future__ import annotations

import numpy as np

__all__ = ["onto"]


def onto(t: np.ndarray, t_from: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``values`` (S, n) at the increasing times ``t_from`` (S,) [s] interpolated linearly at ``t``
    (N,) [s]; (N, n). Outside [t_from[0], t_from[-1]] the end values are held: callers keep the
    samples inside only."""
    values = np.asarray(values, dtype=float)
    return np.column_stack([np.interp(t, t_from, values[:, j]) for j in range(values.shape[1])])
