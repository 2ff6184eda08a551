"""One model stepped through windows in MuJoCo: one MjData reused, reset at each window's start; the
recorded torque held over each sample as ``qfrc_applied`` (plus the terms applied from the fit)."""
from __future__ import annotations

import math

import numpy as np

from identify.rollout.defaults import MAX_STEP_S
from identify.rollout.model import SimulatorModel, load_mujoco

__all__ = ["Simulator", "substeps"]


def substeps(period: float, max_step: float = MAX_STEP_S) -> int:
    """Equal MuJoCo steps per sample of ``period`` [s]: the fewest no longer than ``max_step`` [s]."""
    return max(1, math.ceil(period / max_step - 1e-9))


class Simulator:
    """Windows of one :class:`SimulatorModel` (its MjModel's timestep set per sampling period)."""

    def __init__(self, model: SimulatorModel) -> None:
        self.mujoco = load_mujoco()
        self.sm = model
        self.data = self.mujoco.MjData(model.model)
        self.period = float("nan")
        self.substeps = 1

    def set_period(self, period: float) -> None:
        """Step the recording's sampling period [s] in :func:`substeps` equal steps."""
        if period != self.period:
            self.period, self.substeps = period, substeps(period, min(MAX_STEP_S, self.sm.max_step))
            self.sm.model.opt.timestep = period / self.substeps

    def run(self, q0: np.ndarray, v0: np.ndarray, tau: np.ndarray, keep: bool = False
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, bool]:
        """From q0 [rad, controller angles], v0 [rad/s] under tau (N, n) [N m], sample k's torque held
        over its period: (q, q̇ at the end, the positions at every sample (N+1, n) when ``keep``,
        whether MuJoCo reset an unstable simulation on the way)."""
        mj, m, d = self.mujoco, self.sm.model, self.data
        mj.mj_resetData(m, d)
        d.qpos[:], d.qvel[:] = q0, v0
        path = np.empty((tau.shape[0] + 1, q0.size)) if keep else None
        if keep:
            path[0] = q0
        extra = self.sm.add_extra_force if self.sm.applies_forces else None
        applied, step = d.qfrc_applied, mj.mj_step
        for k in range(tau.shape[0]):
            if extra is not None:
                for _ in range(self.substeps):
                    applied[:] = tau[k]
                    extra(d.qpos, d.qvel, applied)
                    step(m, d)
            else:
                applied[:] = tau[k]
                step(m, d, self.substeps)
            if keep:
                path[k + 1] = d.qpos
        unstable = d.warning[mj.mjtWarning.mjWARN_BADQACC].number > 0
        return d.qpos.copy(), d.qvel.copy(), path, bool(unstable)
