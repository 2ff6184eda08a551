"""The recorded-torque checks of a fit (scale against the torque limits, gravity at rest), block by block.

:func:`identify.fitting.plausibility.torque_scale_flags` needs each joint's torque peak and
:func:`identify.fitting.plausibility.static_gravity_flags` the rest samples' sums Σ τ·g and Σ g² per
joint (g: the nominal parameters' gravity torque): both are sums over samples, so a log read block by
block gives the figures of the same log held whole (the velocity that says "at rest", the recorded one
or ``numpy.gradient`` of q, from windows one sample wider on each side, as on the whole log):
:class:`GravityAtRest` holds the sums for both (a recording in memory is one block), and
:func:`identify.fit` flags alike on whole recordings and in blocks.
"""
from __future__ import annotations

from typing import Any, Iterator, Sequence

import numpy as np

import rx90sym

from identify.fitting.plausibility import (GRAVITY_RATIO, GRAVITY_SHARE, REST_SAMPLES, REST_SPEED, Flag,
                                           static_gravity_flags, torque_scale_flags)

__all__ = ["CODES", "GravityAtRest", "recorded_torque_flags", "streamed_torque_flags"]

#: The codes of the recorded-torque checks (errors: ``rx90 identify`` exits 2 on them, nothing written).
CODES = ("torque_scale", "static_gravity")


class GravityAtRest:
    """Sums over the samples at rest (every joint slower than REST_SPEED) of the torque times the nominal
    gravity torque and of its square, per joint; fed block by block."""

    def __init__(self, robot: rx90sym.Robot, nominal: dict) -> None:
        self.robot = robot
        self.chi = robot.parameter_vector({k: v for k, v in nominal.items() if k in robot.parameter_names
                                           and not k.startswith(("FS", "FV", "OFF"))}, strict=False)
        self.count = 0
        self.tau_g = np.zeros(robot.n)
        self.g_g = np.zeros(robot.n)

    def add(self, q: np.ndarray, tau: np.ndarray, dq: np.ndarray) -> None:
        """Samples (S, n): positions [rad], torques [N m], velocities [rad/s]."""
        rest = np.all(np.abs(dq) < REST_SPEED, axis=1)
        if not rest.any():
            return
        Q = np.asarray(q)[rest]
        Z = np.zeros_like(Q)
        g = self.robot.regressor_batch(Q, Z, Z) @ self.chi
        if self.robot.spring is not None:  # the motor holds gravity minus the spring (Y = tau + spring, eq. 7)
            g = g - self.robot.spring_torque_batch(Q)[:, :, 0]
        self.count += Q.shape[0]
        self.tau_g += np.einsum("sj,sj->j", np.asarray(tau)[rest], g)
        self.g_g += np.einsum("sj,sj->j", g, g)

    def flags(self) -> list[Flag]:
        """static_gravity errors: on each joint whose nominal gravity RMS is at least GRAVITY_SHARE of its
        limit, the least-squares scale of measured on nominal outside [1/GRAVITY_RATIO, GRAVITY_RATIO]."""
        if self.count < REST_SAMPLES:
            return []
        robot = self.robot
        judged = np.sqrt(self.g_g / self.count) >= GRAVITY_SHARE * np.asarray(robot.limits.tau_max, dtype=float)
        flags = []
        for j in np.flatnonzero(judged):
            s = float(self.tau_g[j] / self.g_g[j])
            if not 1 / GRAVITY_RATIO <= s <= GRAVITY_RATIO:
                cause = "the torque sign" if s < 0 else "the robot, the units or the gains"
                flags.append(Flag("static_gravity", "error", f"at rest, joint {j + 1}'s torque is {s:.3g} x the "
                                  f"gravity of robot {robot.name}'s nominal parameters ({self.count} samples at rest; "
                                  f"expected {1 / GRAVITY_RATIO:.2g}..{GRAVITY_RATIO:g})", f"check {cause}",
                                  joint=int(j) + 1))
        return flags


def _checked(robot: rx90sym.Robot, blocks: Iterator[tuple], nominal: dict | None) -> list[Flag]:
    """Both checks on ``blocks`` ((q, tau, dq) of consecutive samples, every recording's in turn)."""
    peak = None
    gravity = GravityAtRest(robot, nominal) if nominal else None
    for q, tau, dq in blocks:
        top = np.max(np.abs(np.asarray(tau, dtype=float)), axis=0) if len(tau) else None
        peak = top if peak is None else peak if top is None else np.maximum(peak, top)
        if gravity is not None and dq is not None:
            gravity.add(q, tau, dq)
    scale = torque_scale_flags([] if peak is None else [peak[None, :]], robot)
    return scale + (gravity.flags() if gravity is not None else [])


def recorded_torque_flags(robot: rx90sym.Robot, recordings: Sequence[Any],
                          nominal: dict | None | str = "robot") -> list[Flag]:
    """torque_scale and static_gravity errors of recordings held in memory (each one block); nominal: the
    parameters of the gravity check ("robot": the robot's nominal parameters; None: no gravity check)."""
    nominal = rx90sym.nominal_parameters(robot) if isinstance(nominal, str) else nominal
    return (torque_scale_flags([r.tau for r in recordings if r.tau is not None], robot)
            + static_gravity_flags(recordings, robot, nominal))


def _source_blocks(sources: Sequence[Any], scans: Sequence[Any], block: int) -> Iterator[tuple]:
    """(q, tau, dq) of consecutive blocks of ``block`` samples of every source, the velocity of each from a
    window one sample wider on each side (the whole recording's ``numpy.gradient`` at its cores)."""
    for src, scan in zip(sources, scans):
        n = int(scan.samples)
        starts = range(0, n, int(block))
        spans = [(max(0, a - 1), min(n, a + int(block) + 1)) for a in starts]
        for a, (r0, r1), rec in zip(starts, spans, src.windows(spans)):
            if rec.tau is None:
                break
            core = slice(a - r0, min(n, a + int(block)) - r0)
            dq = rec.dq if rec.dq is not None else np.gradient(np.asarray(rec.q), np.asarray(rec.t), axis=0)
            yield rec.q[core], rec.tau[core], dq[core] if n >= 3 else None


def streamed_torque_flags(robot: rx90sym.Robot, sources: Sequence[Any], scans: Sequence[Any], block: int,
                          nominal: dict | None | str = "robot") -> list[Flag]:
    """:func:`recorded_torque_flags` of logs read block by block (``scans``: their first pass, for their
    lengths); the same flags and figures as the logs held whole."""
    nominal = rx90sym.nominal_parameters(robot) if isinstance(nominal, str) else nominal
    return _checked(robot, _source_blocks(sources, scans, block), nominal)
