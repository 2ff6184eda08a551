"""The consistency margin: could *any* standard parameters reproducing β be physical?"""
from __future__ import annotations

from collections.abc import Sequence

import cvxpy as cp
import numpy as np

from identify.estimation.consistency.lmi import body_indices, nonnegative_indices, pseudo_inertia
from identify.estimation.consistency.errors import ConsistencyError
from identify.estimation.consistency.problem import DEFAULT_SOLVER_OPTIONS, SOLVERS, ConsistentProblem, null_space, solve_problem

__all__ = ["consistency_margin"]

# Null-space tie-break weights tried in turn while the solver stops short (docstring).
_TIE_BREAKS = (1e-8, 1e-6, 1e-4)

def consistency_margin(
    beta: np.ndarray,
    K: np.ndarray,
    names: Sequence[str],
    *,
    nonnegative: Sequence[str] = ("IA", "FV", "FS"),
    solver: str = "CLARABEL",
    cap: float = 1.0,
) -> tuple[float, np.ndarray]:
    """How consistent can standard parameters reproducing β be? (exact "was OLS consistent?").

    β is consistent when *some* standard parameters with ``K χ = β`` are (the null space of K
    is free), which a check of one particular χ cannot tell. This solves::

        t* = max t   s.t.  K χ = β,  J_b(χ) ⪰ t·1₄ for every body,  χ_i ≥ t (prefixed names),
                           t ≤ cap

    (tie-break: the smallest null-space component, weight 1e-8, only to keep χ bounded; when the
    solver stops short of its tolerances, as on a far inconsistent β whose unseen directions
    drift (t* = −705 on a 4 s UR10e twin, |χ| ≈ 4e4), the weight is raised to 1e-6, then 1e-4:
    t* moved by 2e-4 there); when t* > 0 a second solve returns the smallest witness χ with
    margin t*/2.

    Args:
        beta: (c,) base parameters.
        K: (c, len(names)) standard → base map.
        names: standard parameter names.
        nonnegative: name prefixes that must be ≥ 0 (module docstring).
        solver: ``"CLARABEL"`` or ``"SCS"``.
        cap: upper limit of t (mixed units: kg·m², kg, N·m; only keeps the problem bounded).

    Returns:
        ``(t*, χ)``: t* > 0 → β is strictly consistent, and χ (reproducing β to solver
        accuracy, pseudo-inertia eigenvalues ≥ t*/2) is a witness; t* < 0 → no consistent χ
        reproduces β (−t* is how far the best one is from the cones, and χ is that one);
        |t*| ≲ 1e-8 → on the boundary to solver accuracy.

    Raises:
        ConsistencyError: the solver did not reach an optimal status.
    """
    names = tuple(names)
    beta = np.asarray(beta, dtype=float).reshape(-1)
    K = np.asarray(K, dtype=float)
    if K.ndim != 2 or K.shape != (beta.size, len(names)):
        raise ValueError(f"K: expected shape ({beta.size}, {len(names)}) for beta and names, got {K.shape}")
    solver = solver.upper()
    if solver not in SOLVERS:
        raise ValueError(f"solver: expected one of {SOLVERS}, got {solver!r}")
    # Rows scaled to unit norm so the equality tolerance is relative to each base parameter.
    row_scale = np.maximum(np.linalg.norm(K, axis=1), np.finfo(float).tiny)
    chi = cp.Variable(len(names), name="chi")
    t = cp.Variable(name="t")
    constraints: list[cp.Constraint] = [(K / row_scale[:, None]) @ chi == beta / row_scale, t <= cap]
    for idx in body_indices(names).values():
        constraints.append(pseudo_inertia(chi[idx]) - t * np.eye(4) >> 0)
    nonneg = nonnegative_indices(names, nonnegative)
    if nonneg.size:
        constraints.append(chi[nonneg] >= t)
    null = null_space(K)
    spread = cp.norm(null.T @ chi, 2) if null.shape[1] else cp.Constant(0.0)
    options = DEFAULT_SOLVER_OPTIONS[solver]
    for weight in _TIE_BREAKS:
        built = ConsistentProblem(cp.Problem(cp.Maximize(t - weight * spread), constraints), chi, names, 1.0, 1.0, 0.0)
        try:
            value, _, _ = solve_problem(built, solver, options)
            break
        except ConsistencyError as exc:
            if exc.status != cp.OPTIMAL_INACCURATE or weight == _TIE_BREAKS[-1]:
                raise
    margin = float(t.value)
    if margin > 0 and null.shape[1]:
        # Maximising t leaves the bodies that do not limit it wherever the solver drifted (we
        # saw |χ| ≈ 2e3): re-solve for the smallest witness keeping half the margin.
        constraints.append(t == margin / 2)
        built = ConsistentProblem(cp.Problem(cp.Minimize(spread), constraints), chi, names, 1.0, 1.0, 0.0)
        value, _, _ = solve_problem(built, solver, options)
    return margin, value
