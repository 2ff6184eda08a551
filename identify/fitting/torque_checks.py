"""The recorded-torque checks of a fit (scale against the torque limits, gravity at rest), block by block.

:func:`identify.fitting.plausibility.torque_scale_flags` needs each joint's torque peak and
:func:`identify.fitting.plausibility.static_gravity_flags` the rest samples' sums Σ τ·g and Σ g² per
joint (g: the nominal parameters' gravity torque): both are sums over samples, so a log read block by
block gives the figures of the same log held whole (the velocity that says "at rest", the recorded one
or ``numpy.gradient`` of q, from windows one sample wider on each side, as on the whole log):
:class:`identify.fitting.plausibility.GravityAtRest` holds the sums for both (a recording in memory is one block), and
:func:`identify.fit` flags alike on whole recordings and in blocks.
"""
from __future__ import annotations

from typing import Any, Iterator, Sequence

import numpy as np

import rx90sym

from identify.fitting.plausibility import GravityAtRest, Flag, static_gravity_flags, torque_scale_flags
from identify.io.unlogged import constant_channels

__all__ = ["CODES", "NOT_LOGGED", "not_logged_flags", "recorded_torque_flags", "streamed_torque_flags"]

#: The codes of the recorded-torque checks (errors: ``rx90 identify`` exits 2 on them, nothing written).
CODES = ("torque_scale", "static_gravity")
#: The code of a joint whose torque is constant over a recording (a channel not logged), left out of the fit.
NOT_LOGGED = "torque_not_logged"


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


def not_logged_flags(scans: Sequence[Any], joints: Sequence[int]) -> list[Flag]:
    """A warning per joint (0-based ``joints``) whose torque is constant over a recording of ``scans``
    (:func:`identify.observation.stream.torque_left_out`: a channel not logged), left out of the fit."""
    out = []
    for j in joints:
        where = [f"{s.source} ({s.tau_range[0, j]:.6g} N·m)" for s in scans
                 if s.tau_range is not None and constant_channels(s.tau_range[0, j:j + 1], s.tau_range[1, j:j + 1])]
        out.append(Flag(NOT_LOGGED, "warning",
                        f"joint {j + 1}'s torque holds one value on every sample of {', '.join(where)}: a channel "
                        f"not logged; joint {j + 1} is left out of the fit (its rows out of W, its torque neither "
                        f"fitted nor scored in the choices, not predicted)",
                        "log the joint's torque (or its current with --gains) to identify it", joint=j + 1))
    return out
