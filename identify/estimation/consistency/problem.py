"""Physically consistent least squares: the conic problem and one solve of it (cvxpy).

The least-squares identification of the base parameters (eqs. 9-10) rewritten over the
standard parameters χ with ``β = K·χ`` and the pseudo-inertia LMIs of :mod:`.lmi` (Wensing,
Kim & Slotine 2017). The data enter only through their QR compression, so the problem does not
grow with the number of samples. A failed or inaccurate solve raises :class:`ConsistencyError`;
the fit with its external check and margin retry is :mod:`.fit`.
"""
from __future__ import annotations

import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import cvxpy as cp
import numpy as np

from rx90sym.messages import plain

from identify.estimation.consistency.errors import ConsistencyError  # noqa: F401 (raised here, re-exported)
from identify.estimation.consistency.lmi import body_indices, nonnegative_indices, pseudo_inertia

__all__ = ["DEFAULT_SOLVER_OPTIONS", "SOLVERS", "ConsistencyError", "ConsistentProblem",
           "build_consistent_problem", "null_space", "solve_problem"]
# Objective scale floor relative to ‖z‖² (noise-free data, or rss_outside not given).
_SCALE_FLOOR = 1e-10
# Default null-space tie-break (see build_consistent_problem): bounded, and a negligible fit cost.
NULL_SPACE_WEIGHT = 1e-6

SOLVERS = ("CLARABEL", "SCS")

#: Bounds of the options: (lo, hi) with None for an open side; per body (1..n or "c").
Interval = tuple[float | None, float | None]
MassBounds = Mapping[int | str, Interval]
ComBoxes = Mapping[int | str, tuple[Sequence[float], Sequence[float]]]

# SCS is a first-order method: its default tolerances (1e-4) are far looser than a comparison
# with Clarabel can live with; 1e-7 is the tightest that converged on high signal-to-noise RX90
# data (1e-9 hit the iteration limit there). Its small cone violations are then handled by the
# external check and margin retry.
DEFAULT_SOLVER_OPTIONS: dict[str, dict[str, Any]] = {
    "CLARABEL": {},
    "SCS": {"eps_abs": 1e-7, "eps_rel": 1e-7, "max_iters": 100_000},
}


# The fit
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ConsistentProblem:
    """A built (not yet solved) consistent least-squares problem.

    Attributes:
        problem: the cvxpy problem; its size depends on c and len(names), never on the number
            of data rows.
        chi: the decision variable (standard parameters, SI).
        names: standard parameter names.
        scale: s_o, the constant dividing the objective (weighted torque units): the noise
            scale s_n for ``objective_scale="noise"``, ‖z‖ for ``"data"``.
        noise_scale: s_n = √max(rss_outside, 1e-10·‖z‖²), the residual no β can remove.
        epsilon: margin actually imposed (``J ⪰ ε·1`` and prefixed parameters ``≥ ε``).
    """

    problem: cp.Problem
    chi: cp.Variable
    names: tuple[str, ...]
    scale: float
    noise_scale: float
    epsilon: float


def _as_bounds(value: Any, what: str) -> tuple[float, float]:
    """(lo, hi) with None → ∓inf; ValueError naming ``what`` otherwise."""
    try:
        lo, hi = value
    except (TypeError, ValueError):
        raise ValueError(f"{what}: expected a pair (lo, hi), got {plain(value)}") from None
    lo = -np.inf if lo is None else float(lo)
    hi = np.inf if hi is None else float(hi)
    if np.isnan(lo) or np.isnan(hi):
        raise ValueError(f"{what}: NaN bound in {plain(value)}")
    return lo, hi


def null_space(K: np.ndarray) -> np.ndarray:
    """Orthonormal basis (np, np − rank) of the null space of K (SVD, relative tolerance)."""
    _, sv, vt = np.linalg.svd(K)
    rank = int(np.sum(sv > sv[0] * max(K.shape) * np.finfo(float).eps)) if sv.size and sv[0] > 0 else 0
    return vt[rank:].T


def build_consistent_problem(
    R: np.ndarray,
    z: np.ndarray,
    K: np.ndarray,
    names: Sequence[str],
    *,
    rss_outside: float = 0.0,
    prior: Mapping[str, float] | None = None,
    prior_weight: float = 0.0,
    mass_bounds: MassBounds | None = None,
    total_mass: Interval | None = None,
    com_boxes: ComBoxes | None = None,
    epsilon: float = 0.0,
    nonnegative: Sequence[str] = ("IA", "FV", "FS"),
    null_space_weight: float = NULL_SPACE_WEIGHT,
    objective_scale: str = "noise",
    carried: Mapping[str, np.ndarray] | None = None,
) -> ConsistentProblem:
    """Build the conic problem behind :func:`consistent_least_squares` (same arguments).

    Formulation (one second-order cone + 4×4 LMIs, no quadratic objective)::

        minimise   (1/s_o)·‖ [ R K χ − z ;  √w·(χ_P − χ_prior) ;  √δ·s_n·Nᵀ(χ − χ_ref) ] ‖₂
        subject to J_b(χ) − J(carried_b) ⪰ ε·1₄ for every body b,  χ_i ≥ ε for prefixed names,
                   mass / total-mass bounds, m·lo ≤ h ≤ m·hi CoM boxes,

    with N an orthonormal basis of null(K), δ = ``null_space_weight``, χ_ref the prior values
    (0 where no prior), s_n² = max(rss_outside, 1e-10·‖z‖²) the noise scale (the residual no β
    can remove; the floor covers noise-free data and a missing rss_outside) and s_o the
    objective scale. Minimising the norm instead of its square has the same minimisers and is
    better scaled; s_o changes the numbers the solver sees, never the minimiser:

    * ``objective_scale="noise"`` (s_o = s_n, used for Clarabel): the objective is ≈ 1 at a good
      fit, so the interior-point tolerances (1e-8) are 1e-8 of the *noise* and the solver error
      is negligible against the statistical uncertainty at any signal-to-noise ratio.
    * ``objective_scale="data"`` (s_o = ‖z‖, used for SCS): the objective is 1 at χ = 0. SCS,
      a first-order method, fails to converge when the fit rows are ~1e3 times larger than the
      cone rows, which the noise scale produces on high signal-to-noise data.
    """
    names = tuple(names)
    R, z, K = _checked_system(R, z, K, names)
    if not (np.isfinite(epsilon) and epsilon >= 0.0):
        raise ValueError(f"epsilon: must be finite and >= 0, got {plain(epsilon)}")
    bodies = body_indices(names)
    noise_scale, scale = _scales(z, rss_outside, objective_scale)
    chi = cp.Variable(len(names), name="chi")
    residuals = [(R @ K / scale) @ chi - z / scale]
    residuals += _prior_residual(chi, names, prior, prior_weight, scale)
    residuals += _null_space_residual(chi, names, K, prior, null_space_weight, noise_scale / scale)
    objective = cp.norm(cp.hstack(residuals), 2)
    constraints = (_cone_constraints(chi, names, bodies, epsilon, nonnegative, carried)
                   + _mass_constraints(chi, bodies, mass_bounds, total_mass)
                   + _com_box_constraints(chi, bodies, com_boxes))
    problem = cp.Problem(cp.Minimize(objective), constraints)
    return ConsistentProblem(problem, chi, names, scale, noise_scale, float(epsilon))


def _checked_system(R: np.ndarray, z: np.ndarray, K: np.ndarray,
                    names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(R, z, K) as float arrays of matching shapes, all finite; ValueError naming the culprit."""
    R = np.asarray(R, dtype=float)
    z = np.asarray(z, dtype=float).reshape(-1)
    K = np.asarray(K, dtype=float)
    n_par = len(names)
    if K.ndim != 2 or K.shape[1] != n_par:
        raise ValueError(f"K: expected shape (c, {n_par}) to match names, got {K.shape}")
    c = K.shape[0]
    if R.ndim != 2 or R.shape[1] != c:
        raise ValueError(f"R: expected {c} columns (one per base parameter, rows of K), got shape {R.shape}")
    if z.shape != (R.shape[0],):
        raise ValueError(f"z: expected length {R.shape[0]} (rows of R), got {z.shape[0]}")
    for label, arr in (("R", R), ("z", z), ("K", K)):
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{label}: contains NaN or inf")
    return R, z, K


def check_rss_outside(rss_outside: float) -> None:
    if not (np.isfinite(rss_outside) and rss_outside >= 0.0):
        raise ValueError(f"rss_outside: must be finite and >= 0, got {plain(rss_outside)}")


def _scales(z: np.ndarray, rss_outside: float, objective_scale: str) -> tuple[float, float]:
    """(s_n, s_o): the noise scale and the objective scale (build_consistent_problem)."""
    check_rss_outside(rss_outside)
    noise_scale = float(np.sqrt(max(rss_outside, _SCALE_FLOOR * float(z @ z))))
    if noise_scale == 0.0:
        noise_scale = 1.0  # zero data: any scale works, keep 1 to avoid dividing by zero
    if objective_scale == "noise":
        return noise_scale, noise_scale
    if objective_scale == "data":
        return noise_scale, max(float(np.linalg.norm(z)), noise_scale)
    raise ValueError(f"objective_scale: expected 'noise' or 'data', got {objective_scale!r}")


def prior_indices(names: tuple[str, ...], prior: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """Indices in ``names`` and values of the prior's parameters."""
    unknown = [n for n in prior if n not in names]
    if unknown:
        raise ValueError(f"prior: unknown parameter names {unknown}")
    idx = np.array([names.index(n) for n in prior], dtype=int)
    ref = np.array([float(prior[n]) for n in prior])
    if not np.all(np.isfinite(ref)):
        raise ValueError("prior: contains NaN or inf")
    return idx, ref


def _prior_residual(chi: cp.Variable, names: tuple[str, ...], prior: Mapping[str, float] | None,
                    prior_weight: float, scale: float) -> list[cp.Expression]:
    """√w·(χ_P − χ_prior)/s_o, or nothing without a prior."""
    if not prior:
        if prior_weight != 0.0:
            raise ValueError("prior_weight: given without a prior (pass prior={name: value, ...})")
        return []
    if not (np.isfinite(prior_weight) and prior_weight > 0.0):
        raise ValueError(f"prior_weight: must be > 0 when a prior is given, got {plain(prior_weight)}")
    idx, ref = prior_indices(names, prior)
    return [(np.sqrt(prior_weight) / scale) * (chi[idx] - ref)]


def _null_space_residual(chi: cp.Variable, names: tuple[str, ...], K: np.ndarray,
                         prior: Mapping[str, float] | None, null_space_weight: float,
                         relative_scale: float) -> list[cp.Expression]:
    """√δ·(s_n/s_o)·Nᵀ(χ − χ_ref), the null-space tie-break, or nothing when δ = 0."""
    if not (np.isfinite(null_space_weight) and null_space_weight >= 0.0):
        raise ValueError(f"null_space_weight: must be finite and >= 0, got {plain(null_space_weight)}")
    if null_space_weight == 0.0:
        return []
    # Directions of χ that K maps to 0 do not change the fit. Some are unbounded inside the
    # consistent set (e.g. XX1 + YY1 of a first link turning about a fixed axis can grow
    # without limit), and an interior-point solver then drifts along them (we saw
    # |χ| ≈ 4e4 on a 3-link arm). A small pull on the null-space coordinates ν only makes
    # the optimum unique and bounded. It leaves the fit alone when a consistent χ with the
    # OLS β exists at the pulled point; otherwise its cost is at most δ·s_n²·‖ν‖², i.e. a
    # fraction δ·‖ν‖² of the residual (measured on RX90 data at δ = 1e-6: ≤ 5e-5 of the
    # residual, while δ = 0 let unseen masses drift to 800 kg).
    null = null_space(K)
    if not null.shape[1]:
        return []
    ref = np.zeros(len(names))
    for name, value in (prior or {}).items():
        ref[names.index(name)] = float(value)
    weight = np.sqrt(null_space_weight) * relative_scale
    return [weight * (null.T @ chi - null.T @ ref)]


def _cone_constraints(chi: cp.Variable, names: tuple[str, ...], bodies: Mapping[str, np.ndarray],
                      epsilon: float, nonnegative: Sequence[str],
                      carried: Mapping[str, np.ndarray] | None = None) -> list[cp.Constraint]:
    """J_b(χ) − J(carried_b) ⪰ ε·1 per body and χ_i ≥ ε for the prefixed names (carried_b: XX..M
    of what body b carries and an export writes apart, e.g. a URDF link's lumped hand; 0 if none)."""
    # J ⪰ ε·1: PSD ⇔ physically consistent incl. triangle inequalities (Wensing 2017).
    carried = carried or {}
    constraints = [pseudo_inertia(chi[idx]) - (pseudo_inertia(np.asarray(carried[b], dtype=float)) if b in carried else 0.0)
                   - epsilon * np.eye(4) >> 0 for b, idx in bodies.items()]
    nonneg = nonnegative_indices(names, nonnegative)
    if nonneg.size:
        constraints.append(chi[nonneg] >= epsilon)
    return constraints


def _body(bodies: Mapping[str, np.ndarray], key: int | str, what: str) -> np.ndarray:
    body = str(key)
    if body not in bodies:
        raise ValueError(f"{what}: no body {body!r} in the parameter names (bodies: {list(bodies)})")
    return bodies[body]


def _interval(expr: cp.Expression, lo: float, hi: float) -> list[cp.Constraint]:
    """lo ≤ expr ≤ hi, leaving out an infinite side."""
    return ([expr >= lo] if np.isfinite(lo) else []) + ([expr <= hi] if np.isfinite(hi) else [])


def _mass_constraints(chi: cp.Variable, bodies: Mapping[str, np.ndarray],
                      mass_bounds: MassBounds | None,
                      total_mass: Interval | None) -> list[cp.Constraint]:
    """Bounds on single masses and on the sum of the link masses [kg]."""
    constraints: list[cp.Constraint] = []
    for key, bounds in (mass_bounds or {}).items():
        lo, hi = _as_bounds(bounds, f"mass_bounds[{key!r}]")
        constraints += _interval(chi[_body(bodies, key, "mass_bounds")[9]], lo, hi)
    if total_mass is not None:
        lo, hi = _as_bounds(total_mass, "total_mass")
        link_masses = [idx[9] for body, idx in bodies.items() if body.isdigit()]
        if not link_masses:
            raise ValueError("total_mass: no link inertial parameters in names")
        constraints += _interval(cp.sum(chi[np.array(link_masses)]), lo, hi)
    return constraints


def _com_box_constraints(chi: cp.Variable, bodies: Mapping[str, np.ndarray],
                         com_boxes: ComBoxes | None
                         ) -> list[cp.Constraint]:
    """m·lo ≤ h ≤ m·hi: the centre of mass h/m in a box (m), linear because m ≥ 0 (J ⪰ 0)."""
    constraints: list[cp.Constraint] = []
    for key, box in (com_boxes or {}).items():
        try:
            lo3, hi3 = (np.asarray(b, dtype=float).reshape(3) for b in box)
        except (TypeError, ValueError):
            raise ValueError(f"com_boxes[{key!r}]: expected (lo3, hi3), two triples in m, got {box!r}") from None
        idx = _body(bodies, key, "com_boxes")
        h, m = chi[idx[6:9]], chi[idx[9]]
        for axis in range(3):
            if np.isfinite(lo3[axis]):
                constraints.append(h[axis] >= lo3[axis] * m)
            if np.isfinite(hi3[axis]):
                constraints.append(h[axis] <= hi3[axis] * m)
    return constraints


def solve_problem(built: ConsistentProblem, solver: str, options: Mapping[str, Any]) -> tuple[np.ndarray, float, int | None]:
    """Solve ``built``; raise ConsistencyError for anything but an optimal status."""
    start = time.perf_counter()
    try:
        with warnings.catch_warnings():
            # cvxpy warns "Solution may be inaccurate"; such a status is raised below instead.
            warnings.filterwarnings("ignore", message="Solution may be inaccurate", category=UserWarning)
            built.problem.solve(solver=solver, **options)
    except cp.error.SolverError as exc:
        raise ConsistencyError(
            f"consistent least squares: solver {solver} failed (status 'solver_error'): {exc}",
            status="solver_error",
            solver=solver,
        ) from exc
    elapsed = time.perf_counter() - start
    status = built.problem.status
    if status != cp.OPTIMAL or built.chi.value is None:
        hint = {
            cp.INFEASIBLE: " — the bounds (mass, total mass, CoM boxes, epsilon) cannot all hold for a physical body",
            cp.INFEASIBLE_INACCURATE: " — probably infeasible bounds",
            cp.OPTIMAL_INACCURATE: " — solver stopped short of its tolerances; the result is not returned",
        }.get(status, "")
        raise ConsistencyError(
            f"consistent least squares: solver {solver} returned status {status!r}{hint}",
            status=str(status),
            solver=solver,
        )
    return np.array(built.chi.value, dtype=float), elapsed, built.problem.solver_stats.num_iters
