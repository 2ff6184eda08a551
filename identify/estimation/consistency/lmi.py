"""Pseudo-inertia LMIs: is a set of standard parameters a physical rigid body?

Parameter layout (paper eq. 4), per link ``j``::

    XXj XYj XZj YYj YZj ZZj MXj MYj MZj Mj IAj FSj FVj

inertia about the *origin* of frame ``j`` expressed in frame ``j`` (kg·m²), first moments
``MX, MY, MZ = M·S`` (kg·m), mass ``M`` (kg), rotor inertia ``IA`` (kg·m²), Coulomb and viscous
friction ``FS`` (N·m) and ``FV`` (N·m·s/rad). Robot-level parameters follow the links
(``FVM6 FSM6``, ``OFF1..OFFn``). The payload ``XXc .. Mc`` (frame 6, about its origin) has the
same ten-entry layout and is treated as one more body.

Pseudo-inertia (Wensing et al. 2017, eq. 11)::

    J = [[ ½·tr(I)·1₃ − I ,  h ],
         [ hᵀ             ,  m ]]          (4×4, h = (MX, MY, MZ), m = M)

``J ⪰ 0`` ⇔ the ten numbers are the moments of a non-negative mass distribution, i.e.
``m ≥ 0``, inertia about the centre of mass PSD *and* its principal moments obeying the
triangle inequalities. ``J ≻ 0`` ⇔ strictly consistent.

Non-negativity rule and the check itself (one function with one tolerance, shared with every
export): :mod:`rx90sym.physical`. A parameter is required to be ``≥ 0`` (``≥ margin``) when its
name *starts with* one of the given prefixes, default ``("IA", "FV", "FS")``. ``FVM6`` and
``FSM6`` therefore fall under ``FV`` and ``FS``; offsets ``OFFj`` and all inertial names are not
affected (no inertial name starts with these prefixes).
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import cvxpy as cp
import numpy as np

from rx90sym.physical import (INERTIAL_FIELDS, NONNEGATIVE, body_indices, body_problem,  # noqa: F401 (re-exported)
                             nonnegative_indices, parameter_problems)

__all__ = ["INERTIAL_FIELDS", "BodyConsistency", "ConsistencyReport", "body_indices",
           "consistency_report", "nonnegative_indices", "pseudo_inertia"]

def _pseudo_inertia_map() -> np.ndarray:
    """Constant (16, 10) matrix L with vec_row(J) = L @ p10 (J row-major)."""
    L = np.zeros((4, 4, 10))
    xx, xy, xz, yy, yz, zz, mx, my, mz, m = range(10)
    # Σ = ½·tr(I)·1 − I: diagonal is half the sum of the two *other* moments minus this one.
    L[0, 0, [xx, yy, zz]] = (-0.5, 0.5, 0.5)
    L[1, 1, [xx, yy, zz]] = (0.5, -0.5, 0.5)
    L[2, 2, [xx, yy, zz]] = (0.5, 0.5, -0.5)
    for (r, c), k in {(0, 1): xy, (0, 2): xz, (1, 2): yz}.items():
        L[r, c, k] = L[c, r, k] = -1.0  # off-diagonal of Σ is minus the product of inertia
    for r, k in enumerate((mx, my, mz)):
        L[r, 3, k] = L[3, r, k] = 1.0
    L[3, 3, m] = 1.0
    return L.reshape(16, 10)


_PSEUDO_INERTIA_MAP = _pseudo_inertia_map()


def pseudo_inertia(p10: Any) -> Any:
    """4×4 pseudo-inertia of one body from its ten inertial parameters.

    Args:
        p10: ``(XX, XY, XZ, YY, YZ, ZZ, MX, MY, MZ, M)`` in kg·m², kg·m, kg — inertia about
            the frame origin, first moments, mass. Either array-like of 10 floats, or a cvxpy
            expression of shape ``(10,)`` (e.g. a slice of the decision variable).

    Returns:
        ``numpy.ndarray (4, 4)`` for numeric input; an affine cvxpy expression ``(4, 4)`` for
        cvxpy input (symmetric by construction, ready for ``J >> 0``).
    """
    if isinstance(p10, cp.Expression):
        if p10.shape != (10,):
            raise ValueError(f"pseudo_inertia: expected a cvxpy expression of shape (10,), got {p10.shape}")
        return cp.reshape(_PSEUDO_INERTIA_MAP @ p10, (4, 4), order="C")
    p = np.asarray(p10, dtype=float)
    if p.shape != (10,):
        raise ValueError(f"pseudo_inertia: expected 10 inertial parameters, got shape {p.shape}")
    return (_PSEUDO_INERTIA_MAP @ p).reshape(4, 4)


# ---------------------------------------------------------------------------------------------
# The check
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BodyConsistency:
    """Consistency of one body.

    Attributes:
        body: ``"1"``…``"n"`` for links, ``"c"`` for the payload.
        min_eigenvalue: smallest eigenvalue of the pseudo-inertia (mixed units: kg·m² for the
            inertial directions, kg for the mass direction; reported as computed).
        mass: M (kg).
        com: centre of mass S = h / M in frame j (m); NaN when M ≤ 0.
        ok: physical with the report's margin (rx90sym.physical.body_problem).
    """

    body: str
    min_eigenvalue: float
    mass: float
    com: tuple[float, float, float]
    ok: bool


@dataclass(frozen=True)
class ConsistencyReport:
    """Physical consistency of a standard parameter vector (see :func:`consistency_report`).

    Attributes:
        bodies: one entry per body with inertial parameters.
        nonnegative: ``(name, value, ok)`` for every parameter under the prefix rule.
        margin: margin checked (pseudo-inertias ⪰ margin·1, prefixed parameters ≥ margin; SI).
        problems: rx90sym.physical.parameter_problems: one line per failure (empty when ``ok``).
        ok: no problem.
    """

    bodies: tuple[BodyConsistency, ...]
    nonnegative: tuple[tuple[str, float, bool], ...]
    margin: float
    problems: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return not self.problems

    @property
    def min_eigenvalue(self) -> float:
        """Smallest pseudo-inertia eigenvalue over all bodies (inf when there is no body)."""
        return min((b.min_eigenvalue for b in self.bodies), default=float("inf"))

    def violations(self) -> tuple[str, ...]:
        """Human-readable list of what fails (empty when ``ok``)."""
        return self.problems


def consistency_report(
    chi: Any,
    names: Sequence[str],
    margin: float = 0.0,
    nonnegative: Sequence[str] = NONNEGATIVE,
    carried: Mapping[str, np.ndarray] | None = None,
) -> ConsistencyReport:
    """Check a standard parameter vector for physical consistency (numpy only): the check of
    every export (rx90sym.physical.parameter_problems, one tolerance), with a margin.

    Args:
        chi: standard parameters, array ``(len(names),)`` in SI units, or a mapping name → value.
        names: their names (eq. 4 layout; payload ``XXc..Mc`` optional).
        margin: a body passes when its pseudo-inertia's smallest eigenvalue is ``≥ margin``, a
            prefixed parameter when it is ``≥ margin`` (absolute, SI units; 0: physical, what an
            export needs; a consistent fit checks rx90sym.physical.DEFAULT_MARGIN).
        nonnegative: name prefixes that must be ``≥ margin`` (prefix rule, module docstring).
        carried: ``{body: XX..M}`` a body carries that an export writes apart (a URDF link's
            lumped hand, rx90sym.urdf_export.carried_bodies): the body minus it is checked and
            reported.

    Returns:
        A frozen :class:`ConsistencyReport`.
    """
    names = tuple(names)
    if isinstance(chi, Mapping):
        missing = [n for n in names if n not in chi]
        if missing:
            raise ValueError(f"consistency_report: chi has no value for {missing}")
        x = np.array([float(chi[n]) for n in names])
    else:
        x = np.asarray(chi, dtype=float)
    if x.shape != (len(names),):
        raise ValueError(f"consistency_report: chi has shape {x.shape}, names has {len(names)} entries")
    if not np.all(np.isfinite(x)):
        bad = [names[i] for i in np.flatnonzero(~np.isfinite(x))]
        raise ValueError(f"consistency_report: non-finite values for {bad}")
    bodies = []
    for body, idx in body_indices(names).items():
        p = x[idx] - np.asarray((carried or {}).get(body, 0.0), dtype=float)
        lam = float(np.linalg.eigvalsh(pseudo_inertia(p))[0])
        mass = float(p[9])
        com = tuple(float(v) for v in p[6:9] / mass) if mass > 0 else (float("nan"),) * 3
        bodies.append(BodyConsistency(body, lam, mass, com, body_problem(p, margin) is None))  # type: ignore[arg-type]
    nonneg = tuple((names[i], float(x[i]), bool(x[i] >= margin)) for i in nonnegative_indices(names, nonnegative))
    return ConsistencyReport(tuple(bodies), nonneg, float(margin), parameter_problems(names, x, margin, nonnegative,
                                                                              carried=carried))
