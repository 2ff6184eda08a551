"""Physical consistency of standard dynamic parameters, and consistent least squares.

Two things live here:

* the *check*: :func:`pseudo_inertia` and :func:`consistency_report`, plain numpy, used to
  ask "is this parameter vector something a real robot could have?";
* the *fit*: :func:`consistent_least_squares`, the least-squares identification of the base
  parameters rewritten over the standard parameters χ with the physical-consistency LMIs of
  Wensing, Kim & Slotine (2017), solved as a conic program through cvxpy.

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

Non-negativity rule (documented once, used by both the check and the fit): a parameter is
required to be ``≥ 0`` when its name *starts with* one of the given prefixes, default
``("IA", "FV", "FS")``. ``FVM6`` and ``FSM6`` therefore fall under ``FV`` and ``FS``; offsets
``OFFj`` and all inertial names are not affected (no inertial name starts with these prefixes).
"""

from __future__ import annotations

import re
import time
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp
import numpy as np

__all__ = [
    "INERTIAL_FIELDS",
    "BodyConsistency",
    "ConsistencyError",
    "ConsistencyReport",
    "ConsistentProblem",
    "ConsistentSolution",
    "body_indices",
    "build_consistent_problem",
    "consistency_report",
    "consistent_least_squares",
    "consistency_margin",
    "pseudo_inertia",
]

#: The ten inertial entries of one body, in the order of eq. 4 (and of the payload XXc..Mc).
INERTIAL_FIELDS: tuple[str, ...] = ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")

# A body is a link number or the payload suffix "c". The alternation lists two-letter fields
# first so that "MX1" is read as MX of link 1, never as M of a link called "X1".
_INERTIAL_NAME = re.compile(r"^(XX|XY|XZ|YY|YZ|ZZ|MX|MY|MZ|M)(\d+|c)$")

# Relative size of the automatic PSD/non-negativity margin used when a first solve comes back
# a hair outside the cone (interior-point feasibility tolerance is ~1e-8 relative).
_RETRY_MARGIN_FACTOR = 10.0
# Objective scale floor relative to ‖z‖² (noise-free data, or rss_outside not given).
_SCALE_FLOOR = 1e-10
# Default null-space tie-break (see build_consistent_problem): bounded, and a negligible fit cost.
_NULL_SPACE_WEIGHT = 1e-6
_RETRY_ATTEMPTS = 3  # solves in all: the requested one and at most two tightened ones

_SOLVERS = ("CLARABEL", "SCS")

# SCS is a first-order method: its default tolerances (1e-4) are far looser than a comparison
# with Clarabel can live with; 1e-7 is the tightest that converged on high signal-to-noise RX90
# data (1e-9 hit the iteration limit there). Its small cone violations are then handled by the
# external check and margin retry.
_DEFAULT_SOLVER_OPTIONS: dict[str, dict[str, Any]] = {
    "CLARABEL": {},
    "SCS": {"eps_abs": 1e-7, "eps_rel": 1e-7, "max_iters": 100_000},
}


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


def body_indices(names: Sequence[str]) -> dict[str, np.ndarray]:
    """Indices of the ten inertial parameters of every body present in ``names``.

    Returns:
        ``{body: indices (10,)}`` with body ``"1"``, ``"2"``, … for links (numeric order) and
        ``"c"`` for the payload (last); indices follow :data:`INERTIAL_FIELDS`.

    Raises:
        ValueError: a body has some but not all of its ten inertial parameters (a partial body
            cannot be checked and would silently escape the constraints), or a name repeats.
    """
    position: dict[str, int] = {}
    for i, name in enumerate(names):
        if name in position:
            raise ValueError(f"parameter names: {name!r} appears twice (positions {position[name]} and {i})")
        position[name] = i
    found: dict[str, dict[str, int]] = {}
    for name, i in position.items():
        match = _INERTIAL_NAME.match(name)
        if match:
            found.setdefault(match.group(2), {})[match.group(1)] = i
    out: dict[str, np.ndarray] = {}
    for body in sorted(found, key=lambda b: (b == "c", int(b) if b.isdigit() else 0)):
        fields = found[body]
        missing = [f + body for f in INERTIAL_FIELDS if f not in fields]
        if missing:
            raise ValueError(
                f"parameter names: body {body!r} has only some inertial parameters; missing {missing}"
            )
        out[body] = np.array([fields[f] for f in INERTIAL_FIELDS], dtype=int)
    return out


def _nonnegative_indices(names: Sequence[str], prefixes: Sequence[str]) -> np.ndarray:
    """Indices of names starting with any of ``prefixes`` (the documented prefix rule)."""
    prefixes = tuple(prefixes)
    if not prefixes:
        return np.zeros(0, dtype=int)
    return np.array([i for i, n in enumerate(names) if n.startswith(prefixes)], dtype=int)


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
        ok: ``min_eigenvalue ≥ −tol``.
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
        tol: tolerance used (same units as the quantities compared).
        ok: every body PSD within ``tol`` and every prefixed parameter ``≥ −tol``.
    """

    bodies: tuple[BodyConsistency, ...]
    nonnegative: tuple[tuple[str, float, bool], ...]
    tol: float
    ok: bool

    @property
    def min_eigenvalue(self) -> float:
        """Smallest pseudo-inertia eigenvalue over all bodies (inf when there is no body)."""
        return min((b.min_eigenvalue for b in self.bodies), default=float("inf"))

    def violations(self) -> tuple[str, ...]:
        """Human-readable list of what fails (empty when ``ok``)."""
        out = [f"body {b.body}: pseudo-inertia min eigenvalue {b.min_eigenvalue:.3e}" for b in self.bodies if not b.ok]
        out += [f"{name} = {value:.3e} < 0" for name, value, ok in self.nonnegative if not ok]
        return tuple(out)


def consistency_report(
    chi: Any,
    names: Sequence[str],
    tol: float = 1e-9,
    nonnegative: Sequence[str] = ("IA", "FV", "FS"),
) -> ConsistencyReport:
    """Check a standard parameter vector for physical consistency (numpy only).

    Args:
        chi: standard parameters, array ``(len(names),)`` in SI units, or a mapping name → value.
        names: their names (eq. 4 layout; payload ``XXc..Mc`` optional).
        tol: a body passes when its pseudo-inertia's smallest eigenvalue is ``≥ −tol``, a
            prefixed parameter when it is ``≥ −tol`` (absolute, SI units).
        nonnegative: name prefixes that must be non-negative (prefix rule, module docstring).

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
        p = x[idx]
        lam = float(np.linalg.eigvalsh(pseudo_inertia(p))[0])
        mass = float(p[9])
        com = tuple(float(v) for v in p[6:9] / mass) if mass > 0 else (float("nan"),) * 3
        bodies.append(BodyConsistency(body, lam, mass, com, lam >= -tol))  # type: ignore[arg-type]
    nonneg = tuple((names[i], float(x[i]), bool(x[i] >= -tol)) for i in _nonnegative_indices(names, nonnegative))
    ok = all(b.ok for b in bodies) and all(entry[2] for entry in nonneg)
    return ConsistencyReport(tuple(bodies), nonneg, float(tol), ok)


# ---------------------------------------------------------------------------------------------
# The fit
# ---------------------------------------------------------------------------------------------


class ConsistencyError(ValueError):
    """The consistent least-squares problem could not be solved to optimality.

    Attributes:
        status: cvxpy status string (``"infeasible"``, ``"optimal_inaccurate"``,
            ``"solver_error"``, …) or ``"external_check_failed"``.
        solver: solver name (``"CLARABEL"``, ``"SCS"``).
    """

    def __init__(self, message: str, *, status: str, solver: str) -> None:
        super().__init__(message)
        self.status = status
        self.solver = solver


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
        epsilon: margin imposed in the returned solve (≥ the requested ``epsilon``; larger when
            the automatic retry was needed, see :func:`consistent_least_squares`).
        retried: whether the automatic margin retry was used.
        rows: number of equations behind (R, z), when given.
        report: :func:`consistency_report` of ``chi`` (always ``ok``).
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


def _as_bounds(value: Any, what: str) -> tuple[float, float]:
    """(lo, hi) with None → ∓inf; ValueError naming ``what`` otherwise."""
    try:
        lo, hi = value
    except (TypeError, ValueError):
        raise ValueError(f"{what}: expected a pair (lo, hi), got {value!r}") from None
    lo = -np.inf if lo is None else float(lo)
    hi = np.inf if hi is None else float(hi)
    if np.isnan(lo) or np.isnan(hi):
        raise ValueError(f"{what}: NaN bound in {value!r}")
    return lo, hi


def _null_space(K: np.ndarray) -> np.ndarray:
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
    mass_bounds: Mapping[int | str, tuple[float | None, float | None]] | None = None,
    total_mass: tuple[float | None, float | None] | None = None,
    com_boxes: Mapping[int | str, tuple[Sequence[float], Sequence[float]]] | None = None,
    epsilon: float = 0.0,
    nonnegative: Sequence[str] = ("IA", "FV", "FS"),
    null_space_weight: float = _NULL_SPACE_WEIGHT,
    objective_scale: str = "noise",
) -> ConsistentProblem:
    """Build the conic problem behind :func:`consistent_least_squares` (same arguments).

    Formulation (one second-order cone + 4×4 LMIs, no quadratic objective)::

        minimise   (1/s_o)·‖ [ R K χ − z ;  √w·(χ_P − χ_prior) ;  √δ·s_n·Nᵀ(χ − χ_ref) ] ‖₂
        subject to J_b(χ) ⪰ ε·1₄ for every body b,  χ_i ≥ ε for prefixed names,
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
    if not (np.isfinite(epsilon) and epsilon >= 0.0):
        raise ValueError(f"epsilon: must be finite and >= 0, got {epsilon!r}")

    bodies = body_indices(names)
    if not (np.isfinite(rss_outside) and rss_outside >= 0.0):
        raise ValueError(f"rss_outside: must be finite and >= 0, got {rss_outside!r}")
    noise_scale = float(np.sqrt(max(rss_outside, _SCALE_FLOOR * float(z @ z))))
    if noise_scale == 0.0:
        noise_scale = 1.0  # zero data: any scale works, keep 1 to avoid dividing by zero
    if objective_scale == "noise":
        scale = noise_scale
    elif objective_scale == "data":
        scale = max(float(np.linalg.norm(z)), noise_scale)
    else:
        raise ValueError(f"objective_scale: expected 'noise' or 'data', got {objective_scale!r}")
    chi = cp.Variable(n_par, name="chi")
    residuals = [(R @ K / scale) @ chi - z / scale]

    if prior:
        if not (np.isfinite(prior_weight) and prior_weight > 0.0):
            raise ValueError(f"prior_weight: must be > 0 when a prior is given, got {prior_weight!r}")
        unknown = [n for n in prior if n not in names]
        if unknown:
            raise ValueError(f"prior: unknown parameter names {unknown}")
        idx = np.array([names.index(n) for n in prior], dtype=int)
        ref = np.array([float(prior[n]) for n in prior])
        if not np.all(np.isfinite(ref)):
            raise ValueError("prior: contains NaN or inf")
        residuals.append((np.sqrt(prior_weight) / scale) * (chi[idx] - ref))
    elif prior_weight != 0.0:
        raise ValueError("prior_weight: given without a prior (pass prior={name: value, ...})")
    if not (np.isfinite(null_space_weight) and null_space_weight >= 0.0):
        raise ValueError(f"null_space_weight: must be finite and >= 0, got {null_space_weight!r}")
    if null_space_weight > 0.0:
        # Directions of χ that K maps to 0 do not change the fit. Some are unbounded inside the
        # consistent set (e.g. XX1 + YY1 of a first link turning about a fixed axis can grow
        # without limit), and an interior-point solver then drifts along them (we saw
        # |χ| ≈ 4e4 on a 3-link arm). A small pull on the null-space coordinates ν only makes
        # the optimum unique and bounded. It leaves the fit alone when a consistent χ with the
        # OLS β exists at the pulled point; otherwise its cost is at most δ·s_n²·‖ν‖², i.e. a
        # fraction δ·‖ν‖² of the residual (measured on RX90 data at δ = 1e-6: ≤ 5e-5 of the
        # residual, while δ = 0 let unseen masses drift to 800 kg).
        null = _null_space(K)
        if null.shape[1]:
            ref = np.zeros(n_par)
            for name, value in (prior or {}).items():
                ref[names.index(name)] = float(value)
            weight = np.sqrt(null_space_weight) * noise_scale / scale
            residuals.append(weight * (null.T @ chi - null.T @ ref))
    objective = cp.norm(cp.hstack(residuals), 2)

    constraints: list[cp.Constraint] = []
    for idx in bodies.values():
        # J ⪰ ε·1: PSD ⇔ physically consistent incl. triangle inequalities (Wensing 2017).
        constraints.append(pseudo_inertia(chi[idx]) - epsilon * np.eye(4) >> 0)
    nonneg = _nonnegative_indices(names, nonnegative)
    if nonneg.size:
        constraints.append(chi[nonneg] >= epsilon)

    def body_of(key: int | str, what: str) -> np.ndarray:
        body = str(key)
        if body not in bodies:
            raise ValueError(f"{what}: no body {body!r} in the parameter names (bodies: {list(bodies)})")
        return bodies[body]

    for key, bounds in (mass_bounds or {}).items():
        lo, hi = _as_bounds(bounds, f"mass_bounds[{key!r}]")
        m = chi[body_of(key, "mass_bounds")[9]]
        if np.isfinite(lo):
            constraints.append(m >= lo)
        if np.isfinite(hi):
            constraints.append(m <= hi)
    if total_mass is not None:
        lo, hi = _as_bounds(total_mass, "total_mass")
        link_masses = [idx[9] for body, idx in bodies.items() if body.isdigit()]
        if not link_masses:
            raise ValueError("total_mass: no link inertial parameters in names")
        total = cp.sum(chi[np.array(link_masses)])
        if np.isfinite(lo):
            constraints.append(total >= lo)
        if np.isfinite(hi):
            constraints.append(total <= hi)
    for key, box in (com_boxes or {}).items():
        try:
            lo3, hi3 = (np.asarray(b, dtype=float).reshape(3) for b in box)
        except (TypeError, ValueError):
            raise ValueError(f"com_boxes[{key!r}]: expected (lo3, hi3), two triples in m, got {box!r}") from None
        idx = body_of(key, "com_boxes")
        h, m = chi[idx[6:9]], chi[idx[9]]
        # lo ≤ h/m ≤ hi written as m·lo ≤ h ≤ m·hi: linear, and equivalent because m ≥ 0 (J ⪰ 0).
        for axis in range(3):
            if np.isfinite(lo3[axis]):
                constraints.append(h[axis] >= lo3[axis] * m)
            if np.isfinite(hi3[axis]):
                constraints.append(h[axis] <= hi3[axis] * m)

    problem = cp.Problem(cp.Minimize(objective), constraints)
    return ConsistentProblem(problem, chi, names, scale, noise_scale, float(epsilon))


def _solve(built: ConsistentProblem, solver: str, options: Mapping[str, Any]) -> tuple[np.ndarray, float, int | None]:
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
    mass_bounds: Mapping[int | str, tuple[float | None, float | None]] | None = None,
    total_mass: tuple[float | None, float | None] | None = None,
    com_boxes: Mapping[int | str, tuple[Sequence[float], Sequence[float]]] | None = None,
    epsilon: float = 0.0,
    solver: str = "CLARABEL",
    nonnegative: Sequence[str] = ("IA", "FV", "FS"),
    solver_options: Mapping[str, Any] | None = None,
    tol: float = 1e-9,
    null_space_weight: float = _NULL_SPACE_WEIGHT,
) -> ConsistentSolution:
    """Physically consistent least squares over the standard parameters.

    Solves ``min ‖R K χ − z‖² (+ prior_weight·‖χ_P − χ_prior‖²)`` subject to every body's
    pseudo-inertia ``⪰ epsilon·1`` and the options below, where (R, z) is the QR-compressed
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
        epsilon: margin: ``J ⪰ ε·1`` and prefixed parameters ``≥ ε`` (ε > 0 gives strict
            consistency).
        solver: ``"CLARABEL"`` (default, interior point) or ``"SCS"`` (first order; run here with
            1e-7 tolerances and up to 1e5 iterations unless ``solver_options`` says otherwise;
            slower, and usually needs the margin retry below).
        nonnegative: name prefixes forced ``≥ epsilon`` (prefix rule, module docstring).
        solver_options: extra keyword arguments for ``cvxpy.Problem.solve``.
        tol: tolerance of the external :func:`consistency_report` check.
        null_space_weight: δ, weight of the tie-break ``δ·s_n²·‖Nᵀ(χ − χ_ref)‖²`` on the
            components ν of χ in the null space of K (χ_ref = prior values, 0 elsewhere), in
            residuals per SI unit². It picks one bounded χ among the many with the same β and
            costs at most a fraction δ·‖ν‖² of the residual; 0 disables it (the solver may
            then return huge values in directions the data do not see).

    Returns:
        :class:`ConsistentSolution` whose ``report.ok`` is always True.

    Raises:
        ConsistencyError: status other than optimal (infeasible bounds, inaccurate, solver
            error), or the external check still failing after the margin retry.
        ValueError: malformed input (shapes, names, bounds).

    Solver-tolerance handling: interior-point solvers meet the cone constraints only to their
    feasibility tolerance (~1e-8 relative), so a solution on the boundary (the usual case when
    the unconstrained estimate is inconsistent) can show a pseudo-inertia eigenvalue of, say,
    −3e-9. The returned χ is always re-checked with :func:`consistency_report` (``tol``). If the
    check fails, the problem is solved again with the margin (``J ⪰ ε·1``, prefixed parameters
    ``≥ ε``) raised by ``10·(worst violation + tol)``, then if needed by 100× the new
    violation; with Clarabel's tolerances that is ~1e-8, far below any physical resolution. If
    the third solve still fails the check, :class:`ConsistencyError` (status
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
    if solver not in _SOLVERS:
        raise ValueError(f"solver: expected one of {_SOLVERS}, got {solver!r}")
    if not (np.isfinite(rss_outside) and rss_outside >= 0.0):
        raise ValueError(f"rss_outside: must be finite and >= 0, got {rss_outside!r}")
    options = {**_DEFAULT_SOLVER_OPTIONS[solver], **(solver_options or {})}
    kwargs = dict(
        rss_outside=rss_outside,
        prior=prior,
        prior_weight=prior_weight,
        mass_bounds=mass_bounds,
        total_mass=total_mass,
        com_boxes=com_boxes,
        nonnegative=nonnegative,
        null_space_weight=null_space_weight,
        # see build_consistent_problem: noise scaling for the interior-point solver, data
        # scaling for the first-order one (same minimiser).
        objective_scale="noise" if solver == "CLARABEL" else "data",
    )
    names = tuple(names)
    R = np.asarray(R, dtype=float)
    z = np.asarray(z, dtype=float).reshape(-1)
    K = np.asarray(K, dtype=float)

    built = build_consistent_problem(R, z, K, names, epsilon=epsilon, **kwargs)
    chi, elapsed, iters = _solve(built, solver, options)
    report = consistency_report(chi, names, tol=tol, nonnegative=nonnegative)
    retried = False
    margin = float(epsilon)
    for attempt in range(1, _RETRY_ATTEMPTS + 1):
        if report.ok:
            break
        if attempt == _RETRY_ATTEMPTS:
            raise ConsistencyError(
                f"consistent least squares: solver {solver} returned 'optimal' but the solution fails the "
                f"external consistency check (tol {tol:.0e}) even with margin {margin:.1e}: "
                f"{'; '.join(report.violations())}",
                status="external_check_failed",
                solver=solver,
            )
        worst = max([-b.min_eigenvalue for b in report.bodies] + [-v for _, v, _ in report.nonnegative] + [0.0])
        # Tighten by 10×, 100× the violation: the next solve lands at least that far inside,
        # unless the solver's own error grows with it (then the loop gives up and raises).
        margin += _RETRY_MARGIN_FACTOR**attempt * (worst + tol)
        built = build_consistent_problem(R, z, K, names, epsilon=margin, **kwargs)
        chi, more_time, iters = _solve(built, solver, options)
        elapsed += more_time
        retried = True
        report = consistency_report(chi, names, tol=tol, nonnegative=nonnegative)

    beta = K @ chi
    chi.flags.writeable = False  # the result is frozen; keep its arrays read-only too
    beta.flags.writeable = False
    cost = float(np.sum((R @ beta - z) ** 2) + rss_outside)
    prior_cost = 0.0
    if prior:
        ref = np.array([prior[n] for n in prior], dtype=float)
        idx = np.array([names.index(n) for n in prior], dtype=int)
        prior_cost = float(prior_weight * np.sum((chi[idx] - ref) ** 2))
    return ConsistentSolution(
        names=names,
        chi=chi,
        beta=beta,
        cost=cost,
        prior_cost=prior_cost,
        solver=solver,
        status=str(built.problem.status),
        solve_time=elapsed,
        iterations=iters,
        epsilon=built.epsilon,
        retried=retried,
        rows=rows,
        report=report,
    )



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

    (tie-break: the smallest null-space component, weight 1e-8, only to keep χ bounded); when
    t* > 0 a second solve returns the smallest witness χ with margin t*/2.

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
    if solver not in _SOLVERS:
        raise ValueError(f"solver: expected one of {_SOLVERS}, got {solver!r}")
    # Rows scaled to unit norm so the equality tolerance is relative to each base parameter.
    row_scale = np.maximum(np.linalg.norm(K, axis=1), np.finfo(float).tiny)
    chi = cp.Variable(len(names), name="chi")
    t = cp.Variable(name="t")
    constraints: list[cp.Constraint] = [(K / row_scale[:, None]) @ chi == beta / row_scale, t <= cap]
    for idx in body_indices(names).values():
        constraints.append(pseudo_inertia(chi[idx]) - t * np.eye(4) >> 0)
    nonneg = _nonnegative_indices(names, nonnegative)
    if nonneg.size:
        constraints.append(chi[nonneg] >= t)
    null = _null_space(K)
    spread = cp.norm(null.T @ chi, 2) if null.shape[1] else cp.Constant(0.0)
    options = _DEFAULT_SOLVER_OPTIONS[solver]
    built = ConsistentProblem(cp.Problem(cp.Maximize(t - 1e-8 * spread), constraints), chi, names, 1.0, 1.0, 0.0)
    value, _, _ = _solve(built, solver, options)
    margin = float(t.value)
    if margin > 0 and null.shape[1]:
        # Maximising t leaves the bodies that do not limit it wherever the solver drifted (we
        # saw |χ| ≈ 2e3): re-solve for the smallest witness keeping half the margin.
        constraints.append(t == margin / 2)
        built = ConsistentProblem(cp.Problem(cp.Minimize(spread), constraints), chi, names, 1.0, 1.0, 0.0)
        value, _, _ = _solve(built, solver, options)
    return margin, value
