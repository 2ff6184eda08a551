"""A recording on other time stamps: the one interpolation rule of the toolkit.

Positions by cubic Hermite interpolation through the samples and the **recorded velocities**
(:class:`scipy.interpolate.CubicHermiteSpline`) when the recording has some, else a not-a-knot
cubic spline (:class:`scipy.interpolate.CubicSpline`); velocities, torques, currents and
auxiliary columns linearly (no overshoot on noisy signals; a velocity recorded as exactly 0 at
rest stays 0). Used to put an irregular log on a uniform grid (:func:`identify.read_log`) and a
second run on the first one's time stamps (:func:`identify.pair_runs`), always before filtering.

Lost packets: a new time stamp inside a step of the recording longer than
:data:`identify.io.gaps.LOST_STEPS` median steps, or next to a sample that was not measured,
is marked as bridged (``Recording.measured`` False). A recording made of segments is put on one
grid per segment (``t0 + k/rate`` from each segment's first sample).
"""
from __future__ import annotations

import math
import numbers
from dataclasses import replace
from typing import Any, Sequence

import numpy as np

from rx90sym.messages import plain
from rx90sym.recording import Recording

from identify.io.gaps import LOST_STEPS

__all__ = ["check_rate", "concatenate", "interpolate", "resample", "uniform_grid"]


#: A time stamp this many sampling steps from a recorded one is taken as that sample (:func:`interpolate`).
SNAP = 1e-9


def uniform_grid(t0: float, t1: float, rate: float) -> np.ndarray:
    """``t0 + k/rate`` for every k that stays within ``[t0, t1]`` (s; rate in Hz)."""
    count = int(math.floor((t1 - t0) * rate * (1.0 + 1e-12))) + 1
    grid = t0 + np.arange(count) / rate
    grid[-1] = min(grid[-1], t1)  # never beyond the last sample through rounding
    return grid


def interpolate(rec: Recording, t: np.ndarray) -> Recording:
    """The recording at times ``t`` (s, within ``rec.t[0]..rec.t[-1]``), by the module's rule.

    Returns:
        A recording with the same source, robot, meta and signals, on the time stamps ``t``; its
        ``measured`` mask marks the time stamps inside a lost-packet step as bridged.

    Raises:
        ValueError: ``rec`` is made of several segments (interpolate each of :meth:`Recording.pieces`).
    """
    from scipy.interpolate import CubicHermiteSpline, CubicSpline  # when used: a fast start

    if rec.n_segments > 1:
        raise ValueError(f"{rec.source}: {rec.n_segments} segments (gaps too long to bridge): interpolate "
                         f"each segment on its own")
    t = np.asarray(t, dtype=float)
    # A time stamp within SNAP steps of a recorded one is that sample (its time and values exactly):
    # a log resampled on its own clock (a counted clock re-timed) is the log itself, to the last digit.
    near = np.clip(np.searchsorted(rec.t, t), 0, rec.t.size - 1)
    near = np.where((near > 0) & (np.abs(t - rec.t[near - 1]) < np.abs(t - rec.t[near])), near - 1, near)
    on = np.abs(t - rec.t[near]) <= SNAP * (float(np.median(np.diff(rec.t))) if rec.t.size > 1 else 1.0)
    t = np.where(on, rec.t[near], t)
    if rec.dq is not None:
        q = CubicHermiteSpline(rec.t, rec.q, rec.dq, axis=0)(t)
    else:
        q = CubicSpline(rec.t, rec.q, axis=0)(t)

    def linear(a: np.ndarray | None) -> np.ndarray | None:
        if a is None:
            return None
        flat = a.reshape(len(rec.t), -1)
        out = np.column_stack([np.interp(t, rec.t, flat[:, j]) for j in range(flat.shape[1])])
        out[on] = flat[near[on]]
        return out.reshape((len(t),) + a.shape[1:])

    q[on] = rec.q[near[on]]

    return replace(rec, t=t, q=q, tau=linear(rec.tau), dq=linear(rec.dq), current=linear(rec.current),
                   aux={k: linear(v) for k, v in rec.aux.items()}, meta=dict(rec.meta),
                   measured=_measured(rec, t), segment=None)


def _measured(rec: Recording, t: np.ndarray) -> np.ndarray:
    """(len(t),) bool: False where ``t`` falls strictly inside a lost-packet step of ``rec``, or
    inside a step that touches a bridged sample (no new time stamp is more measured than its
    neighbours); a time stamp that equals a recorded one keeps that sample's flag."""
    if rec.t.size < 2:
        return np.ones(t.size, dtype=bool)
    dt = np.diff(rec.t)
    ok = rec.measured_mask
    good_step = (dt <= LOST_STEPS * float(np.median(dt))) & ok[:-1] & ok[1:]
    k = np.clip(np.searchsorted(rec.t, t, side="right") - 1, 0, rec.t.size - 2)
    on_left = t == rec.t[k]
    on_right = t == rec.t[k + 1]
    return np.where(on_left, ok[k], np.where(on_right, ok[k + 1], good_step[k]))


def check_rate(rate: Any) -> None:
    """Refuse a resampling rate that is not a positive finite number of Hz."""
    if not (isinstance(rate, numbers.Real) and math.isfinite(rate) and rate > 0):
        raise ValueError(f"resample: expected a positive rate in Hz, got {plain(rate)}")


def resample(rec: Recording, rate: float) -> Recording:
    """The recording on the uniform grid ``t0 + k/rate`` (rate in Hz) of each segment, from its first
    sample ``t0`` up to its last one; bridged samples marked in ``measured``."""
    check_rate(rate)
    parts = [interpolate(p, uniform_grid(float(p.t[0]), float(p.t[-1]), rate)) for p in rec.pieces()]
    if len(parts) == 1:
        return replace(parts[0], source=rec.source)
    return concatenate(parts, rec.source)


def concatenate(parts: list[Recording], source: str, segments: Sequence[int] | None = None,
                measured: bool = True) -> Recording:
    """One recording made of ``parts``: consecutive segments, each part one (``segments``: the segment
    number of each part instead); ``measured`` False: no ``measured`` mask (every sample measured)."""
    def cat(name: str) -> np.ndarray | None:
        arrays = [getattr(p, name) for p in parts]
        return None if arrays[0] is None else np.concatenate(arrays)

    first = parts[0]
    numbers = range(len(parts)) if segments is None else segments
    segment = np.concatenate([np.full(p.n_samples, k, dtype=np.int64) for k, p in zip(numbers, parts)])
    return replace(first, t=cat("t"), q=cat("q"), tau=cat("tau"), dq=cat("dq"), current=cat("current"),
                   aux={k: np.concatenate([p.aux[k] for p in parts]) for k in first.aux},
                   measured=np.concatenate([p.measured_mask for p in parts]) if measured else None,
                   segment=segment, source=source, meta=dict(first.meta))
