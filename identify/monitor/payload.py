"""Payload monitoring (the paper's conclusion): method 4 updated after every loaded motion."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

import rx90sym
from rx90sym.parameters import PAYLOAD_NAMES

from identify.estimation.least_squares import compress, solve_system, stack_systems, weighted_least_squares
from identify.payloads.methods import (PayloadResult, check_joint_count, check_wrist_motion, estimates_in_tip_frame,
                              payload_estimates, payload_motions, payload_rows, recording_list, result_subset)

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

    The empty motions fix the joint weights and the first block of eq. 29; each update adds the
    loaded motion's rows to the QR-compressed system (constant size: the cost of an update does
    not grow with the history) and re-solves. ``history`` holds every estimate.
    """

    def __init__(self, robot: rx90sym.Robot, empty: Sequence[Any], base: Any = None, **options: Any) -> None:
        empty = recording_list(empty)
        if not empty:
            raise ValueError("PayloadMonitor needs at least one empty recording")
        check_joint_count(robot, empty, "empty")
        self.robot = robot
        self.base = base if base is not None else rx90sym.base_parameters(robot)
        self.options = options
        self.names = tuple(self.base.names) + PAYLOAD_NAMES
        cols = list(self.base.independent) + list(rx90sym.payload_regressor_columns(robot))
        self._cols = cols
        nb = self.base.nb
        m_e = payload_motions(robot, empty, cols, options)
        blocks = [np.concatenate([m.Phi[:, :, :nb], np.zeros_like(m.Phi[:, :, nb:])], axis=2) for m in m_e]
        W, Y, joint, _ = payload_rows(blocks, [m.Y for m in m_e], m_e, options)
        empty_fit = weighted_least_squares(W[:, :nb], Y, joint, self.base.names)
        self.weights = empty_fit.weights
        self._systems = [compress(W[joint == j], Y[joint == j]) for j in range(robot.n)]
        self.empty_fit = empty_fit
        self.history: list[MonitorStep] = []

    def update(self, loaded: Any) -> PayloadResult:
        """Add one loaded motion and return the new payload estimate."""
        check_joint_count(self.robot, [loaded], "loaded")
        check_wrist_motion(self.robot, [loaded])
        m = payload_motions(self.robot, [loaded], self._cols, self.options)
        W, Y, joint, _ = payload_rows([x.Phi for x in m], [x.Y for x in m], m, self.options)
        new = [compress(W[joint == j], Y[joint == j]) for j in range(self.robot.n)]
        self._systems = [stack_systems([a, b]) for a, b in zip(self._systems, new)]
        system = stack_systems(self._systems, self.weights)
        fit = solve_system(system, self.names, joint_systems=self._systems, weights=self.weights,
                           method="monitor")
        values, std, rel = payload_estimates(fit)
        if self.robot.urdf is not None:
            values, std, rel = estimates_in_tip_frame(self.robot, fit, values, std)
        nb = self.base.nb
        self.history.append(MonitorStep(loaded.source, values, std, fit.values[:nb]))
        return PayloadResult(4, PAYLOAD_NAMES, values, std, rel, fit, result_subset(fit, self.base.names))
