"""The least-squares systems of payload methods 1, 3 and 4 (eqs. 22, 28, 29), block by block.

The runs go through the section-IV pipeline (:mod:`identify.fitting.run_blocks`: the rows of one
processing, as :func:`identify.fit` makes them); each block's rows, grouped per joint (eq. 7), are
folded into per-joint triangular factors (:class:`identify.estimation.incremental_qr.JointFactors`,
eqs. 9-15 follow from them as from the whole W) and into the segment bootstrap
(:class:`identify.estimation.bootstrap.SegmentBootstrap`): memory bounded by the block, whatever the
runs' length and number of segments.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

import rx90sym

from identify.estimation.bootstrap import BLOCK_S, DRAWS, SegmentBootstrap
from identify.estimation.incremental_qr import JointFactors
from identify.estimation.least_squares import solve_joint_systems
from identify.estimation.results import IdentificationResult
from identify.fitting.run_blocks import RunBlock, RunColumns, Runs, run_blocks
from identify.observation.processing import drops_rest

__all__ = ["FoldedRows", "drop_rest", "fold_rows", "method_1_rows", "method_3_rows", "method_4_rows"]

#: Per joint, the rows of one block: (their sample indices in the block, W_i, Y_i).
JointRows = list[tuple[np.ndarray, np.ndarray, np.ndarray]]


def _per_joint(W: np.ndarray, Y: np.ndarray, keep: np.ndarray) -> JointRows:
    """The kept rows of each joint: W (S, n, c), Y (S, n), keep (S, n)."""
    out = []
    for j in range(Y.shape[1]):
        idx = np.flatnonzero(keep[:, j])
        out.append((idx, W[idx, j, :], Y[idx, j]))
    return out


def method_1_rows(beta: np.ndarray, drop: bool) -> Callable[[RunBlock], JointRows]:
    """Eq. 22: the robot's known part W β (its first ``beta.size`` columns) moved to the right-hand side."""
    nb = beta.size

    def rows(b: RunBlock) -> JointRows:
        m = b.motion
        return _per_joint(m.Phi[:, :, nb:], m.Y - m.Phi[:, :, :nb] @ beta, m.rows(drop))
    return rows


def method_3_rows(drop: bool) -> Callable[[RunBlock], JointRows]:
    """Eq. 28: the loaded run's payload columns; the empty run's torques replace W χ (the rows where the
    loaded run moves and both were measured)."""
    def rows(b: RunBlock) -> JointRows:
        m, e = b.motion, b.empty
        return _per_joint(m.Phi, m.Y - e.Y, m.rows(drop) & e.rows(False))
    return rows


def method_4_rows(drop: bool) -> Callable[[RunBlock], JointRows]:
    """Eq. 29: [W_v 0; W_T W_c] and [Y_v; Y_T] (an empty run's payload columns are 0)."""
    def rows(b: RunBlock) -> JointRows:
        m = b.motion
        Phi = m.Phi if b.loaded else np.concatenate([m.Phi, np.zeros(m.Phi.shape[:2] + (10,))], axis=2)
        return _per_joint(Phi, m.Y, m.rows(drop))
    return rows


class FoldedRows:
    """Per-joint factors of ``[W_i | Y_i]`` and the segment bootstrap of the rows folded so far."""

    def __init__(self, joints: int, names: tuple[str, ...], samples: int, rate: float, seed: int | None) -> None:
        self.names = names
        self.factors = JointFactors(joints, len(names))
        self.boot = (SegmentBootstrap(samples, max(1, int(round(BLOCK_S * rate))), joints, len(names), DRAWS, seed)
                     if seed is not None else None)

    def add(self, first: int, rows: JointRows) -> None:
        for j, (idx, W, Y) in enumerate(rows):
            if idx.size:
                self.factors.add(j, np.column_stack([W, Y]))
                if self.boot is not None:
                    self.boot.add(j, first + idx, W, Y)

    def solve(self, method: str = "wls") -> IdentificationResult:
        """Eqs. 9-15 on the folded rows (each joint weighted by 1/σ of its own residual)."""
        return solve_joint_systems(self.factors.systems(0), self.names, weighted=method != "ols")

    def bootstrap_std(self, fit: IdentificationResult) -> np.ndarray | None:
        """The segment-bootstrap σ of every column for the fit's joint weights (None: no bootstrap)."""
        return None if self.boot is None else self.boot.std(fit.weights)


def fold_rows(robot: rx90sym.Robot, runs: Runs, columns: dict[str, RunColumns], rows: Callable[[RunBlock], JointRows],
              names: tuple[str, ...], seed: int | None, client: Any = None,
              folded: FoldedRows | None = None) -> FoldedRows:
    """Every block of ``runs`` through ``rows`` (on the Dask workers with ``client``), folded in order
    (into ``folded`` when given: rows added to those of earlier runs)."""
    out = folded if folded is not None else FoldedRows(robot.n, names, runs.samples, runs.rate, seed)
    for first_rows in run_blocks(robot, runs, columns, lambda b: (b.first, rows(b)), client):
        out.add(*first_rows)
    return out


def drop_rest(runs: Runs) -> bool:
    """Whether the runs' rest rows are dropped (a rest threshold and the "drop" policy on some joint)."""
    return runs.processing.min_velocity is not None and drops_rest(runs.processing.rest)
