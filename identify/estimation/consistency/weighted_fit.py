"""The model weighed between the description and the data: min ‖W β − Y‖²_w + λ·D(θ ‖ θ₀) over physical θ.

The fit's columns β (base parameters, torque offsets, the friction forms' extra columns) are a linear
map of the variables x = [θ ; e]: β = A x, θ the standard parameters (eq. 4; β_base = K θ), e the
columns that are not standard parameters (torque offsets OFFj, Stribeck levels FSTj, presliding
magnitudes FPj, spring coefficients), each its own variable (:func:`column_map`). On the weighted
compressed system (R, z) of eqs. 9-11 (each joint's rows weighted by 1/σ_j) the model solves

    minimise   ‖R A x − z‖² + λ·D(θ ‖ θ₀) + δ·‖T⁻¹ (x − x_ref)‖²
    subject to J_b(θ) − J(carried_b) ⪰ ε·1 for every link, IA, FV, FS ≥ ε     (Wensing et al. 2017)

with D the prior's divergence (:mod:`identify.estimation.consistency.body_prior`), λ ≥ 0 its
weight (λ = ∞: the informed links' bodies are the description's, the rest fitted), and a tie-break
δ = :data:`TIE_BREAK` on every variable in units of its typical size T (x_ref: the prior's bodies,
0 elsewhere) so that a direction neither the data nor the prior determine has one answer. The
objective is divided by the weighted residual of the least-squares fit, so the solver sees numbers
of order one whatever the log's length.

One :class:`PriorProblem` is compiled once (cvxpy parameters: the data, λ) and solved for every fold
and weight of the cross-validation (:mod:`identify.selection.prior_weight`).
"""
from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import cvxpy as cp
import numpy as np

import rx90sym
from rx90sym.physical import DEFAULT_MARGIN, INERTIAL_FIELDS, NONNEGATIVE

from identify.estimation.consistency.body_prior import BodyPrior
from identify.estimation.consistency.errors import ConsistencyError
from identify.estimation.consistency.problem import DEFAULT_SOLVER_OPTIONS, _cone_constraints
from identify.estimation.consistency.lmi import body_indices, consistency_report

__all__ = ["ColumnMap", "PriorProblem", "TIE_BREAK", "column_map"]

#: Weight of the tie-break (module docstring), relative to the data term's curvature of one
#: residual variance per typical size.
TIE_BREAK = 1e-6
#: Typical sizes T of a variable by kind [SI] where no prior body gives one (a 1 kg link of 0.1 m).
TYPICAL = {"M": 1.0, "MX": 0.1, "XX": 0.01, "IA": 0.01, "FS": 1.0, "FV": 1.0, "OFF": 1.0}
#: The solver is asked for this many times the margin it is checked against (as the consistent fit).
SOLVE_FACTOR = 10.0


@dataclass(frozen=True)
class ColumnMap:
    """β = A x: A (c, p), the fit's column names (c), the variables' names (p: the robot's standard
    parameters, then the columns that are not standard parameters)."""

    A: np.ndarray
    columns: tuple[str, ...]
    names: tuple[str, ...]
    standard: int

    def beta(self, x: np.ndarray) -> np.ndarray:
        return self.A @ np.asarray(x, dtype=float)


def _base_of(columns: Any) -> Any:
    """The base parameters (with K) inside wrapped columns (offsets, friction forms, spring)."""
    inner = columns
    while not hasattr(inner, "K"):
        if not hasattr(inner, "base"):
            raise ValueError(f"columns {type(columns).__name__}: no base parameters (K) inside")
        inner = inner.base
    return inner


def column_map(robot: rx90sym.Robot, columns: Any, fitted: Sequence[str] | None = None) -> ColumnMap:
    """The :class:`ColumnMap` of a fit's ``columns`` (base parameters, possibly wrapped by torque
    offsets, friction forms or a spring: their own columns come after the base parameters');
    ``fitted``: the columns the fit kept, when fewer (their rows of A)."""
    base = _base_of(columns)
    inner, names = tuple(base.names), tuple(columns.names)
    if names[:len(inner)] != inner:
        raise ValueError("the fit's columns do not start with the base parameters")
    extras = names[len(inner):]
    standard = tuple(robot.parameter_names)
    clash = sorted(set(extras) & set(standard))
    if clash:
        raise ValueError(f"columns {clash} are both standard parameters and extra columns")
    A = np.zeros((len(names), len(standard) + len(extras)))
    A[:len(inner), :len(standard)] = np.asarray(base.K, dtype=float)
    A[len(inner):, len(standard):] = np.eye(len(extras))
    if fitted is not None and tuple(fitted) != names:
        rows = [names.index(n) for n in fitted]
        A, names = A[rows], tuple(fitted)
    return ColumnMap(A, names, standard + extras, len(standard))


def _typical(names: Sequence[str], prior: BodyPrior | None) -> np.ndarray:
    """T of every variable: the prior's scale where it has one, :data:`TYPICAL` by kind elsewhere."""
    out = np.ones(len(names))
    for i, name in enumerate(names):
        if prior is not None and name in prior.scales:
            out[i] = prior.scales[name]
            continue
        kind = name.rstrip("0123456789c")
        kind = {"MY": "MX", "MZ": "MX", "XY": "XX", "XZ": "XX", "YY": "XX", "YZ": "XX", "ZZ": "XX"}.get(kind, kind)
        out[i] = TYPICAL.get(kind, TYPICAL.get(kind[:2], 1.0))
    return out


def _off_determined(determined: np.ndarray | None, informed: np.ndarray, scales: np.ndarray) -> np.ndarray:
    """(m, k) rows of an orthonormal basis of the prior's scaled deviations u = (x_I - θ0) / s that leave every
    determined base parameter unchanged (the orthogonal complement of their directions a_i,I s): what the
    prior may weigh. The identity without determined parameters."""
    k = informed.size
    if determined is None or determined.size == 0 or k == 0:
        return np.eye(k)
    B = (np.asarray(determined, dtype=float)[:, informed] * scales).T
    B = B[:, np.any(B != 0.0, axis=0)]
    if B.size == 0:
        return np.eye(k)
    U, sv, _ = np.linalg.svd(B, full_matrices=True)
    rank = int(np.sum(sv > sv[0] * 1e-10))
    return U[:, rank:].T


class PriorProblem:
    """The compiled problem of the module docstring for one set of variables and one prior.

    cmap: the columns; prior: the description's bodies (None: the data alone, the tie-break toward
    0); fixed: λ = ∞ (the prior's directions held at its values; λ unused); carried: what links carry
    that an export writes apart (the consistent fit's ``carried``); reference: x_ref beyond the prior
    (e.g. the description's rotor inertias), name -> value; determined: rows (k, p) of the base
    parameters the data determine (β_i = a_i x): a Gaussian prior leaves their directions to the data
    (it penalises the prior's scaled deviation only orthogonally to them), so that no weight lets the
    description override what the data determine; held: variables held at a value (name -> value: the
    friction and rotor inertia of a joint that never moves in the fitted rows, which neither the data
    nor the description give).
    """

    def __init__(self, cmap: ColumnMap, prior: BodyPrior | None, *, fixed: bool = False,
                 carried: Mapping[str, np.ndarray] | None = None, margin: float = DEFAULT_MARGIN,
                 nonnegative: Sequence[str] = NONNEGATIVE, reference: Mapping[str, float] | None = None,
                 solver: str = "CLARABEL", solve_margin: float | None = None, bounds: Sequence[Any] = (),
                 determined: np.ndarray | None = None, held: Mapping[str, float] | None = None) -> None:
        self.cmap, self.prior, self.fixed, self.margin = cmap, prior, fixed and prior is not None, margin
        self.solve_margin = SOLVE_FACTOR * margin if solve_margin is None else float(solve_margin)
        self.carried, self.nonnegative, self.solver = carried, tuple(nonnegative), solver.upper()
        names = cmap.names
        p, c = len(names), len(cmap.columns)
        index = {n: i for i, n in enumerate(names)}
        self.ref = np.array([(prior.values.get(n) if prior is not None else None) or (reference or {}).get(n, 0.0)
                             for n in names])
        self.typical = _typical(names, prior)
        self.data = cp.Parameter((c, p), name="data")      # R A / sqrt(scale)
        self.target = cp.Parameter(c, name="target")       # z / sqrt(scale)
        self.weight = cp.Parameter(nonneg=True, name="weight")  # λ / scale
        self.x = cp.Variable(p, name="x")
        objective = cp.sum_squares(self.data @ self.x - self.target)
        objective += TIE_BREAK * cp.sum_squares(cp.multiply(1.0 / self.typical, self.x - self.ref))
        constraints = _cone_constraints(self.x[:cmap.standard], names[:cmap.standard],
                                        body_indices(names[:cmap.standard]), self.solve_margin,
                                        self.nonnegative, carried)
        for build in bounds:
            constraints += build(self.x)
        extra_nonneg = [i for i in range(cmap.standard, p) if names[i].startswith(self.nonnegative)]
        if extra_nonneg:
            constraints.append(self.x[np.array(extra_nonneg)] >= self.solve_margin)
        # Variables the data cannot see and no prior gives (a still joint's friction): held at a value.
        held = {n: v for n, v in (held or {}).items() if n in index}
        self.held = np.array([index[n] for n in held], dtype=int)
        self.held_values = np.array([max(float(held[n]), self.solve_margin) if n.startswith(self.nonnegative)
                                     else float(held[n]) for n in held])
        if self.held.size:
            constraints.append(self.x[self.held] == self.held_values)
        # The prior as a quadratic form on the informed variables' scaled deviation u = (x_I - θ0) / s: its rows
        # G (Gaussian: u projected off the directions the data determine; G u = 0 at λ = ∞).
        self.informed = np.array([index[n] for n in prior.names()], dtype=int) if prior is not None else np.zeros(0, int)
        self.gram = np.zeros((0, p))
        if prior is not None and prior.divergence == "gaussian":
            scales = np.array([prior.scales[n] for n in prior.names()])
            P = _off_determined(determined, self.informed, scales)
            self.gram = np.zeros((P.shape[0], p))
            self.gram[:, self.informed] = P / scales
        if prior is not None and self.fixed:
            theta0 = self.ref[self.informed]
            if prior.divergence == "gaussian":
                constraints.append(self.gram[:, self.informed] @ (self.x[self.informed] - theta0) == 0)
            else:
                constraints.append(self.x[self.informed] == theta0)
        elif prior is not None:
            prior_term = (cp.sum_squares(self.gram @ (self.x - self.ref)) if prior.divergence == "gaussian"
                          else prior.expression(self.x, index))
            objective += self.weight * prior_term
        self.problem = cp.Problem(cp.Minimize(objective), constraints)
        # The objective is quadratic (a Gaussian prior, or none) and, without bounds, its minimiser without the
        # physical constraints solves the problem whenever it is physical: a linear solve, not the conic solver.
        self.quadratic = (prior is None or prior.divergence == "gaussian") and not bounds
        self.extra_nonneg = np.array(extra_nonneg, dtype=int)

    def _unconstrained(self, M: np.ndarray, t: np.ndarray, w: float) -> np.ndarray:
        """The minimiser of the quadratic objective without the physical constraints (module docstring); at
        λ = ∞ under the prior's equality (G (x - x_ref) = 0), by its KKT system."""
        tie = TIE_BREAK / self.typical ** 2
        G = self.gram
        H = M.T @ M + np.diag(tie) + (0.0 if self.fixed else w) * G.T @ G
        b = M.T @ t + tie * self.ref + (0.0 if self.fixed else w) * G.T @ (G @ self.ref)
        # Equalities C x = d: the held variables, and at λ = ∞ the prior's (KKT system).
        p = H.shape[0]
        C = np.zeros((self.held.size, p))
        C[np.arange(self.held.size), self.held] = 1.0
        d = self.held_values.copy()
        if self.fixed and G.shape[0]:
            C, d = np.vstack([C, G]), np.r_[d, G @ self.ref]
        if C.shape[0] == 0:
            return np.linalg.solve(H, b)
        kkt = np.block([[H, C.T], [C, np.zeros((C.shape[0], C.shape[0]))]])
        return np.linalg.lstsq(kkt, np.r_[b, d], rcond=None)[0][:p]

    def prior_term(self, x: np.ndarray) -> float:
        """The prior's term of the objective at ``x`` without its weight: D(θ ‖ θ0), for the Gaussian the
        squared scaled deviation off the directions the data determine (0 at λ = ∞)."""
        if self.prior is None:
            return 0.0
        if self.prior.divergence == "gaussian":
            return float(np.sum((self.gram @ (np.asarray(x) - self.ref)) ** 2))
        return self.prior.value(dict(zip(self.cmap.names, x)))

    def prior_precision(self, weight: float) -> np.ndarray:
        """(p, p) the prior's curvature at λ = ``weight`` in the cost ‖·‖² + λ D (Gaussian: λ GᵀG; the
        log-det divergence: λ/2 times its Hessian at θ0); zero without a prior."""
        p = len(self.cmap.names)
        if self.prior is None:
            return np.zeros((p, p))
        if self.prior.divergence == "gaussian":
            return weight * self.gram.T @ self.gram
        return 0.5 * weight * self.prior.hessian(self.cmap.names)

    def _physical(self, x: np.ndarray) -> bool:
        """Whether ``x`` meets the constraints at the solve's margin."""
        names = self.cmap.names[:self.cmap.standard]
        report = consistency_report(x[:self.cmap.standard], names, margin=self.solve_margin,
                                    nonnegative=self.nonnegative, carried=self.carried)
        return report.ok and bool(np.all(x[self.extra_nonneg] >= self.solve_margin))

    def solve(self, R: np.ndarray, z: np.ndarray, weight: float, scale: float) -> np.ndarray:
        """x of the system ‖R β − z‖² (R: (k, c) on the fit's columns) at λ = ``weight``, the
        objective divided by ``scale`` (> 0); raises ConsistencyError when the solver fails."""
        M = (np.asarray(R, dtype=float) @ self.cmap.A) / np.sqrt(scale)
        t = np.asarray(z, dtype=float) / np.sqrt(scale)
        w = 0.0 if self.fixed or not np.isfinite(weight) else float(weight) / scale
        if self.quadratic:
            x = self._unconstrained(M, t, w)
            if self._physical(x):
                return x
        self.data.value, self.target.value, self.weight.value = M, t, w
        options = DEFAULT_SOLVER_OPTIONS.get(self.solver, {})
        try:
            with warnings.catch_warnings():
                # cvxpy warns "Solution may be inaccurate": the external check judges the solution instead.
                warnings.filterwarnings("ignore", message="Solution may be inaccurate", category=UserWarning)
                self.problem.solve(solver=self.solver, **options)
        except cp.error.SolverError as exc:
            raise ConsistencyError(f"the prior-weighted fit: solver {self.solver} failed: {exc}",
                                   status="solver_error", solver=self.solver) from exc
        # An inaccurate optimum is used (the external check decides whether it is physical), not a failure.
        if self.problem.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE) or self.x.value is None:
            raise ConsistencyError(f"the prior-weighted fit: solver {self.solver} returned status "
                                   f"{self.problem.status!r} (λ = {weight:g})", status=str(self.problem.status),
                                   solver=self.solver)
        return np.array(self.x.value, dtype=float)

    def check(self, x: np.ndarray) -> Any:
        """The external consistency check of a solution at the margin (rx90sym.physical)."""
        names = self.cmap.names[:self.cmap.standard]
        return consistency_report(np.asarray(x)[:self.cmap.standard], names, margin=self.margin,
                                  nonnegative=self.nonnegative, carried=self.carried)
