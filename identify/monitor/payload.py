"""Payload monitoring (the paper's conclusion): method 4 updated after every loaded motion."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

import rx90sym
from rx90sym.parameters import PAYLOAD_NAMES

from identify.estimation.least_squares import solve_joint_systems, solve_system, stack_systems
from identify.fitting.run_blocks import RunColumns, open_runs
from identify.payloads.methods import (PayloadResult, check_wrist_motion, estimates_in_tip_frame, payload_estimates,
                                       processing_of, read_block, recording_list, result_subset)
from identify.payloads.systems import FoldedRows, drop_rest, fold_rows, method_4_rows

__all__ = ["MonitorStep", "PayloadMonitor"]


@dataclass(frozen=True)
class MonitorStep:
    """One update: the loaded motion added and the payload estimate after it."""

    source: str
    values: np.ndarray
    std: np.ndarray
    robot_values: np.ndarray


class PayloadMonitor:
    """Payload (and robot) estimate updated after every loaded motion (method 4, recursively).

    The empty motions fix the joint weights, the cut-off (chosen on them unless given) and the first
    block of eq. 29; each update folds the loaded motion's rows, block by block, into the per-joint
    triangular factors (constant size: the cost of an update does not grow with the history) and
    re-solves. ``history`` holds every estimate. options: the processing of :func:`identify.payload`;
    convention, gains, block: how files are read.
    """

    def __init__(self, robot: rx90sym.Robot, empty: Sequence[Any], base: Any = None, *, convention: str | None = None,
                 gains: Any = None, block: int | None = None, **options: Any) -> None:
        empty = recording_list(empty)
        if not empty:
            raise ValueError("PayloadMonitor needs at least one empty recording")
        self.robot = robot
        self.base = base if base is not None else rx90sym.base_parameters(robot)
        self.read = dict(convention=convention, gains=gains)
        self.names = tuple(self.base.names) + PAYLOAD_NAMES
        self.block = read_block(block)
        runs = open_runs(robot, empty, [], processing_of(options), self.block, **self.read)
        self.processing = runs.processing  # its cut-off chosen: every loaded motion filtered alike
        self._folded = fold_rows(robot, runs, {"empty": RunColumns(robot, self.base, payload=False)}, method_4_rows(drop_rest(runs)),
                                 self.names, None, folded=FoldedRows(robot.n, self.names, 0, 1.0, None))
        nb = self.base.nb
        self.empty_fit = solve_joint_systems(self._folded.factors.subset(range(nb)).systems(0), self.base.names)
        self.weights = self.empty_fit.weights
        self.history: list[MonitorStep] = []

    def update(self, loaded: Any) -> PayloadResult:
        """Add one loaded motion (a recording or a file) and return the new payload estimate."""
        runs = open_runs(self.robot, [], [loaded], self.processing, self.block, **self.read)
        check_wrist_motion(self.robot, runs.q_range, [s.source for s in runs.loaded_scans])
        fold_rows(self.robot, runs, {"loaded": RunColumns(self.robot, self.base)}, method_4_rows(drop_rest(runs)),
                  self.names, None, folded=self._folded)
        systems = self._folded.factors.systems(0)
        fit = solve_system(stack_systems(systems, self.weights), self.names, joint_systems=systems,
                           weights=self.weights, method="monitor")
        values, std, rel = payload_estimates(fit)
        if self.robot.urdf is not None:
            values, std, rel = estimates_in_tip_frame(self.robot, fit, values, std)
        nb = self.base.nb
        self.history.append(MonitorStep(runs.loaded_scans[0].source, values, std, fit.values[:nb]))
        return PayloadResult(4, PAYLOAD_NAMES, values, std, rel, fit, result_subset(fit, self.base.names))
