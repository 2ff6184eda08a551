"""Delay between the positions and the torques (or currents) of a log.

A controller often logs torques a few milliseconds after the positions they belong to; an
uncompensated lag of a few ms biases inertia and friction. The lag is estimated as the shift of
the torques that minimises the residual of a first least-squares fit on the same W (only Y moves):
a coarse grid of whole steps, then a parabola through the best three points (a fraction of a sample).
The shifted torques are extra right-hand sides of the fit's per-joint factors, block by block
(:func:`estimate_delay`, :mod:`identify.fitting.passes`).

A least cost at either end of the grid is no estimate: the lag may lie beyond the bound, or the cost
may have no minimum inside it at all (a coloured residual the shift trades against, with no lag in
the log: on one real run the search ended at -20 ms, on another of the same arm at +20 ms). It is
reported as not found and never applied: the fit keeps the lag given (0 by default) and says why.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

import rx90sym
from rx90sym.threads import one_blas_thread

from identify.estimation.joint_factors import joint_factors, plans_of
from identify.io.blocks import DEFAULT_BLOCK, block_source, check_block
from identify.observation.processing import Processing
from identify.observation.rest import presliding_base
from identify.observation.scan import scan_all, torque_left_out

__all__ = ["DelayEstimate", "delay_grid", "estimate_delay", "joint_log_rms", "lag_estimate", "refined_delay"]


@dataclass(frozen=True, eq=False)
class DelayEstimate:
    """delay [s] (> 0: torques lag the positions; compensated by τ(t + delay); 0 when not found); grid [s]
    and cost (sum over joints of log residual RMS of the fit) of the coarse search; at_bound: the best
    grid point is at ±max_delay, the lag not found (module docstring)."""

    delay: float
    grid: np.ndarray
    cost: np.ndarray
    at_bound: bool

    @property
    def found(self) -> bool:
        """Whether the least cost lies inside the search (else ``delay`` is 0, not an estimate)."""
        return not self.at_bound

    @property
    def best(self) -> float:
        """The grid's lag of least cost [s] (at a bound when not found)."""
        return float(self.grid[int(np.argmin(self.cost))])

    def summary(self) -> str:
        if self.at_bound:
            return (f"torque delay not found: the search's least cost is at its bound ({1e3 * self.best:+.3g} ms of "
                    f"±{1e3 * float(np.max(np.abs(self.grid))):.3g} ms; the lag may lie beyond it, or the residual "
                    f"trades against the shift with no lag inside): not applied (0 ms)")
        return f"torque delay {1e3 * self.delay:.3g} ms"


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
    """The grid's best lag refined by a parabola through the best three points (0, not found, at a bound)."""
    k = int(np.argmin(costs))
    at_bound = k in (0, grid.size - 1)
    delay = 0.0 if at_bound else float(grid[k])
    if not at_bound:
        c0, c1, c2 = costs[k - 1:k + 2]
        curvature = c0 - 2 * c1 + c2
        if curvature > 0:
            delay += float(np.clip(0.5 * (c0 - c2) / curvature, -1, 1) * step)
    return DelayEstimate(delay, grid, costs, at_bound)


def lag_estimate(factors: Any, grid: np.ndarray, step: float) -> DelayEstimate:
    """The lag of least cost on ``grid`` [s] (the torques shifted by each: right-hand sides 1.. of the
    per-joint factors, :class:`~identify.estimation.incremental_qr.JointFactors`), refined by a parabola."""
    return refined_delay(grid, np.array([joint_log_rms(factors.systems(k + 1)) for k in range(len(grid))]), step)


@one_blas_thread()
def estimate_delay(robot: rx90sym.Robot, recordings: Sequence[Any], processing: Processing | None = None,
                   base: Any = None, max_delay: float = 0.02, steps: int = 41, block: int = DEFAULT_BLOCK,
                   client: Any = None, convention: str | None = None, gains: Any = None) -> DelayEstimate:
    """Torque-to-position lag [s] of ``recordings`` (recordings, files or block sources; one lag for all),
    within ±``max_delay`` s, read block by block: the torques shifted by each lag of a grid of ``steps``
    points (at least one sampling period apart) are extra right-hand sides of the per-joint factors, the
    best refined by a parabola (module docstring). processing: the filtering and rest handling of the rows
    (None: the defaults without a rest threshold, every row a moving one; cut-off None: the automatic one;
    its delay is the search's; :func:`identify.fit` gives its own); base: the columns (default: the
    symbolic base parameters); block, client, convention, gains: as :func:`identify.fit`.
    BLAS on one thread inside the call, the caller's count back after it (rx90sym.threads)."""
    if not (max_delay > 0 and np.isfinite(max_delay)):
        raise ValueError(f"max_delay must be a positive duration in s, got {max_delay!r}")
    processing = (processing if processing is not None else Processing(min_velocity=None)).chosen(delay=0.0)
    block = check_block(block)
    sources = [block_source(r, robot, convention, gains) for r in recordings]
    columns = presliding_base(robot, base if base is not None else rx90sym.base_parameters(robot),
                              processing.rest if processing.min_velocity is not None else None)
    scans, processing = scan_all(sources, processing, block)
    left_out = torque_left_out(scans, robot.n)  # a torque not logged: its rows out
    plans, _ = plans_of(scans, processing.chosen(delay=max_delay), block)
    grid, step = delay_grid(max(1.0 / s.rate for s in scans), max_delay, steps)
    factors = joint_factors(robot, sources, plans, processing, columns, grid, left_out, client)[0]
    return lag_estimate(factors, grid, step)
