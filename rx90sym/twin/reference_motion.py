"""The reference motion the twin follows: samples of a trajectory, checked against the limits."""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable

import numpy as np
from scipy.interpolate import CubicHermiteSpline


if TYPE_CHECKING:  # for annotations only
    from ..description import Robot


# --------------------------------------------------------------------------- the reference
Trajectory = Any  # .sample(rate) -> (t, q, qd, qdd), a tuple of arrays, or a callable t -> (q, qd, qdd)


def reference(robot: Robot, trajectory: Trajectory, rate: float, oversample: int = 1,
              duration: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Reference (t, q, qd, qdd) on the grid t0 + k / (rate * oversample) [s, rad, rad/s, rad/s^2].

    The number of grid points is oversample * (number of output samples), so every
    ``oversample``-th point is an output sample time.
    """
    if not np.isfinite(rate) or rate <= 0:
        raise ValueError(f"rate must be > 0 Hz, got {rate}")
    fine = rate * oversample
    if hasattr(trajectory, "sample"):
        t, q, qd, qdd = (np.asarray(a, dtype=float) for a in trajectory.sample(fine))
        _check_reference(robot, t, q, qd, qdd)
        keep = len(t) - len(t) % oversample
        if duration is not None:
            keep = min(keep, int(np.floor(duration * rate + 1e-9)) * oversample)
        return t[:keep], q[:keep], qd[:keep], qdd[:keep]
    if callable(trajectory):
        if duration is None:
            raise ValueError("trajectory: a callable t -> (q, qd, qdd) needs a duration [s]")
        t = np.arange(int(np.floor(duration * rate + 1e-9)) * oversample) / fine
        q, qd, qdd = _evaluate_callable(trajectory, t, robot.n)
        _check_reference(robot, t, q, qd, qdd)
        return t, q, qd, qdd
    try:
        t, q, qd, qdd = (np.asarray(a, dtype=float) for a in trajectory)
    except (TypeError, ValueError):
        raise ValueError("trajectory: expected an object with .sample(rate), a tuple "
                         "(t, q, qd, qdd) of arrays or a callable t -> (q, qd, qdd)") from None
    _check_reference(robot, t, q, qd, qdd)
    span = t[-1] - t[0] if duration is None else min(duration, t[-1] - t[0] + 1 / rate)
    count = int(np.floor(span * rate + 1e-9)) + (1 if duration is None else 0)
    tf = t[0] + np.arange(count * oversample) / fine
    if len(tf) <= len(t) and np.allclose(t[:len(tf)], tf, rtol=0, atol=1e-9 / fine):
        return t[:len(tf)], q[:len(tf)], qd[:len(tf)], qdd[:len(tf)]  # already on the grid
    # Cubic Hermite on (q, qd) and on (qd, qdd): exact at the given samples, C1 between them.
    tc = np.clip(tf, t[0], t[-1])
    q_f = CubicHermiteSpline(t, q, qd, axis=0)(tc)
    qd_f = CubicHermiteSpline(t, qd, qdd, axis=0)(tc)
    qdd_f = np.stack([np.interp(tc, t, qdd[:, j]) for j in range(robot.n)], axis=1)
    return tf, q_f, qd_f, qdd_f


def _evaluate_callable(f: Callable, t: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    try:
        out = tuple(np.asarray(a, dtype=float) for a in f(t))
        if len(out) == 3 and all(a.shape == (len(t), n) for a in out):
            return out
    except (TypeError, ValueError):
        pass  # not vectorised: evaluate sample by sample below
    rows = [tuple(np.asarray(a, dtype=float).reshape(n) for a in f(float(tk))) for tk in t]
    return tuple(np.array([r[i] for r in rows]) for i in range(3))


def _check_reference(robot: Robot, t: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> None:
    if t.ndim != 1 or len(t) < 2:
        raise ValueError(f"trajectory: t must be 1-D with >= 2 samples, got shape {t.shape}")
    for name, a in (("q", q), ("qd", qd), ("qdd", qdd)):
        if a.shape != (len(t), robot.n):
            raise ValueError(f"trajectory: {name} must have shape ({len(t)}, {robot.n}), got {a.shape}")
        bad = np.argwhere(~np.isfinite(a))
        if len(bad):
            raise ValueError(f"trajectory: {name}{bad[0, 1] + 1} is not finite at row {bad[0, 0]}")
    if np.any(np.diff(t) <= 0):
        raise ValueError(f"trajectory: t must increase (row {int(np.argmax(np.diff(t) <= 0)) + 1})")
