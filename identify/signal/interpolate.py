"""Samples of one time grid carried onto another by linear interpolation (a decimated prediction onto a
recording's own time stamps, where it is scored against the raw measured torques)."""
from __future__ import annotations

import numpy as np

__all__ = ["onto", "onto_weights"]


def onto_weights(t: np.ndarray, t_from: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(k, w) such that ``values[k] + w (values[k + 1] - values[k])`` is :func:`onto`'s value at each
    time of ``t`` (N,) [s] from samples at the increasing times ``t_from`` (S >= 2,) [s]: the same
    weights for every column of ``values``."""
    t, t_from = np.asarray(t, dtype=float), np.asarray(t_from, dtype=float)
    k = np.clip(np.searchsorted(t_from, t, side="right") - 1, 0, t_from.size - 2)
    return k, np.clip((t - t_from[k]) / (t_from[k + 1] - t_from[k]), 0.0, 1.0)


def onto(t: np.ndarray, t_from: np.ndarray, values: np.ndarray,
         weights: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """``values`` (S, ...) at the increasing times ``t_from`` (S,) [s] interpolated linearly at ``t``
    (N,) [s]; (N, ...), every column alike. Outside [t_from[0], t_from[-1]] the end values are held
    (numpy.interp's rule): callers keep the samples inside only. weights: :func:`onto_weights` of
    ``t`` and ``t_from`` when already computed (several arrays on one pair of grids)."""
    values = np.asarray(values, dtype=float)
    if np.size(t_from) == 1:
        return np.repeat(values[:1], np.size(t), axis=0)
    k, w = weights if weights is not None else onto_weights(t, t_from)
    w = w.reshape((-1,) + (1,) * (values.ndim - 1))
    return values[k] + w * (values[k + 1] - values[k])
