"""The baseline a user writes in 30 lines: plain least squares with a fixed 10 Hz filter on every
joint (no weighting, no rest handling, no decimation), and its held-out prediction."""
from __future__ import annotations

from typing import Any

import numpy as np

import rx90sym
from identify.signal.filtering import derivatives

#: The fixed cut-off of the baseline, Hz.
PLAIN_CUTOFF = 10.0


def plain_ls(robot: rx90sym.Robot, rec: Any, base: Any, cutoff: float = PLAIN_CUTOFF) -> np.ndarray:
    """beta over ``base.names`` by ordinary least squares on the raw torques, q filtered at ``cutoff``."""
    d = derivatives(rec.t, rec.q, cutoff=cutoff)
    Phi = base.regressor_batch(d.q, d.dq, d.ddq)                       # (S, n, c)
    Y = np.asarray(rec.torques)[d.kept] + robot.spring_torque_batch(d.q)[:, :, 0]
    beta, *_ = np.linalg.lstsq(Phi.reshape(-1, Phi.shape[2]), Y.reshape(-1), rcond=None)
    return beta


def plain_prediction(robot: rx90sym.Robot, beta: np.ndarray, rec: Any, base: Any,
                     cutoff: float = PLAIN_CUTOFF) -> tuple[np.ndarray, slice]:
    """(predicted torques (S, n) without the spring, the samples of ``rec`` they belong to)."""
    d = derivatives(rec.t, rec.q, cutoff=cutoff)
    pred = base.regressor_batch(d.q, d.dq, d.ddq) @ beta - robot.spring_torque_batch(d.q)[:, :, 0]
    return pred, d.kept
