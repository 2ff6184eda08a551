"""A recording on other time stamps: the one interpolation rule of the toolkit.

Positions by cubic Hermite interpolation through the samples and the **recorded velocities**
(:class:`scipy.interpolate.CubicHermiteSpline`) when the recording has some, else a not-a-knot
cubic spline (:class:`scipy.interpolate.CubicSpline`); velocities, torques, currents and
auxiliary columns linearly (no overshoot on noisy signals; a velocity recorded as exactly 0 at
rest stays 0). Used to put an irregular log on a uniform grid (:func:`identify.read_log`) and a
second run on the first one's time stamps (:func:`identify.pair_runs`), always before filtering.
"""
from __future__ import annotations

import math
import numbers
from dataclasses import replace

import numpy as np

from rx90sym.messages import plain
from rx90sym.recording import Recording

__all__ = ["interpolate", "resample", "uniform_grid"]


def uniform_grid(t0: float, t1: float, rate: float) -> np.ndarray:
    """``t0 + k/rate`` for every k that stays within ``[t0, t1]`` (s; rate in Hz)."""
    count = int(math.floor((t1 - t0) * rate * (1.0 + 1e-12))) + 1
    grid = t0 + np.arange(count) / rate
    grid[-1] = min(grid[-1], t1)  # never beyond the last sample through rounding
    return grid


def interpolate(rec: Recording, t: np.ndarray) -> Recording:
    """The recording at times ``t`` (s, within ``rec.t[0]..rec.t[-1]``), by the module's rule.

    Returns:
        A recording with the same source, robot, meta and signals, on the time stamps ``t``.
    """
    from scipy.interpolate import CubicHermiteSpline, CubicSpline  # when used: a fast start

    t = np.asarray(t, dtype=float)
    if rec.dq is not None:
        q = CubicHermiteSpline(rec.t, rec.q, rec.dq, axis=0)(t)
    else:
        q = CubicSpline(rec.t, rec.q, axis=0)(t)

    def linear(a: np.ndarray | None) -> np.ndarray | None:
        if a is None:
            return None
        flat = a.reshape(len(rec.t), -1)
        out = np.column_stack([np.interp(t, rec.t, flat[:, j]) for j in range(flat.shape[1])])
        return out.reshape((len(t),) + a.shape[1:])

    return replace(rec, t=t, q=q, tau=linear(rec.tau), dq=linear(rec.dq), current=linear(rec.current),
                   aux={k: linear(v) for k, v in rec.aux.items()}, meta=dict(rec.meta))


def resample(rec: Recording, rate: float) -> Recording:
    """The recording on the uniform grid ``rec.t[0] + k/rate`` (rate in Hz) up to its last sample."""
    if not (isinstance(rate, numbers.Real) and math.isfinite(rate) and rate > 0):
        raise ValueError(f"resample: expected a positive rate in Hz, got {plain(rate)}")
    return interpolate(rec, uniform_grid(float(rec.t[0]), float(rec.t[-1]), rate))
