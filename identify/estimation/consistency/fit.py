"""Physically consistent least squares (paper eqs. 9-10 under the pseudo-inertia LMIs): build,
solve with ten times the margin, check the solution outside the solver against the margin (the check
of every export, rx90sym.physical), and re-solve with a larger margin when the solver's error ate
it. The problem itself is :mod:`.problem`.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rx90sym.physical import DEFAULT_MARGIN

from identify.estimation.consistency.lmi import ConsistencyReport, consistency_report
from identify.estimation.consistency.problem import (DEFAULT_SOLVER_OPTIONS, NULL_SPACE_WEIGHT, SOLVERS, ComBoxes, ConsistencyError,
                      ConsistentProblem, Interval, MassBounds, build_consistent_problem, check_rss_outside,
                      prior_indices, solve_problem)

__all__ = ["ConsistentSolution", "consistent_least_squares"]

# The solver is asked for SOLVE_FACTOR times the margin it is checked against (rx90sym.physical):
# room for its feasibility error (measured up to 4e-8 in SI units on 4 s twins; the default margin
# is 1e-8). With 2: every short UR10e twin re-solved once (solve time x2); with 10: none.
SOLVE_FACTOR = 10.0
# When the check still fails, the solve's margin grows by 10x, then 100x the shortfall (at least
# the solver's error, 1e-9): the next solve lands at least that far inside.
_RETRY_MARGIN_FACTOR = 10.0
_SOLVER_ERROR = 1e-9
_RETRY_ATTEMPTS = 3  # solves in all: the requested one and at most two tightened ones


@dataclass(frozen=True)
class ConsistentSolution:
    """Result of :func:`consistent_least_squares`.

    Attributes:
        names: standard parameter names.
        chi: standard parameters (SI), same order as ``names``.
        beta: base parameters ``K @ chi``.
        cost: ``‖R K χ − z‖² + rss_outside`` — the weighted residual sum of squares of the full
            system ``‖W β − Y‖²`` (units of the weighted torques, squared). The prior term is
            not included (see ``prior_cost``).
        prior_cost: ``prior_weight · ‖χ_P − χ_prior‖²`` at the solution (0 without prior).
        solver: solver used.
        status: cvxpy status (always ``"optimal"``: anything else raises).
        solve_time: wall time of the solve, cvxpy canonicalisation included (s).
        iterations: solver iterations (last solve).
        epsilon: margin imposed in the returned solve (``SOLVE_FACTOR`` × the checked margin,
            more when the automatic retry was needed, see :func:`consistent_least_squares`).
        retried: whether the automatic margin retry was used.
        rows: number of equations behind (R, z), when given.
        report: :func:`consistency_report` of ``chi`` at the requested margin (always ``ok``:
            every pseudo-inertia eigenvalue and prefixed parameter ≥ ``report.margin``).
    """

    names: tuple[str, ...]
    chi: np.ndarray
    beta: np.ndarray
    cost: float
    prior_cost: float
    solver: str
    status: str
    solve_time: float
    iterations: int | None
    epsilon: float
    retried: bool
    rows: int | None
    report: ConsistencyReport = field(repr=False)

    @property
    def standard(self) -> dict[str, float]:
        """Standard parameters as ``{name: value}`` (SI)."""
        return {n: float(v) for n, v in zip(self.names, self.chi)}


def consistent_least_squares(
    R: np.ndarray,
    z: np.ndarray,
    K: np.ndarray,
    names: Sequence[str],
    *,
    rss_outside: float = 0.0,
    rows: int | None = None,
    prior: Mapping[str, float] | None = None,
    prior_weight: float = 0.0,
    mass_bounds: MassBounds | None = None,
    total_mass: Interval | None = None,
    com_boxes: ComBoxes | None = None,
    epsilon: float = DEFAULT_MARGIN,
    solver: str = "CLARABEL",
    nonnegative: Sequence[str] = ("IA", "FV", "FS"),
    solver_options: Mapping[str, Any] | None = None,
    null_space_weight: float = NULL_SPACE_WEIGHT,
    carried: Mapping[str, np.ndarray] | None = None,
) -> ConsistentSolution:
    """Physically consistent least squares over the standard parameters.

    Solves ``min ‖R K χ − z‖² (+ prior_weight·‖χ_P − χ_prior‖²)`` subject to every body's
    pseudo-inertia ``⪰ epsilon·1`` (checked after the solve) and the options below, where (R, z) is the QR-compressed
    weighted base-parameter system (``W = Q R``, ``z = Qᵀ Y``, ``rss_outside = ‖Y‖² − ‖z‖²``),
    so the conic problem has the size of the base parameters, not of the data.

    Args:
        R: (c, c) upper-triangular factor of the weighted base observation matrix (any (m, c)
            works, but the problem then grows with m).
        z: (c,) ``Qᵀ Y`` (weighted torques, N·m after weighting).
        K: (c, len(names)) standard → base map, ``β = K χ``.
        names: standard parameter names (eq. 4 layout, payload ``XXc..Mc`` optional).
        rss_outside: ``‖Y‖² − ‖z‖²``, the part of the residual no β can explain; added to the
            reported cost and used as the noise scale s_n (pass it: without it s_n falls back to
            1e-5·‖z‖, solver tolerances are no longer tied to the noise and the tie-break below
            becomes negligible).
        rows: number of equations behind (R, z), kept in the result for reporting.
        prior: ``{name: value}`` reference values (e.g. CAD) pulling the directions the data do
            not see; weighted by ``prior_weight`` in cost units per (parameter unit)².
        mass_bounds: ``{link: (lo, hi)}`` in kg; link is ``1..n`` (int or str) or ``"c"``;
            ``None`` for an open side.
        total_mass: ``(lo, hi)`` in kg on the sum of the *link* masses (payload excluded).
        com_boxes: ``{link: (lo3, hi3)}`` box on the centre of mass in frame j (m), imposed as
            ``M·lo ≤ (MX, MY, MZ) ≤ M·hi``; ±inf for an open side.
        epsilon: margin ε: ``J ⪰ ε·1`` and prefixed parameters ``≥ ε`` in the returned χ
            (default rx90sym.physical.DEFAULT_MARGIN, 1e-8 SI, absolute: its docstring says
            why; what every export then accepts without a tolerance argument). 0: physical
            only, to rounding (an MJCF export may then refuse a near-massless link).
        solver: ``"CLARABEL"`` (default, interior point) or ``"SCS"`` (first order; run here with
            1e-7 tolerances and up to 1e5 iterations unless ``solver_options`` says otherwise;
            slower, and usually needs the margin retry below).
        nonnegative: name prefixes forced ``≥ epsilon`` (prefix rule, module docstring).
        solver_options: extra keyword arguments for ``cvxpy.Problem.solve``.
        null_space_weight: δ, weight of the tie-break ``δ·s_n²·‖Nᵀ(χ − χ_ref)‖²`` on the
            components ν of χ in the null space of K (χ_ref = prior values, 0 elsewhere), in
            residuals per SI unit². It picks one bounded χ among the many with the same β and
            costs at most a fraction δ·‖ν‖² of the residual; 0 disables it (the solver may
            then return huge values in directions the data do not see).
        carried: ``{body: XX..M}`` (body "1".."n") a link carries that an export writes apart (a
            URDF link's lumped hand and fingers: rx90sym.urdf_export.carried_bodies): the link
            minus it is held physical with the margin, so the export never refuses it.

    Returns:
        :class:`ConsistentSolution` whose ``report.ok`` is always True.

    Raises:
        ConsistencyError: status other than optimal (infeasible bounds, inaccurate, solver
            error), or the external check still failing after the margin retry.
        ValueError: malformed input (shapes, names, bounds).

    Solver-tolerance handling: interior-point solvers meet the cone constraints only to their
    feasibility tolerance, so a solution on the boundary (the usual case when the unconstrained
    estimate is inconsistent) comes back up to ~1e-9 outside (we saw pseudo-inertia eigenvalues
    of −8e-10 and a rotor inertia of −2.7e-10 that exports then refused). The problem is
    therefore solved with ``SOLVE_FACTOR``·ε (``J ⪰ 10ε·1``, prefixed parameters ``≥ 10ε``) and
    the returned χ checked against ε with :func:`consistency_report` (rx90sym.physical: the
    check of every export, one tolerance). If the check fails, the problem is solved again with
    the solve's margin raised by ``10·max(shortfall, 1e-9)``, then if needed by 100× the new
    shortfall. If the third solve still fails the check, :class:`ConsistencyError` (status
    ``"external_check_failed"``) is raised. ``solution.epsilon`` and ``solution.retried`` say
    what happened. User bounds (mass, total mass, CoM box) hold to the solver tolerance.

    Note: the standard parameters are not unique (K has a null space); directions the data do
    not see are decided by the constraints, the prior if any, and the small null-space
    tie-break (which, without a prior, pulls unseen parameters toward 0 as far as consistency
    allows — e.g. the smallest mass compatible with the seen first moments). Give a CAD
    ``prior`` when the unseen values matter. Compare ``beta`` across solvers, not ``chi``: β is
    unique because R is non-singular.
    """
    solver = solver.upper()
    if solver not in SOLVERS:
        raise ValueError(f"solver: expected one of {SOLVERS}, got {solver!r}")
    check_rss_outside(rss_outside)
    names = tuple(names)
    R, z, K = (np.asarray(R, dtype=float), np.asarray(z, dtype=float).reshape(-1), np.asarray(K, dtype=float))

    def build(margin: float) -> ConsistentProblem:
        return build_consistent_problem(
            R, z, K, names, epsilon=margin, rss_outside=rss_outside, prior=prior, prior_weight=prior_weight,
            mass_bounds=mass_bounds, total_mass=total_mass, com_boxes=com_boxes, nonnegative=nonnegative,
            null_space_weight=null_space_weight, carried=carried,
            # see build_consistent_problem: noise scaling for the interior-point solver, data
            # scaling for the first-order one (same minimiser).
            objective_scale="noise" if solver == "CLARABEL" else "data")

    options = {**DEFAULT_SOLVER_OPTIONS[solver], **(solver_options or {})}
    if not (np.isfinite(epsilon) and epsilon >= 0.0):
        raise ValueError(f"epsilon: must be finite and >= 0, got {epsilon!r}")
    solve = _solve_checked(build, epsilon, solver, options, names, nonnegative, carried=carried)
    return _solution(solve, R, z, K, names, rss_outside, prior, prior_weight, solver, rows)


@dataclass(frozen=True)
class _CheckedSolve:
    """The last solve of the margin-retry loop and what it took."""

    built: ConsistentProblem
    chi: np.ndarray
    elapsed: float
    iterations: int | None
    report: ConsistencyReport
    retried: bool


def _shortfall(report: ConsistencyReport) -> float:
    """How far the solution is from the checked margin: the largest margin − eigenvalue or
    margin − prefixed parameter (≤ 0 when every one is above the margin)."""
    return max([report.margin - b.min_eigenvalue for b in report.bodies]
               + [report.margin - v for _, v, _ in report.nonnegative] + [0.0])


def _solve_checked(build: Callable[[float], ConsistentProblem], margin: float, solver: str,
                   options: Mapping[str, Any], names: tuple[str, ...],
                   nonnegative: Sequence[str], solve_margin: float | None = None,
                   carried: Mapping[str, np.ndarray] | None = None) -> _CheckedSolve:
    """Solve with ``solve_margin`` (default SOLVE_FACTOR × ``margin``), check against ``margin``,
    and re-solve with a larger solve margin while the check fails (at most ``_RETRY_ATTEMPTS``
    solves; see consistent_least_squares)."""
    retried = False
    solve_at = SOLVE_FACTOR * margin if solve_margin is None else max(solve_margin, margin)
    built = build(solve_at)
    chi, elapsed, iters = solve_problem(built, solver, options)
    report = consistency_report(chi, names, margin=margin, nonnegative=nonnegative, carried=carried)
    for attempt in range(1, _RETRY_ATTEMPTS):
        if report.ok:
            return _CheckedSolve(built, chi, elapsed, iters, report, retried)
        # Tighten by 10×, 100× the shortfall: the next solve lands at least that far inside,
        # unless the solver's own error grows with it (then the loop gives up and raises).
        solve_at += _RETRY_MARGIN_FACTOR**attempt * max(_shortfall(report), _SOLVER_ERROR)
        built = build(solve_at)
        chi, more_time, iters = solve_problem(built, solver, options)
        elapsed += more_time
        retried = True
        report = consistency_report(chi, names, margin=margin, nonnegative=nonnegative, carried=carried)
    if not report.ok:
        raise ConsistencyError(
            f"consistent least squares: solver {solver} returned 'optimal' but the solution fails the "
            f"external consistency check (margin {margin:.1e}) even when solved with margin {solve_at:.1e}: "
            f"{'; '.join(report.violations())}",
            status="external_check_failed",
            solver=solver,
        )
    return _CheckedSolve(built, chi, elapsed, iters, report, retried)


def _solution(solve: _CheckedSolve, R: np.ndarray, z: np.ndarray, K: np.ndarray, names: tuple[str, ...],
              rss_outside: float, prior: Mapping[str, float] | None, prior_weight: float, solver: str,
              rows: int | None) -> ConsistentSolution:
    """The frozen result: β = K χ, the full residual cost and the prior's cost."""
    chi = solve.chi
    beta = K @ chi
    chi.flags.writeable = False  # the result is frozen; keep its arrays read-only too
    beta.flags.writeable = False
    prior_cost = 0.0
    if prior:
        idx, ref = prior_indices(names, prior)
        prior_cost = float(prior_weight * np.sum((chi[idx] - ref) ** 2))
    return ConsistentSolution(
        names=names, chi=chi, beta=beta, cost=float(np.sum((R @ beta - z) ** 2) + rss_outside),
        prior_cost=prior_cost, solver=solver, status=str(solve.built.problem.status),
        solve_time=solve.elapsed, iterations=solve.iterations, epsilon=solve.built.epsilon,
        retried=solve.retried, rows=rows, report=solve.report)
