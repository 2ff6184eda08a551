"""Observation matrix of the identification model (eqs. 6-8) from one or many recordings.

Per recording: q filtered and differentiated (eq. 20), the regressor evaluated on every kept
sample, Y = measured torque + spring torque (axis 2, section II-C), then Y and every column of W
decimated by the same zero-phase filter (parallel filtering), and rows grouped per joint (eq. 7).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

import rx90sym

from .filtering import decimate, decimation_factor, derivatives


@dataclass(frozen=True, eq=False)
class Observation:
    """Y = W x + rho (eq. 6), rows grouped per joint (eq. 7).

    W: (r, c) observation matrix for the parameters ``names``; Y: (r,) torques [N m] with the
    spring added; joint: (r,) joint index (0-based) of each row; samples: (r,) index of each row's
    sample in the concatenated, decimated motion; qd: (S, n) joint velocities of those samples;
    cutoffs: per recording cut-off [Hz]; rate: rate after decimation [Hz]; sources: recordings.
    """

    W: np.ndarray
    Y: np.ndarray
    joint: np.ndarray
    names: tuple[str, ...]
    samples: np.ndarray
    cutoffs: tuple[float, ...]
    rates: tuple[float, ...]
    rate: float
    sources: tuple[str, ...]
    n_samples: int

    @property
    def rows(self) -> int:
        return self.W.shape[0]

    def summary(self) -> str:
        """One line per recording: rows, rates, cut-off (what a user checks first)."""
        head = (f"{self.rows} equations, {len(self.names)} parameters, {self.n_samples} samples "
                f"after decimation to {self.rate:g} Hz")
        lines = [head] + [f"  {s}: rate {r:g} Hz, cut-off {c:.3g} Hz"
                          for s, r, c in zip(self.sources, self.rates, self.cutoffs)]
        return "\n".join(lines)


@dataclass(frozen=True, eq=False)
class FilteredMotion:
    """Samples of one recording after derivation and parallel filtering (time on axis 0)."""

    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    Y: np.ndarray        # measured torque + spring, (S, n)
    Phi: np.ndarray      # standard regressor, (S, n, n_params), filtered like Y
    cutoff: float
    rate: float
    source: str


def filtered_motion(robot: Any, rec: Any, cutoff: float | None = None,
                    decimate_to: float | None = None, spring: bool = True,
                    regressor_batch: Callable[..., np.ndarray] | None = None) -> FilteredMotion:
    """Derivatives, regressor and torques of one recording, decimated together.

    regressor_batch: (Q, QD, QDD) -> (S, n, c) giving the columns wanted (default: all the
    standard columns, robot.regressor_batch); selecting before filtering saves the work of
    filtering columns nobody uses."""
    if rec.q.shape[1] != robot.n:
        raise ValueError(f"{rec.source}: recording has {rec.q.shape[1]} joints, robot "
                         f"{robot.name!r} has {robot.n}")
    if rec.robot and rec.robot != robot.name:
        raise ValueError(f"{rec.source}: recording is of robot {rec.robot!r}, not {robot.name!r}")
    d = derivatives(rec.t, rec.q, cutoff=cutoff)
    tau = np.asarray(rec.tau)[d.kept]
    Y = tau + (robot.spring_torque_batch(d.q)[:, :, 0] if spring else 0.0)
    Phi = (regressor_batch or robot.regressor_batch)(d.q, d.dq, d.ddq)
    rate = d.rate
    q, dq, ddq = d.q, d.dq, d.ddq
    if decimate_to is not None:
        k = decimation_factor(d.rate, decimate_to)
        if k > 1:
            # Parallel filtering: the same zero-phase filter on Y and on every column of W.
            Y, Phi = decimate(Y, k), decimate(Phi, k)
            q, dq, ddq = q[::k], dq[::k], ddq[::k]
            rate = d.rate / k
    return FilteredMotion(q, dq, ddq, Y, Phi, d.cutoff, rate, rec.source)


def stack_rows(blocks: Sequence[np.ndarray], Ys: Sequence[np.ndarray], min_velocity: float | None = None,
               dqs: Sequence[np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Rows grouped per joint (eqs. 7-8): W = [W_1; ...; W_n], each W_i the joint-i rows of every
    sample of every motion. blocks: per motion (S, n, c); Ys: per motion (S, n).

    min_velocity [rad/s]: drop joint i's rows where |qd_i| is below it (friction sign unknown).
    """
    Phi = np.concatenate(blocks, axis=0)
    Y = np.concatenate(Ys, axis=0)
    S, n, c = Phi.shape
    keep = np.ones((S, n), dtype=bool)
    if min_velocity is not None:
        keep = np.abs(np.concatenate(dqs, axis=0)) >= min_velocity
    W_rows, Y_rows, joints, samples = [], [], [], []
    for i in range(n):
        idx = np.flatnonzero(keep[:, i])
        W_rows.append(Phi[idx, i, :])
        Y_rows.append(Y[idx, i])
        joints.append(np.full(idx.size, i))
        samples.append(idx)
    return (np.concatenate(W_rows), np.concatenate(Y_rows), np.concatenate(joints),
            np.concatenate(samples))


def observation_matrix(robot: Any, recordings: Sequence[Any], cutoff: float | None = None,
                       decimate_to: float | None = 50.0, base: Any = None,
                       columns: Sequence[str] | None = None, spring: bool = True,
                       min_velocity: float | None = None) -> Observation:
    """Observation matrix W and torque vector Y (eqs. 6-8) from one or many recordings.

    cutoff [Hz]: Butterworth cut-off for q (None: chosen from each recording, reported);
    decimate_to [Hz]: rate after parallel filtering (None: no decimation);
    base: BaseParameters giving the columns (default: symbolic base parameters of ``robot``);
    columns: standard parameter names instead of the base parameters (e.g. a payload's);
    spring: add the spring torque to the measured torque (Y2 = Gamma_motor2 + Gamma_s);
    min_velocity [rad/s]: drop each joint's rows where that joint is nearly at rest.
    """
    if isinstance(recordings, (str, bytes)) or not isinstance(recordings, Sequence):
        recordings = [recordings]
    if not recordings:
        raise ValueError("observation_matrix: no recordings given")
    if columns is not None:
        idx = robot.parameter_index(columns)
        names = tuple(columns)

        def regressor(Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray) -> np.ndarray:
            return robot.regressor_batch(Q, QD, QDD)[:, :, idx]
    else:
        base = base if base is not None else rx90sym.base_parameters(robot)
        names = tuple(base.names)
        regressor = base.regressor_batch
    motions = [filtered_motion(robot, rec, cutoff, decimate_to, spring, regressor) for rec in recordings]
    W, Y, joint, samples = stack_rows([m.Phi for m in motions], [m.Y for m in motions],
                                      min_velocity, [m.dq for m in motions])
    rates = tuple(m.rate for m in motions)
    if len(set(rates)) > 1:
        raise ValueError(f"recordings have different rates after decimation: {rates}; "
                         f"give decimate_to")
    return Observation(W, Y, joint, names, samples, tuple(m.cutoff for m in motions), rates,
                       rates[0], tuple(m.source for m in motions), sum(len(m.Y) for m in motions))
