"""Delay between the positions and the torques (or currents) of a log.

A controller often logs torques a few milliseconds after the positions they belong to; an
uncompensated lag of a few ms biases inertia and friction. The lag is estimated as the shift of
the torques that minimises the residual of a first least-squares fit on the same W (only Y moves):
a coarse grid of whole steps, then a parabola through the best three points (a fraction of a sample).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.signal.filtering import decimate
from identify.observation.matrix import automatic_cutoff, column_regressor, filtered_motions, shifted_torques, stack_rows
from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.observation.processing import RestPolicy, drops_rest

__all__ = ["DelayEstimate", "delay_grid", "estimate_delay", "joint_log_rms", "refined_delay"]


@dataclass(frozen=True, eq=False)
class DelayEstimate:
    """delay [s] (> 0: torques lag the positions; compensated by τ(t + delay)); grid [s] and cost
    (sum over joints of log residual RMS of the fit) of the coarse search; at_bound: the best grid
    point is at ±max_delay (the true lag may be larger)."""

    delay: float
    grid: np.ndarray
    cost: np.ndarray
    at_bound: bool

    def summary(self) -> str:
        warn = " (at the search bound: the lag may be larger)" if self.at_bound else ""
        return f"torque delay {1e3 * self.delay:.3g} ms{warn}"


def _costs(W: np.ndarray, Y: np.ndarray, joint: np.ndarray, n: int) -> np.ndarray:
    """The cost of each column of ``Y`` (rows, lags): plain LS on W, then the sum over joints of
    the log of each joint's residual RMS (scale-free: every joint counts alike whatever its torque range)."""
    x, *_ = np.linalg.lstsq(W, Y, rcond=None)
    r = Y - W @ x
    return sum((np.log(np.sqrt(np.mean(r[joint == j] ** 2, axis=0)) + 1e-300) for j in range(n) if np.any(joint == j)),
               np.zeros(Y.shape[1]))


def estimate_delay(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any = None,
                   cutoff: float | None = None, decimate_to: float | None = DEFAULT_DECIMATE_TO,
                   spring: bool = True, min_velocity: float | None = None, rest: RestPolicy = "drop",
                   max_delay: float = 0.02, steps: int = 41) -> DelayEstimate:
    """Torque-to-position lag [s] of ``recordings`` (one lag for all), within ±``max_delay`` s.

    The filtering options are those of :func:`identify.observation_matrix`; ``steps`` points on the
    coarse grid (at least one sampling period apart), refined by a parabola.
    """
    if not (max_delay > 0 and np.isfinite(max_delay)):
        raise ValueError(f"max_delay must be a positive duration in s, got {max_delay!r}")
    names, regressor = column_regressor(robot, base)
    cutoff = cutoff if cutoff is not None else automatic_cutoff(recordings, decimate_to)
    motions, _, pieces = filtered_motions(robot, recordings, cutoff, decimate_to, spring, regressor, names,
                                          min_velocity, rest)
    masks = [m.rows(min_velocity is not None and drops_rest(rest)) for m in motions]
    period = max(float(np.median(np.diff(rec.t))) for rec in recordings)
    grid, step = delay_grid(period, max_delay, steps)

    # W does not depend on the lag: its rows stacked once; the torques of every lag shifted, decimated in one
    # call (each column filtered alone) and fitted together (one factorisation of W for all the lags).
    W, _, joint, samples = stack_rows([m.Phi for m in motions], [m.Y for m in motions], masks=masks)
    Ys = []
    for rec, m in zip(pieces, motions):
        group = max(1, LAG_BYTES // (8 * robot.n * max(1, np.asarray(rec.t)[m.kept].size)))  # lags at once: memory bounded
        parts = []
        for g in range(0, grid.size, group):
            Y = np.stack([shifted_torques(rec, d)[m.kept] + m.extra for d in grid[g:g + group]], axis=2)  # (S, n, lags)
            parts.append(decimate(Y, m.factor) if m.factor > 1 else Y)
        Ys.append(np.concatenate(parts, axis=2))
    Y = np.concatenate(Ys)[samples, joint]   # (rows, lags), the rows of W
    return refined_delay(grid, _costs(W, Y, joint, robot.n), step)


#: Bytes of shifted torques :func:`estimate_delay` holds at once before decimating them.
LAG_BYTES = 64 << 20


def delay_grid(period: float, max_delay: float = 0.02, steps: int = 41) -> tuple[np.ndarray, float]:
    """The coarse grid of lags [s] of :func:`estimate_delay` for a sampling ``period`` [s], and its step [s]."""
    step = max(period, 2 * max_delay / (steps - 1))
    return np.arange(-max_delay, max_delay + step / 2, step), step


def joint_log_rms(systems: Sequence[Any]) -> float:
    """The cost of :func:`estimate_delay` from the joints' compressed systems of one lag: plain LS on
    all joints, then the sum over joints of the log of each joint's residual RMS."""
    from identify.estimation.compression import stack_systems

    stacked = stack_systems(systems)
    x, *_ = np.linalg.lstsq(stacked.R, stacked.z, rcond=None)
    return float(sum(np.log(np.sqrt(s.rss(x) / s.rows) + 1e-300) for s in systems if s.rows))


def refined_delay(grid: np.ndarray, costs: np.ndarray, step: float) -> DelayEstimate:
    """The grid's best lag refined by a parabola through the best three points."""
    k = int(np.argmin(costs))
    at_bound = k in (0, grid.size - 1)
    delay = float(grid[k])
    if not at_bound:
        c0, c1, c2 = costs[k - 1:k + 2]
        curvature = c0 - 2 * c1 + c2
        if curvature > 0:
            delay += float(np.clip(0.5 * (c0 - c2) / curvature, -1, 1) * step)
    return DelayEstimate(delay, grid, costs, at_bound)
