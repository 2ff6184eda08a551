"""The consistent fit with a prior: the best fit of the data, then the physical chi nearest to the
prior among those that fit the data as well to within one residual variance (the two stages of
:mod:`identify.estimation.consistency.prior`)."""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import cvxpy as cp
import numpy as np

from rx90sym.physical import DEFAULT_MARGIN

from identify.estimation.consistency.fit import ConsistentSolution, _solution, _solve_checked, consistent_least_squares
from identify.estimation.consistency.lmi import body_indices
from identify.estimation.consistency.prior import PhysicalPrior, prior_constraints, prior_scales
from identify.estimation.consistency.problem import (DEFAULT_SOLVER_OPTIONS, ConsistentProblem, _cone_constraints,
                                                     check_rss_outside)

__all__ = ["PRIOR_BUDGET", "prior_fit", "unseen_distance"]

# How far the prior may move the base parameters from the best consistent fit, in standard
# deviations (the ellipsoid of their covariance). Measured (docs/export.md): 1 keeps the twin's
# base parameters within 2.5 sigma of the truth but leaves UR10e links 3-4 at 2.3x / 0.4x of UR's
# masses; 2: twin within 2.7 sigma, every UR10e link within a factor 2, held-out RMS +0.3 %;
# 3: the twin's base parameters reach 3.15 sigma.
PRIOR_BUDGET = 2.0


def prior_fit(R: np.ndarray, z: np.ndarray, K: np.ndarray, names: Sequence[str], prior: PhysicalPrior, *,
              rss_outside: float = 0.0, rows: int | None = None, solver: str = "CLARABEL",
              nonnegative: Sequence[str] = ("IA", "FV", "FS"), epsilon: float = DEFAULT_MARGIN,
              solver_options: Mapping[str, Any] | None = None, covariance: np.ndarray | None = None,
              budget: float = PRIOR_BUDGET, carried: Mapping[str, np.ndarray] | None = None
              ) -> tuple[ConsistentSolution, ConsistentSolution]:
    """(stage 1, stage 2) solutions: the consistent least squares under the prior's bounds, and
    the physical chi nearest the prior (scaled norm, :func:`prior_scales`) whose base parameters
    lie within ``budget`` standard deviations of stage 1's:
    ``(K chi - beta1)^T C^-1 (K chi - beta1) <= budget^2`` with C the base parameters' covariance: ``covariance`` (e.g. the segment bootstrap's, which
    is what the data support when the residual is coloured) or eq. 13's, sigma_rho^2 (R^T R)^-1
    (sigma_rho^2 = RSS / (rows - c), eq. 12). Arguments as :func:`consistent_least_squares`;
    ``rows`` is needed (the residual variance)."""
    check_rss_outside(rss_outside)
    names = tuple(names)
    if rows is None:
        raise ValueError("prior_fit: rows (the number of equations) is needed for the residual variance")
    first = consistent_least_squares(R, z, K, names, rss_outside=rss_outside, rows=rows, solver=solver,
                                     nonnegative=nonnegative, epsilon=epsilon, solver_options=solver_options,
                                     physical_prior=prior, carried=carried)
    R, z, K = (np.asarray(a, dtype=float) for a in (R, z, K))
    fit1 = float(np.sum((R @ first.beta - z) ** 2))
    whiten = _whitening(R, covariance, (fit1 + rss_outside) / max(rows - K.shape[0], 1))
    reference = np.array([prior.values.get(n, v) for n, v in zip(names, first.chi)])
    scales = prior_scales(names, prior)
    noise = float(np.sqrt(max(rss_outside + fit1, 1e-300)))

    def build(margin: float) -> ConsistentProblem:
        chi = cp.Variable(len(names), name="chi")
        fit = cp.norm((whiten @ K) @ chi - whiten @ first.beta, 2) <= float(budget)
        constraints = [fit, *_cone_constraints(chi, names, body_indices(names), margin, nonnegative, carried),
                       *prior_constraints(chi, names, prior)]
        problem = cp.Problem(cp.Minimize(cp.norm(cp.multiply(1.0 / scales, chi - reference), 2)), constraints)
        return ConsistentProblem(problem, chi, names, noise, noise, float(margin))

    options = {**DEFAULT_SOLVER_OPTIONS[solver.upper()], **(solver_options or {})}
    # Stage 2 starts from the margin stage 1 needed (its retry, if any, says the solver needs it).
    solve = _solve_checked(build, epsilon, solver.upper(), options, names, nonnegative, solve_margin=first.epsilon,
                           carried=carried)
    second = _solution(solve, R, z, K, names, rss_outside, None, 0.0, solver.upper(), rows)
    return first, second


def _whitening(R: np.ndarray, covariance: np.ndarray | None, variance: float) -> np.ndarray:
    """A matrix G with G^T G = C^-1: R / sigma_rho for eq. 13's covariance, else from C's
    eigen-decomposition (directions with no spread are held fixed by a large weight)."""
    if covariance is None:
        return R / np.sqrt(variance)
    C = np.asarray(covariance, dtype=float)
    lam, V = np.linalg.eigh(0.5 * (C + C.T))
    floor = max(float(lam.max()), 1e-300) * 1e-12
    return (V / np.sqrt(np.maximum(lam, floor))).T


def unseen_distance(K: np.ndarray, names: Sequence[str], prior: PhysicalPrior, chi: np.ndarray) -> float:
    """|| N^T S^-1 (chi - prior) || / || N^T S^-1 prior ||: how far the directions the data cannot see
    (the null space N of K S, scaled units) are from the prior's (0: exactly the prior's)."""
    from identify.estimation.consistency.problem import null_space

    names = tuple(names)
    scales = prior_scales(names, prior)
    keep = np.array([n in prior.values for n in names])
    reference = np.array([prior.values.get(n, 0.0) for n in names])
    N = null_space(np.asarray(K, dtype=float) * scales[None, :])
    y = (np.asarray(chi, dtype=float) - reference) / scales
    y0 = reference / scales
    return float(np.linalg.norm(N[keep].T @ y[keep]) / np.linalg.norm(N[keep].T @ y0[keep]))
