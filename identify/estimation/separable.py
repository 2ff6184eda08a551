"""Separable least squares for friction nonlinear in a velocity scale (variable projection).

The smooth Coulomb FS·tanh(q̇/vs) and Stribeck (FS + (FST − FS)·exp(−(q̇/vs)²))·sign(q̇)
(identify.observation.friction) are linear in every parameter but the joint's velocity scale vs
[rad/s]. For given scales the linear parameters β are the least-squares solution (eq. 10); the
scales minimise the projected cost F(s) = ½‖D(Y − W(s)·β̂(s))‖² (Golub & Pereyra): the
gradient needs only ∂W/∂s at β̂ (β̂ optimal), CasADi's derivative of the form
(identify.observation.friction.friction_columns; tanh's evaluated in NumPy). D holds the paper's per-joint weights (eq. 11) of a first fit.

Procedure (:func:`velocity_scales`): one observation matrix whose Coulomb columns hold the
filtered, decimated driver speed v of every row (``FrictionBase`` form "probe"); a scan of a
common scale over a log grid gives each joint its start (the joint's own residual); L-BFGS-B in
log s, bounded to :data:`SCALE_BOUNDS` (the lower bound raised to half the 2nd percentile of the
joint's speeds: below it a column fits a handful of rows), refines all scales together. σ of each
scale: the Gauss-Newton covariance σ²(JᵀJ)⁻¹ of the weighted residual in (β, s), σ² its variance.
The columns are evaluated on the decimated speed (f(Dv) for the parallel-filtered D·f(v): equal
where the speed changes slowly over the decimation filter, i.e. for vs above the speed change in
a few decimated periods); the fit itself then uses the exact parallel-filtered columns.

The presliding travel δ per joint (:func:`presliding_travels`) is separable the same way: the
magnitude FPj is linear, δ_j one of :data:`TRAVEL_CANDIDATES`, chosen by coordinate descent on the
projected cost (z is piecewise linear in 1/δ: a grid, not a gradient).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, Sequence

import numpy as np
from scipy.optimize import minimize

import rx90sym
from identify.estimation.least_squares import weighted_least_squares
from identify.observation.friction import friction_columns
from identify.observation.friction_model import PRESLIDING_PREFIX, FrictionBase, friction_probe
from identify.observation.matrix import Observation, observation_matrix

__all__ = ["SCALE_BOUNDS", "TRAVEL_CANDIDATES", "PreslidingTravels", "VelocityScales", "presliding_travels",
           "velocity_scales", "scales_from_observation"]

#: Velocity scales searched [rad/s]: below 1e-4 the form is sign(q̇) on any logged speed; above
#: 2 rad/s it is a second viscous term on the speeds of an arm.
SCALE_BOUNDS = (1e-4, 2.0)
_GRID = np.geomspace(1e-3, 1.0, 13)
#: Share of a joint's moving rows that must lie below its velocity scale (see _log_bounds).
LOW_SPEED_SHARE = 0.02


@dataclass(frozen=True)
class VelocityScales:
    """Velocity scale per joint of a smooth friction form: form (one, or one per joint); scales,
    std (n,) [rad/s] (nan for a joint without a Coulomb term or of the Coulomb form); at_bound (n,): the search stopped on a bound of
    :data:`SCALE_BOUNDS` (the data prefer a sign, or a viscous term); cost: the weighted cost F;
    converged: the search reported success."""

    form: str | tuple[str, ...]
    scales: tuple[float, ...]
    std: tuple[float, ...]
    at_bound: tuple[bool, ...]
    cost: float
    converged: bool = True       # the L-BFGS-B search reported success

    def to_json(self) -> dict[str, Any]:
        def num(v: float) -> float | None:
            return float(v) if np.isfinite(v) else None

        return {"form": self.form if isinstance(self.form, str) else list(self.form), "velocity_scale": [num(v) for v in self.scales],
                "velocity_scale_std": [num(v) for v in self.std], "at_bound": list(self.at_bound),
                "converged": self.converged}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> "VelocityScales":
        def num(v: float | None) -> float:
            return float("nan") if v is None else float(v)

        form = d["form"] if isinstance(d["form"], str) else tuple(str(f) for f in d["form"])
        return cls(form, tuple(num(v) for v in d["velocity_scale"]),
                   tuple(num(v) for v in d["velocity_scale_std"]), tuple(bool(b) for b in d.get("at_bound", ())),
                   float("nan"), bool(d.get("converged", True)))

    def summary(self) -> str:
        per_joint = not isinstance(self.form, str)
        cells = [f"j{j + 1} {self.form[j] + ' ' if per_joint else ''}{s:.4g} ± {d:.2g}{' (bound)' if b else ''}"
                 for j, (s, d, b) in enumerate(zip(self.scales, self.std, self.at_bound)) if np.isfinite(s)]
        coulomb = [f"j{j + 1}" for j, f in enumerate(self.form) if f == "coulomb"] if per_joint else []
        head = "friction per joint" if per_joint else f"friction {self.form}"
        return (f"{head}: velocity scale [rad/s] " + ", ".join(cells)
                + (f"; coulomb (no scale): {', '.join(coulomb)}" if coulomb else ""))


@dataclass(frozen=True, eq=False)
class _Problem:
    """The probe observation split for the search. Columns that do not depend on the scales
    (``fixed``) are projected out once (thin QR: Q of D·W_fixed), so each cost evaluation solves
    only for the friction columns (``varying``: the Coulomb columns, then FST's for Stribeck).

    W, Y: the probe system (a Coulomb-form joint's column holding sign(v): fixed); d (r,): row
    weights; joints: joints of a smooth form (their scales searched); entries: per joint (rows,
    column index in ``varying`` order, speeds v) of its Coulomb entries; forms: per joint of
    ``joints`` its form."""

    W: np.ndarray
    Y: np.ndarray
    d: np.ndarray
    joints: tuple[int, ...]
    entries: dict[int, list[tuple[np.ndarray, int, np.ndarray]]]
    forms: dict[int, str]
    fixed: np.ndarray
    varying: np.ndarray

    @cached_property
    def Q(self) -> np.ndarray:
        """Orthonormal basis of the weighted fixed columns (thin QR)."""
        return np.linalg.qr(self.W[:, self.fixed] * self.d[:, None])[0]

    @cached_property
    def b_perp(self) -> np.ndarray:
        b = self.Y * self.d
        return b - self.Q @ (self.Q.T @ b)

    @classmethod
    def build(cls, obs: Observation, terms: Sequence[Any], form: str | Sequence[str],
              weights: np.ndarray) -> "_Problem":
        """``form``: one smooth form, or one form per joint (a Coulomb joint's column is sign(v), no scale)."""
        form_of = (lambda j: form) if isinstance(form, str) else (lambda j: form[j])
        W = obs.W
        signs = [t for t in terms if form_of(t.row) not in ("tanh", "stribeck")]
        if signs:   # the Coulomb joints' columns do not depend on the scales: sign(v), with the fixed ones
            W = obs.W.copy()
            for t in signs:
                rows = np.flatnonzero(obs.joint == t.row)
                W[rows, t.column] = np.sign(obs.W[rows, t.column])
        smooth = [t for t in terms if t not in signs]
        coulomb = sorted({t.column for t in smooth})
        entries: dict[int, list] = {}
        for term in smooth:
            rows = np.flatnonzero(obs.joint == term.row)
            entries.setdefault(term.row, []).append((rows, coulomb.index(term.column),
                                                     obs.W[rows, term.column].copy()))
        fixed = np.array([c for c in range(obs.W.shape[1]) if c not in coulomb], dtype=int)
        return cls(W, obs.Y, np.asarray(weights, dtype=float)[obs.joint], tuple(sorted(entries)), entries,
                   {j: form_of(j) for j in entries}, fixed, np.array(coulomb, dtype=int))

    def columns(self, s: np.ndarray) -> tuple[np.ndarray, list[list[tuple[np.ndarray, int, np.ndarray]]]]:
        """Weighted friction columns (r, m: Coulomb's, then FST's for Stribeck) at the scales s and
        per joint the pieces of their derivative: (rows, column, D·∂column/∂s_j)."""
        m = len(self.varying)
        stribeck = [j for j in self.joints if self.forms[j] == "stribeck"]   # FST's columns, after Coulomb's
        A = np.zeros((self.W.shape[0], m + len(stribeck)))
        parts = []
        for k, j in enumerate(self.joints):
            part = []
            for rows, col, v in self.entries[j]:
                cols, dcols = friction_columns(self.forms[j], v, float(s[k]))
                d = self.d[rows]
                A[rows, col] = cols[:, 0] * d
                part.append((rows, col, dcols[:, 0] * d))
                if j in stribeck:
                    extra = m + stribeck.index(j)
                    A[rows, extra] = cols[:, 1] * d
                    part.append((rows, extra, dcols[:, 1] * d))
            parts.append(part)
        return A, parts

    def solve(self, s: np.ndarray) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
        """(cost, weighted residual, weighted friction columns, ∂(D·W·β̂)/∂s (r, joints)) at s."""
        A, parts = self.columns(s)
        A_perp = A - self.Q @ (self.Q.T @ A)
        gamma = np.linalg.lstsq(A_perp, self.b_perp, rcond=None)[0]
        r = self.b_perp - A_perp @ gamma     # the whole residual: the fixed columns are projected out
        ds = np.zeros((A.shape[0], len(parts)))
        for k, part in enumerate(parts):
            for rows, col, dcol in part:
                ds[rows, k] += dcol * gamma[col]
        return 0.5 * float(r @ r), r, A, ds


def _log_bounds(prob: _Problem) -> tuple[np.ndarray, np.ndarray]:
    """log bounds of each joint's scale: :data:`SCALE_BOUNDS`, the lower one raised to half the
    :data:`LOW_SPEED_SHARE` quantile of the joint's moving speeds: below it the low-speed
    zone (|v| < 2 vs) holds a handful of rows and its column fits their noise (e.g. the rows where the
    filtered speed has the wrong sign around a reversal), not a friction law."""
    lo = []
    for j in prob.joints:
        v = np.abs(np.concatenate([e[2] for e in prob.entries[j]]))
        v = v[v > 0]
        # The form departs from sign(v) up to about 2 vs: that zone must hold the share of rows.
        lo.append(max(SCALE_BOUNDS[0], float(np.quantile(v, LOW_SPEED_SHARE)) / 2 if v.size else 0.0))
    lo = np.minimum(np.array(lo), SCALE_BOUNDS[1] / 10)
    return np.log(lo), np.full(len(lo), np.log(SCALE_BOUNDS[1]))


def scales_from_observation(obs: Observation, terms: Sequence[Any], form: str | Sequence[str],
                            n: int, std: bool = True) -> VelocityScales:
    """The velocity scales of ``form`` (one smooth form, or one form per joint: only the smooth
    joints' scales are searched, a Coulomb joint keeps sign(v)) from a probe observation (Coulomb
    columns = driver speed); ``std`` False: their σ left NaN (the friction choice's folds use the
    scales only)."""
    form = form if isinstance(form, str) else tuple(form)
    if not any((form if isinstance(form, str) else form[t.row]) in ("tanh", "stribeck") for t in terms):
        raise ValueError(f"friction form {form!r}: no joint with a Coulomb term has a velocity scale to search")
    # Eq. 11's weights from a first fit at a middle scale (the probe's own columns are speeds,
    # collinear with the viscous ones).
    plain = _Problem.build(obs, terms, form, np.ones(n))
    A, _ = plain.columns(np.full(len(plain.joints), _GRID[len(_GRID) // 2]))
    W = np.hstack([plain.W[:, plain.fixed], A])
    first = weighted_least_squares(W, obs.Y, obs.joint, [f"c{k}" for k in range(W.shape[1])])
    prob = _Problem.build(obs, terms, form, first.weights)
    lo, hi = _log_bounds(prob)
    # Start: a common scale over the grid, each joint taking the one its own rows prefer.
    per_joint = []
    for s in _GRID:
        r = prob.solve(np.full(len(prob.joints), s))[1]
        per_joint.append([float(r[obs.joint == j] @ r[obs.joint == j]) for j in prob.joints])
    u0 = np.clip(np.log(_GRID[np.argmin(np.array(per_joint), axis=0)]), lo, hi)

    def cost(u: np.ndarray) -> tuple[float, np.ndarray]:
        s = np.exp(u)
        f, r, _, ds = prob.solve(s)
        # Variable projection: dF/ds_j = −rᵀ ∂(DW)/∂s_j β̂ (β̂ optimal); in log s times s_j.
        return f, -(r @ ds) * s

    best = minimize(cost, u0, jac=True, method="L-BFGS-B", bounds=list(zip(lo, hi)))
    s = np.exp(best.x)
    f, r, A, ds = prob.solve(s)
    sigma = np.full(len(s), np.nan)
    if std:
        J = np.hstack([prob.W[:, prob.fixed] * prob.d[:, None], A, ds])   # ∂(D·model)/∂(β, s): Gauss-Newton
        dof = max(1, J.shape[0] - J.shape[1])
        cov = (r @ r) / dof * np.linalg.pinv(J.T @ J)
        sigma = np.sqrt(np.maximum(np.diag(cov)[-len(s):], 0.0))
    out_s, out_std, out_b = np.full(n, np.nan), np.full(n, np.nan), [False] * n
    for k, j in enumerate(prob.joints):
        out_s[j], out_std[j] = s[k], sigma[k]
        out_b[j] = bool(min(best.x[k] - lo[k], hi[k] - best.x[k]) < 1e-3)
    return VelocityScales(form, tuple(out_s), tuple(out_std), tuple(out_b), f, bool(best.success))


def velocity_scales(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any, form: str | Sequence[str],
                    **options: Any) -> VelocityScales:
    """The velocity scale per joint of the smooth friction ``form`` ("tanh" | "stribeck", or one
    form per joint, "coulomb" on the joints without a scale) on
    ``recordings`` with the base columns ``base`` and the observation ``options`` of the fit
    (cutoff, decimate_to, min_velocity, rest, spring, delay: :func:`identify.observation_matrix`)."""
    base = base if base is not None else rx90sym.base_parameters(robot)
    _, probe, terms, asymmetric = friction_probe(robot, base)
    if not terms:
        raise ValueError(f"friction form {form!r}: robot {robot.name!r} has no Coulomb parameter in its columns")
    if asymmetric:
        raise ValueError(f"friction form {form!r}: asymmetric Coulomb (FS+, FS-) on joint(s) "
                         f"{', '.join(map(str, asymmetric))} of {robot.name!r}: a smooth form has one magnitude per "
                         f"joint; give friction 'coulomb', or symmetric Coulomb on those joints")
    obs = observation_matrix(robot, recordings, base=probe, **options)
    return scales_from_observation(obs, terms, form, robot.n)


# ---------------------------------------------------------------- presliding travel per joint
#: Presliding travels δ tried for every joint [rad] (docs/real-logs.md: the UR10e prefers the short
#: ones, the twin's Dahl state has 5 mrad).
TRAVEL_CANDIDATES = (0.25e-3, 0.5e-3, 1e-3, 2e-3, 5e-3, 10e-3)


@dataclass(frozen=True)
class PreslidingTravels:
    """The presliding travel δ [rad] per joint (nan: no presliding column, e.g. never at rest),
    chosen among ``candidates`` [rad] by the fit's weighted cost (``cost``: per joint, per
    candidate, the others at their choice)."""

    travels: tuple[float, ...]
    candidates: tuple[float, ...]
    cost: tuple[tuple[float, ...], ...]

    def to_json(self) -> dict[str, Any]:
        return {"presliding_travel": [float(v) if np.isfinite(v) else None for v in self.travels],
                "presliding_candidates": list(self.candidates),
                "presliding_cost": [[float(c) if np.isfinite(c) else None for c in row] for row in self.cost]}


def presliding_travels(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any,
                       candidates: Sequence[float] = TRAVEL_CANDIDATES, **options: Any) -> PreslidingTravels:
    """The presliding travel per joint, separable like the velocity scales: FPj is linear, δ_j
    one of ``candidates`` [rad]. One observation matrix holds a column FPj_k per candidate (rest
    policy "presliding" in ``options``, the fit's other observation options); the other columns
    are projected out once and each joint's δ is chosen by coordinate descent on the weighted cost
    (two sweeps; eq. 11's weights from the fit at the middle candidate)."""
    inner, _, terms, _ = friction_probe(robot, base)
    form = base.form if isinstance(base, FrictionBase) else "coulomb"
    scales = base.scales if isinstance(base, FrictionBase) else None
    probe = FrictionBase(inner, tuple((t.row, t.column, t.driver) for t in terms), form, scales, True,
                         None, tuple(float(d) for d in candidates))
    obs = observation_matrix(robot, recordings, base=probe, **options)
    names = list(obs.names)
    columns = {t.row: [names.index(f"{PRESLIDING_PREFIX}{t.row + 1}_{k}") if f"{PRESLIDING_PREFIX}{t.row + 1}_{k}"
                       in names else None for k in range(len(candidates))] for t in terms}
    columns = {j: c for j, c in columns.items() if all(x is not None for x in c)}
    choice = {j: len(candidates) // 2 for j in columns}
    chosen = sorted(c for j in columns for c in columns[j])
    fixed = [c for c in range(len(names)) if c not in chosen]
    first = weighted_least_squares(obs.W[:, fixed + [columns[j][choice[j]] for j in columns]], obs.Y, obs.joint,
                                   [names[c] for c in fixed] + [f"FP{j + 1}" for j in columns])
    d = np.asarray(first.weights)[obs.joint]
    # The fixed columns projected out once; a choice's cost from the Gram matrix of the candidates.
    Q = np.linalg.qr(obs.W[:, fixed] * d[:, None])[0]
    A = obs.W[:, chosen] * d[:, None]
    b = obs.Y * d
    A, b = A - Q @ (Q.T @ A), b - Q @ (Q.T @ b)
    G, g, bb = A.T @ A, A.T @ b, float(b @ b)
    where = {c: k for k, c in enumerate(chosen)}

    def cost(pick: dict[int, int]) -> float:
        idx = [where[columns[j][pick[j]]] for j in columns]
        x = np.linalg.lstsq(G[np.ix_(idx, idx)], g[idx], rcond=None)[0]
        return 0.5 * (bb - float(g[idx] @ x))   # ½‖b − A x‖² at the least-squares x

    table = {j: [np.nan] * len(candidates) for j in columns}
    for _ in range(2):
        for j in columns:
            table[j] = [cost({**choice, j: k}) for k in range(len(candidates))]
            choice[j] = int(np.argmin(table[j]))
    travels = tuple(float(candidates[choice[j]]) if j in choice else np.nan for j in range(robot.n))
    return PreslidingTravels(travels, tuple(float(c) for c in candidates),
                             tuple(tuple(table.get(j, [np.nan] * len(candidates))) for j in range(robot.n)))
