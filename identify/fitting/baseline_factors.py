"""The plain OLS baseline fitted (:mod:`identify.fitting.baseline` defines it): the rows of every window
compressed into per-(time block, joint) triangular factors, then solved.

The rows of joint j, ``[W_j | y_j]`` (W the baseline's regressor, y the measured torque plus the known
spring torque), are folded chunk by chunk into triangular factors (``RᵀR`` is their Gram matrix, so lstsq
on the stacked factors with the same rcond solves the same problem as on W): one per joint, or one per
(time block, joint) when a blocked cross-validation's time blocks are given, with the factors of the
samples it scores, ``[W_j | y_j | tau_j]``, beside them. Those factors are all the yardsticks need: the plain
OLS (every block stacked), the model the user had (:mod:`identify.fitting.user_model`: the same factors with
the rigid-body columns fixed) and both yardsticks' held-out errors per block
(:mod:`identify.fitting.yardsticks`), from one pass over the data.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Iterable, Sequence

import numpy as np

import rx90sym

from identify.estimation.incremental_qr import JointFactors
from identify.fitting.baseline import (BASELINE_RCOND, BASELINE_TRIM_S, CHUNK, BaselineSegment, PlainBaseline,
                                       baseline_names, baseline_regressor, memory_windows, window_signals)
from identify.selection.folds import time_folds
from identify.signal.blocks import Window

__all__ = ["BaselineFactors", "TimeBlocks", "baseline_factors", "fit_baseline", "fit_baseline_windows",
           "plain_solution", "window_factors"]


def fit_baseline(robot: rx90sym.Robot, recordings: Sequence[Any], spring: bool = True,
                 block: int | None = None) -> PlainBaseline:
    """The plain OLS baseline (module docstring) on every segment of ``recordings`` (held in memory), each
    filtered in blocks of at most ``block`` samples (None: whole; the result is the same to ~1e-12)."""
    return fit_baseline_windows(robot, memory_windows(recordings, block), spring)


@dataclass(frozen=True)
class TimeBlocks:
    """The time blocks of a blocked cross-validation (:class:`identify.selection.raw_torque_scores.RawSpan`'s
    ``start`` [s], ``span`` [s], ``blocks``: :func:`identify.selection.folds.time_folds`) and, for one
    segment, the times [s] between which its samples are scored (None: none of them)."""

    start: float
    span: float
    blocks: int
    bounds: tuple[float, float] | None = None


def window_factors(robot: rx90sym.Robot, segment: BaselineSegment, window: Window, rec: Any, spring: bool = True,
                   blocks: TimeBlocks | None = None) -> tuple[list, list, int]:
    """(fitted, scored, samples fitted) of the core of ``window`` of ``segment`` (a Dask task when the
    blocks are spread): per (time block, joint) present the triangular factor of the fitted samples'
    ``[W_j | y_j]`` (y = torque + spring), and of the scored samples' ``[W_j | y_j | tau_j]`` (those within
    ``blocks.bounds``; none without ``blocks``), as ``(block, joint, factor, rows)``; the rows compressed
    chunk by chunk. A sample falls in the block of its time (clipped to the first and last block)."""
    n = robot.n
    s = window_signals(robot, segment, window, rec, spring)
    kept = np.flatnonzero(s.kept)
    if blocks is None:
        ids, scored = np.zeros(s.t.size, dtype=int), np.zeros(s.t.size, dtype=bool)
    else:
        ids = np.clip(time_folds(s.t, blocks.start, blocks.span, blocks.blocks), 0, blocks.blocks - 1)
        lo, hi = blocks.bounds if blocks.bounds is not None else (np.inf, -np.inf)
        scored = s.kept & (s.t >= lo) & (s.t <= hi)
    fitted: dict = {}
    held: dict = {}
    for start in range(0, kept.size, CHUNK):
        idx = kept[start:start + CHUNK]
        Phi = baseline_regressor(robot, s.q[idx], s.dq[idx], s.ddq[idx])
        y, tau = s.tau[idx] + s.spring[idx], s.tau[idx]
        for b in np.unique(ids[idx]):
            here, score = ids[idx] == b, (ids[idx] == b) & scored[idx]
            for j in range(n):
                _fold(fitted, (int(b), j), np.column_stack([Phi[here, j, :], y[here, j]]))
                if score.any():
                    _fold(held, (int(b), j), np.column_stack([Phi[score, j, :], y[score, j], tau[score, j]]))
    return ([(b, j, R, k) for (b, j), (R, k) in fitted.items()], [(b, j, R, k) for (b, j), (R, k) in held.items()],
            int(kept.size))


def _fold(factors: dict, key: tuple[int, int], rows: np.ndarray) -> None:
    """Fold ``rows`` into ``factors[key]`` = (triangular factor, rows so far)."""
    R = JointFactors.block_factor(rows)
    if key in factors:
        before, count = factors[key]
        factors[key] = (JointFactors.block_factor(np.vstack([before, R])), count + rows.shape[0])
    else:
        factors[key] = (R, rows.shape[0])


class BaselineFactors:
    """The baseline's rows of every window folded per (time block, joint) (one block without a
    cross-validation's blocks): ``fitted[b]`` the factors of ``[W_j | y_j]``, ``scored[b]`` those of
    ``[W_j | y_j | tau_j]`` of the samples scored (None without blocks); ``samples`` fitted. Memory:
    blocks x joints x (13 n + 2)² doubles, twice, whatever the logs' length."""

    def __init__(self, n: int, c: int, blocks: int = 1, scored: bool = False) -> None:
        self.n, self.c, self.blocks = n, c, blocks
        self.fitted = [JointFactors(n, c) for _ in range(blocks)]
        self.scored = [JointFactors(n, c, 2) for _ in range(blocks)] if scored else None
        self.samples = 0

    def add(self, fitted: list, scored: list, samples: int) -> None:
        """Fold in one window's :func:`window_factors`."""
        for b, j, R, k in fitted:
            self.fitted[b].add_factor(j, R, k)
        for b, j, R, k in scored:
            self.scored[b].add_factor(j, R, k)
        self.samples += samples

    def stacked(self, joints: Sequence[int] | None = None, without: int | None = None) -> np.ndarray:
        """The factors of ``joints`` (None: every joint) over every block but ``without``, stacked: the same
        Gram matrix, hence the same least squares, as the samples' rows [W | y]."""
        joints = range(self.n) if joints is None else joints
        parts = [f.R[j] for b, f in enumerate(self.fitted) if b != without for j in joints if f.rows[j]]
        return np.vstack(parts) if parts else np.zeros((0, self.c + 1))

    def plain(self, names: tuple[str, ...], spring: bool) -> PlainBaseline:
        """The plain OLS baseline of every fitted sample (lstsq on the stacked factors, rcond 1e-10)."""
        if self.samples == 0:
            raise ValueError(f"the plain baseline has no sample to fit (every segment shorter than "
                             f"{2 * BASELINE_TRIM_S:g} s)")
        values, rank = plain_solution(self.stacked(), self.c)
        return PlainBaseline(names, values, self.samples, rank, bool(spring), self.residual_rms(values))

    def residual_rms(self, values: np.ndarray) -> np.ndarray:
        """(n,) RMS [N m] of y_j - W_j values on the fitted samples."""
        x = np.r_[values, -1.0]
        return np.array([np.sqrt(sum(np.sum((f.R[j] @ x) ** 2) for f in self.fitted) / self.samples)
                         for j in range(self.n)])


def plain_solution(stacked: np.ndarray, c: int) -> tuple[np.ndarray, int]:
    """(values, rank) of ``numpy.linalg.lstsq(W, y, rcond=1e-10)`` from stacked factors of [W | y]."""
    values, _, rank, _ = np.linalg.lstsq(stacked[:, :c], stacked[:, c], rcond=BASELINE_RCOND)
    return values, int(rank)


def baseline_factors(robot: rx90sym.Robot, windows: Iterable[tuple], spring: bool = True,
                     run: Callable[..., Iterable[tuple]] | None = None, blocks: Any = None) -> BaselineFactors:
    """The :class:`BaselineFactors` of the cores of ``windows`` ((segment, window, raw samples)). blocks: a
    cross-validation's time blocks (an :class:`identify.selection.raw_torque_scores.RawSpan`: its ``start``, ``span``,
    ``blocks`` and, per segment ``key``, the times scored; None: one block, nothing scored). run: how the
    windows' :func:`window_factors` run (``run(task, arguments)`` yielding the results in order, e.g.
    identify.observation.block_rows.in_order on Dask; None: here)."""
    c = len(baseline_names(robot))
    out = BaselineFactors(robot.n, c, 1 if blocks is None else int(blocks.blocks), blocks is not None)

    def spec(segment: BaselineSegment) -> TimeBlocks | None:
        return None if blocks is None else TimeBlocks(float(blocks.start), float(blocks.span), int(blocks.blocks),
                                                      blocks.bounds.get(segment.key))

    tasks = ((robot, segment, window, rec, spring, spec(segment)) for segment, window, rec in windows)
    for parts in (window_factors(*a) for a in tasks) if run is None else run(window_factors, tasks):
        out.add(*parts)
    return out


def fit_baseline_windows(robot: rx90sym.Robot, windows: Iterable[tuple], spring: bool = True,
                         run: Callable[..., Iterable[tuple]] | None = None) -> PlainBaseline:
    """The plain OLS baseline on the cores of ``windows`` ((segment, window, raw samples):
    :func:`memory_windows`, or :func:`identify.fitting.baseline_blocks.source_windows` for a long log).
    The rows of each joint are compressed apart ([W_j | y_j] -> R_j, stacked: the same singular values
    as W), which gives each joint's residual on the fitted samples without a second pass. run: as
    :func:`baseline_factors`'."""
    return baseline_factors(robot, windows, spring, run).plain(baseline_names(robot), spring)
