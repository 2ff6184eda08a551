"""Friction at rest from the position history: a presliding state instead of Coulomb = 0.

At rest a joint is held by static friction anywhere in [-FS, FS]; the sign of a noisy speed says
nothing, so the ``zero-coulomb`` policy predicts 0 there. A real joint stopped after a motion keeps
(part of) the friction of that motion: the UR10e's joint 6 shows -2 N·m for seconds. The
``presliding`` policy replaces the Coulomb entry sign(q̇) at rest by a state z in [-1, 1] driven by
the positions only (never by the torque it is judged against): the *play operator*

    z_k = clip(z_{k-1} + (q_k - q_{k-1}) / delta, -1, 1),

a Dahl model with a sharp knee: z follows the direction of the last motion once the joint has
travelled ``delta`` rad in it, holds it at rest, and swings through 0 over ``delta`` rad when the
motion reverses. While moving, z = sign(q̇) after ``delta`` of travel: the moving rows keep the
Coulomb entry unchanged.
"""
from __future__ import annotations

from functools import lru_cache
from typing import Any, Sequence

import numpy as np
from scipy.ndimage import maximum_filter1d, minimum_filter1d

from identify.observation.defaults import DEFAULT_FRICTION, FRICTION_FORMS

__all__ = ["DEFAULT_FRICTION", "FRICTION_FORMS", "PRESLIDING_TRAVEL", "crossing_passes", "defaulted_travels", "friction_columns", "friction_function",
           "presliding_state"]

#: Travel (rad) over which the presliding state goes from one sign to the other (docs/real-logs.md).
PRESLIDING_TRAVEL = 2e-3


def presliding_state(q: np.ndarray, travel: float = PRESLIDING_TRAVEL) -> np.ndarray:
    """z (N,) of the play operator (module docstring) along the positions ``q`` (N,) [rad]; z_0 = 0."""
    if not travel > 0:
        raise ValueError(f"presliding travel must be a positive angle in rad, got {travel!r}")
    steps = np.diff(np.asarray(q, dtype=float)) / travel
    z = np.empty(steps.size + 1)
    z[0] = 0.0
    for k, s in enumerate(steps, start=1):
        z[k] = min(1.0, max(-1.0, z[k - 1] + s))
    return z


# ---------------------------------------------------------------- friction while moving
# The friction forms (FRICTION_FORMS, DEFAULT_FRICTION) are described in identify.observation.defaults.


def _form_expression(form: str) -> tuple[Any, Any, Any]:  # CasADi SX
    """(v, vs, columns) CasADi symbols: the friction columns of one Coulomb term at speed v
    [rad/s] for the velocity scale vs [rad/s] (FS's column first, then FST's for Stribeck)."""
    import casadi as ca  # here: a command's --help does not pay for CasADi

    v, vs = ca.SX.sym("v"), ca.SX.sym("vs")
    if form == "tanh":
        return v, vs, ca.tanh(v / vs)
    if form == "stribeck":
        e = ca.exp(-(v / vs) ** 2)
        return v, vs, ca.vertcat(ca.sign(v) * (1 - e), ca.sign(v) * e)   # FS·(1 − e)·sgn + FST·e·sgn
    raise ValueError(f"friction form must be one of {FRICTION_FORMS[1:]} to have a velocity scale, got {form!r}")


@lru_cache(maxsize=None)
def friction_function(form: str) -> Any:
    """CasADi function (v, vs) -> (columns, d columns / d vs) of a smooth friction form, for
    row vectors v (1, N) and a scalar vs: columns (k, N), k = 1 (tanh) or 2 (stribeck). The
    derivative is CasADi's (separable least squares' outer gradient)."""
    import casadi as ca

    v, vs, cols = _form_expression(form)
    return ca.Function(f"friction_{form}", [v, vs], [cols, ca.jacobian(cols, vs)])


@lru_cache(maxsize=32)
def _mapped(form: str, size: int) -> Any:
    """:func:`friction_function` mapped over ``size`` speeds, built once per size (the scale search
    evaluates the same rows at every step)."""
    return friction_function(form).map(size)


def friction_columns(form: str, v: np.ndarray, vs: float) -> tuple[np.ndarray, np.ndarray]:
    """(columns (N, k), derivatives (N, k)) of ``form`` at the speeds v (N,) [rad/s], scale vs [rad/s]."""
    if not (np.isfinite(vs) and vs > 0):
        raise ValueError(f"friction velocity scale must be a positive speed in rad/s, got {vs!r}")
    v = np.asarray(v, dtype=float).reshape(-1)
    if form == "tanh":
        # _form_expression's tanh(v/vs) and CasADi's derivative of it, operation for operation, in NumPy
        # (tests/test_friction_rows.py: within an ulp of CasADi's): the scale search evaluates it hundreds of times.
        x = v / vs
        t = np.tanh(x)
        return t[:, None], (-((1 - t * t) * (x / vs)))[:, None]
    cols, dcols = _mapped(form, max(v.size, 1))(v.reshape(1, -1), vs)
    return np.asarray(cols).T, np.asarray(dcols).T


def crossing_passes(mask: np.ndarray, q: np.ndarray, longest: float, travel: float) -> np.ndarray:
    """(S,) True where ``mask`` (below the rest threshold) is a motion, for the "crossing" rest
    policy: inside a run shorter than ``longest`` samples, or where the positions ``q`` [rad] span
    ``travel`` [rad] or more within ``longest`` samples around (a slow motion, or the moments
    after a stop)."""
    size = max(1, int(longest))
    span = maximum_filter1d(q, size, mode="nearest") - minimum_filter1d(q, size, mode="nearest")
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    starts, ends = edges[::2], edges[1::2]
    short = (ends - starts) < longest
    out = np.zeros(mask.size + 1, dtype=np.int32)
    np.add.at(out, starts[short], 1)
    np.add.at(out, ends[short], -1)
    return mask & ((np.cumsum(out[:-1]) > 0) | (span >= travel))


def defaulted_travels(travels: Sequence[float | None]) -> list[float]:
    """Travels [rad] with the default where none was chosen (the joint never rests: no FPj column)."""
    return [PRESLIDING_TRAVEL if v is None or not np.isfinite(v) else float(v) for v in travels]
