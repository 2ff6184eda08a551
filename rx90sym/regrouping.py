"""Symbolic regrouping of the standard parameters of a serial chain (Khalil & Dombre; paper
refs. [2, 12]).

The general rules are not typed in: they are derived from rigid-body transfer. For a revolute
joint j, the part of link j that is invariant under rotation about z_j -- inertia
YY_j (x x' + y y'), first moment MZ_j z and mass M_j -- moves with link j-1 and is added to it
through the constant transform (alpha_j, d_j, r_j); for a prismatic joint the whole inertia
tensor of link j (which only rotates with link j-1) is added to link j-1. Doing this from link n
down to link 1 gives exactly the grouping relations of eq. 19 (into the base for link 1: no
effect). Lengths d_j, r_j stay CasADi symbols; alpha_j are numbers (their sines and cosines are
exactly 0, +-1 for the usual right angles).
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from .geometry import exact_trig
from .parameters import LINK_PARAMETERS

_K = len(LINK_PARAMETERS)
_IDX = {p: i for i, p in enumerate(LINK_PARAMETERS)}


@dataclass(frozen=True)
class GeneralGrouping:
    """Result of the general rules: grouped values as SX expressions of chi and the geometry."""

    chi: ca.SX                    # standard parameters, one symbol each (named like the parameter)
    geometry: ca.SX               # non-zero lengths d_j, r_j as symbols (named like their labels)
    geometry_values: tuple[float, ...]
    values: tuple[ca.SX, ...]     # grouped value of every standard parameter (0 when grouped away)


def geometry_symbols(robot) -> tuple[list, list, list[ca.SX], list[float]]:
    """Per-joint d and r as symbols where non-zero (0 otherwise), with the symbol list and values.

    A prismatic joint's r is its variable, so it never appears in the rules and stays numeric.
    """
    d, r, syms, values = [], [], [], []

    def length(value: float, label: str, free: bool) -> ca.SX | float:
        if not free:
            return 0.0
        syms.append(ca.SX.sym(label))
        values.append(value)
        return syms[-1]

    for j in range(robot.n):
        d.append(length(robot.d[j], robot.d_labels[j], robot.d[j] != 0.0))
        r.append(length(robot.r[j], robot.r_labels[j], robot.r[j] != 0.0 and robot.sigma[j] == 0))
    return d, r, syms, values


def _skew(v: ca.SX) -> ca.SX:
    return ca.skew(v)


def _transfer(vals: list, j: int, J: ca.SX, h: ca.SX, m, R: ca.SX, p: ca.SX) -> None:
    """Add a body (J about O_j in frame j, first moment h, mass m) to link j-1 (0-based j-1)."""
    Rh = ca.mtimes(R, h)
    P, H = _skew(p), _skew(Rh)
    J_prev = ca.mtimes(ca.mtimes(R, J), R.T) - m * ca.mtimes(P, P) - (ca.mtimes(P, H) + ca.mtimes(H, P))
    h_prev = m * p + Rh
    b = _K * (j - 1)
    for name, (a, c) in (("XX", (0, 0)), ("XY", (0, 1)), ("XZ", (0, 2)), ("YY", (1, 1)),
                         ("YZ", (1, 2)), ("ZZ", (2, 2))):
        vals[b + _IDX[name]] = ca.simplify(vals[b + _IDX[name]] + J_prev[a, c])
    for i, name in enumerate(("MX", "MY", "MZ")):
        vals[b + _IDX[name]] = ca.simplify(vals[b + _IDX[name]] + h_prev[i])
    vals[b + _IDX["M"]] = vals[b + _IDX["M"]] + m


def general_grouping(robot) -> GeneralGrouping:
    """Apply the general grouping rules from link n down to link 1."""
    names = robot.parameter_names
    chi = ca.vertcat(*[ca.SX.sym(p) for p in names])
    vals = [chi[i] for i in range(len(names))]
    d, r, syms, values = geometry_symbols(robot)
    zero = ca.SX(0)
    for j in reversed(range(robot.n)):
        b = _K * j
        if robot.sigma[j] == 0:
            YY, MZ, M = vals[b + _IDX["YY"]], vals[b + _IDX["MZ"]], vals[b + _IDX["M"]]
            J = ca.diag(ca.vertcat(YY, YY, zero))
            h = ca.vertcat(zero, zero, MZ)
            m = M
            vals[b + _IDX["XX"]] = vals[b + _IDX["XX"]] - YY
            for name in ("YY", "MZ", "M"):
                vals[b + _IDX[name]] = zero
        else:
            J = ca.SX.zeros(3, 3)
            for name, (a, c) in (("XX", (0, 0)), ("XY", (0, 1)), ("XZ", (0, 2)), ("YY", (1, 1)),
                                 ("YZ", (1, 2)), ("ZZ", (2, 2))):
                J[a, c] = vals[b + _IDX[name]]
                J[c, a] = vals[b + _IDX[name]]
                vals[b + _IDX[name]] = zero
            h = ca.SX.zeros(3, 1)
            m = zero
        if j == 0:
            continue  # grouped into the fixed base: no effect on the model
        ca_, sa = exact_trig(robot.alpha[j])
        Rx = ca.SX(ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, ca_, -sa), ca.horzcat(0, sa, ca_)))
        if robot.sigma[j] == 0:
            R = Rx  # the moved part is invariant under Rot(z), so theta_j does not matter
        else:
            ct, st = exact_trig(robot.theta[j])
            R = ca.mtimes(Rx, ca.SX(ca.vertcat(ca.horzcat(ct, -st, 0), ca.horzcat(st, ct, 0),
                                                ca.horzcat(0, 0, 1))))
        p = ca.vertcat(d[j], -sa * r[j], ca_ * r[j])
        _transfer(vals, j, J, h, m, R, p)
    geometry = ca.vertcat(*syms) if syms else ca.SX(0, 1)
    return GeneralGrouping(chi, geometry, tuple(values), tuple(vals))
