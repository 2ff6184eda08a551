"""The friction forms of the moving rows: each joint's Coulomb column sign(q̇) (Coulomb), the smooth
tanh(q̇/vs), or Stribeck's pair sign(q̇)·(1 − e) and sign(q̇)·e with e = exp(−(q̇/vs)²), vs the joint's
velocity scale [rad/s] (:data:`identify.observation.defaults.FRICTION_FORMS`).

The forms are CasADi expressions (their derivative in vs is CasADi's: the scale search's Gauss-Newton
σ); tanh's columns are evaluated in NumPy, operation for operation, where the search evaluates them
hundreds of times.
"""
from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np

from identify.observation.defaults import DEFAULT_FRICTION, FRICTION_FORMS

__all__ = ["DEFAULT_FRICTION", "FRICTION_FORMS", "friction_columns", "friction_function"]


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
