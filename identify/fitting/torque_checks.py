"""The recorded-torque checks of a fit (scale against the torque limits, gravity at rest, sign against the
description's inverse dynamics), block by block.

:func:`identify.fitting.plausibility.torque_scale_flags` needs each joint's torque peak and
:func:`identify.fitting.plausibility.static_gravity_flags` the rest samples' sums Σ τ·g and Σ g² per
joint (g: the nominal parameters' gravity torque): both are sums over samples, so a log read block by
block gives the figures of the same log held whole (the velocity that says "at rest", the recorded one
or ``numpy.gradient`` of q, from windows one sample wider on each side, as on the whole log):
:class:`identify.fitting.plausibility.GravityAtRest` holds the sums for both (a recording in memory is one block), and
:func:`identify.fit` flags alike on whole recordings and in blocks.
"""
from __future__ import annotations

import re
from typing import Any, Iterator, Sequence

import numpy as np

import rx90sym

from identify.fitting.plausibility import GravityAtRest, Flag, static_gravity_flags, torque_scale_flags
from identify.io.unlogged import constant_channels

__all__ = ["CODES", "NOT_LOGGED", "SIGN_CORRELATION", "SIGN_SIGMAS", "not_logged_flags", "recorded_torque_flags",
           "log_torque_flags", "torque_sign_flags"]

#: The codes of the recorded-torque checks (``rx90 identify`` exits 2 on their errors, nothing written, and
#: prints their warnings).
CODES = ("torque_scale", "static_gravity", "torque_sign")
#: A joint is flagged torque_sign when, friction and offset removed, its recorded torques correlate with the
#: description's inverse dynamics below SIGN_CORRELATION (the rigid body explains a quarter of their
#: variance or more, with the other sign) and their least-squares scale on it is below 0 by SIGN_SIGMAS sigma.
#: Measured (twins 8 s, bodies 0.5-1.5 x the description's, 5 seeds): unmodified correlations >= -0.31 (TX40
#: joint 4 of one seed) and >= 0.34 (Panda); the real TX40 record 0.47-0.99.
SIGN_CORRELATION = -0.5
SIGN_SIGMAS = 3.0
#: The code of a joint whose torque is constant over a recording (a channel not logged), left out of the fit.
NOT_LOGGED = "torque_not_logged"
# Columns fitted freely beside the description's torques: friction, offsets (and what the description has
# no value for: a spring's, the cross-validation's extra columns).
_FREE = re.compile(r"^(FV|FS|OFF|FP)")


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


def log_torque_flags(robot: rx90sym.Robot, sources: Sequence[Any], scans: Sequence[Any], block: int,
                          nominal: dict | None | str = "robot") -> list[Flag]:
    """:func:`recorded_torque_flags` of logs read block by block (``scans``: their first pass, for their
    lengths); the same flags and figures as the logs held whole."""
    nominal = rx90sym.nominal_parameters(robot) if isinstance(nominal, str) else nominal
    return _checked(robot, _source_blocks(sources, scans, block), nominal)


def not_logged_flags(scans: Sequence[Any], joints: Sequence[int]) -> list[Flag]:
    """A warning per joint (0-based ``joints``) whose torque is constant over a recording of ``scans``
    (:func:`identify.observation.scan.torque_left_out`: a channel not logged), left out of the fit."""
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


def _description_columns(base: Any, names: Sequence[str], chi: np.ndarray) -> tuple[np.ndarray, list[int]] | None:
    """(the fit's columns' values for the description's standard parameters ``chi``, friction and extra
    columns 0; the indices of those free columns), or None when the columns have no map from standard
    parameters (columns given by hand)."""
    inner = base
    while not hasattr(inner, "K") and hasattr(inner, "base"):
        inner = inner.base
    if not hasattr(inner, "K"):
        return None
    values = dict(zip(inner.names, inner.K @ chi))
    free = [k for k, name in enumerate(names) if name not in values or _FREE.match(name)]
    beta = np.array([0.0 if k in free else float(values[name]) for k, name in enumerate(names)])
    return beta, free


def _sign_figures(system: Any, beta: np.ndarray, free: list[int]) -> tuple[float, float, float] | None:
    """(correlation, scale, its sigma) of a joint's torques on the description's torques ``W beta`` with
    the ``free`` columns fitted beside, from the joint's compressed system (None: no torque to judge)."""
    R, z = system.R, system.z
    tau0 = R @ beta
    F = R[:, free]
    if not np.any(tau0) or system.rows <= len(free) + 2:
        return None

    def residual(v: np.ndarray) -> np.ndarray:  # v with the free columns' span removed (compressed rows)
        return v - F @ np.linalg.lstsq(F, v, rcond=1e-10)[0] if free else v

    t_perp, y_perp = residual(tau0), residual(z)
    tt = float(t_perp @ t_perp)
    yy = float(y_perp @ y_perp) + system.rss_outside
    if not (tt > 0 and yy > 0):
        return None
    scale = float(t_perp @ y_perp) / tt
    rss = max(yy - scale * scale * tt, 0.0)
    dof = system.rows - 1 - np.linalg.matrix_rank(F) if free else system.rows - 1
    sigma = float(np.sqrt(rss / max(dof, 1) / tt))
    return scale * np.sqrt(tt / yy), scale, sigma


def torque_sign_flags(robot: rx90sym.Robot, result: Any, base: Any, nominal: dict | None | str = "robot",
                      spring_added: bool = False) -> list[Flag]:
    """torque_sign: joints whose recorded torques have the opposite sign of the description's inverse dynamics.

    On the fit's own rows (``result.joint_systems``: each joint's compressed [W | y], the rows the fit kept),
    per joint: the description's torques tau0 = W beta0 (beta0: the fit's columns for the description's
    standard parameters ``nominal``, friction and offsets left free and fitted beside), the correlation of the
    recorded torques with tau0 and their scale on it, friction and offsets removed. The joints with a
    correlation below SIGN_CORRELATION and a scale + SIGN_SIGMAS sigma < 0 are named, with the signs that
    fix the log (rx90 convert --torque-signs); when they are every joint the description determines
    (|correlation| >= -SIGN_CORRELATION; at least two), the fix negates the joints it leaves weakly
    determined too (one convention for the whole log: a wrist whose rigid-body part is small), saying so.
    A joint alone whose description disagrees in sign (a weak correlation) is not named. One warning; none without a
    description (``nominal`` None) or columns with no map from standard parameters. nominal: "robot" for
    rx90sym.nominal_parameters(robot) (the description's prior). spring_added: the rows hold the recorded
    torque plus the robot's spring (Processing.spring): the spring's joint is not judged (a negated torque
    plus the spring is no negated torque)."""
    nominal = rx90sym.nominal_parameters(robot) if isinstance(nominal, str) else nominal
    systems = getattr(result, "joint_systems", ())
    if not nominal or not systems:
        return []
    chi = robot.parameter_vector({k: v for k, v in nominal.items() if k in robot.parameter_names}, strict=False)
    found = _description_columns(base, result.names, chi)
    if found is None:
        return []
    beta, free = found
    spring = {robot.spring.joint} if spring_added and robot.spring is not None else set()
    figures = {j: None if j in spring else _sign_figures(system, beta, free) for j, system in enumerate(systems)}
    negative = [j for j, f in figures.items()
                if f is not None and f[0] < SIGN_CORRELATION and f[1] + SIGN_SIGMAS * f[2] < 0]
    if not negative:
        return []
    from identify.io.torque_signs import signs_text

    strong = {j for j, f in figures.items() if f is not None and abs(f[0]) >= -SIGN_CORRELATION}
    weak = sorted(set(range(len(systems))) - strong - set(negative))
    whole = len(strong) >= 2 and strong <= set(negative) and bool(weak)  # one convention for the whole log
    signs = [-1.0 if j in negative or (whole and j in weak) else 1.0 for j in range(robot.n)]
    which = ", ".join(f"joint {j + 1} (correlation {figures[j][0]:.3f}, scale {figures[j][1]:.3g} ± "
                      f"{figures[j][2]:.2g} over {systems[j].rows} rows)" for j in negative)
    scope = ("every joint" if len(negative) == robot.n else f"joint {negative[0] + 1}" if len(negative) == 1 else
             "joints " + ", ".join(str(j + 1) for j in negative))

    def why(j: int) -> str:
        return "the spring's, not judged" if j in spring else (
            "no description torque" if figures[j] is None else f"correlation {figures[j][0]:.2f}")

    rest = (f"; every joint the description determines has the other sign: joint(s) "
            f"{', '.join(f'{j + 1} ({why(j)})' for j in weak)} negated with them" if whole else "")
    return [Flag("torque_sign", "warning",
                 f"the recorded torques have the opposite sign of the description's inverse dynamics (friction and "
                 f"offsets removed) on {scope}: {which}{rest}",
                 f"if the log counts torques the other way, convert it with torque signs {signs_text(signs)} "
                 f"(rx90 convert --torque-signs {signs_text(signs)}; identify.read_log(..., torque_signs=)); "
                 f"otherwise the description does not fit the robot (joint axes, centres of mass); a physically "
                 f"consistent fit corrects neither", joint=negative[0] + 1)]
