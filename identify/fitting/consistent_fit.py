"""The identified model: physically consistent standard parameters weighed between the description and the data.

:func:`consistent_fit` solves the prior-weighted problem of
:mod:`identify.estimation.consistency.weighted_fit` on the (W)LS fit's weighted compressed system,
at the prior weight λ given or chosen by blocked cross-validation (:mod:`identify.selection.prior_weight`),
and returns a :class:`ConsistentResult`: the base parameters β = A x of a physical x, the standard
parameters, and per base parameter the share the data determined (1 − posterior / prior variance of
the quadratic approximation: 1 where the prior says nothing, 0 where it fixes the value).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Mapping, Sequence

import numpy as np

import rx90sym
from rx90sym.physical import DEFAULT_MARGIN
from rx90sym.threads import one_blas_thread

from identify.estimation.results import IdentificationResult, json_number

__all__ = ["ConsistentResult", "check_prior_weight", "consistent_fit", "data_share"]

#: A base parameter the data determine: least-squares relative σ under this [%] (eq. 15).
DETERMINED_PCT = 10.0
#: How far the model may move a base parameter the data determine from its least-squares estimate [σ]
#: (or no further than the data alone move it, where physical consistency alone moves it more).
DATA_BUDGET = 2.0
#: λ = ∞ in the data share: the prior's weight this many times the data's information.
_HELD = 1e10


@dataclass(frozen=True, eq=False)
class ConsistentResult(IdentificationResult):
    """A physically consistent identification: base values β = A x of a physical x.

    std / rel_std_pct: σ of the least squares on the same columns (eqs. 13-15, inflated by the segment
    bootstrap's ratio where the residuals are coloured): the data's information on each parameter;
    least_squares: those estimates; heldout: the model's held-back errors in the fitted data (the blocked
    cross-validation's: ``score_pct``, ``per_joint_pct``, ``per_block_pct``; None without the fit's folds).
    standard: the standard parameters (name -> value, SI); extras: the model's columns that are not the
    robot's standard parameters (torque offsets it adds, Stribeck levels, presliding magnitudes); cost, wls_cost: weighted residual sum of squares of this
    model and of the (W)LS fit; prior: the prior's record (source, divergence, weight λ and its choice;
    None: no prior, the split of what the data cannot see is the tie-break's); data_share: per base
    parameter the share the data determined (0..1); wls_was_consistent: whether the least-squares
    estimate itself admits physical bodies (then the model differs from it only through the prior).
    """

    standard: dict = field(default_factory=dict)
    extras: dict = field(default_factory=dict)
    cost: float = float("nan")
    wls_cost: float = float("nan")
    prior: dict | None = None
    data_share: np.ndarray | None = None
    wls_was_consistent: bool = False
    least_squares: np.ndarray | None = None
    heldout: dict | None = None

    @property
    def cost_increase_pct(self) -> float:
        """How much the model costs in residual, % of the (W)LS residual sum of squares."""
        return 100.0 * (self.cost - self.wls_cost) / self.wls_cost

    @property
    def prior_weight(self) -> float | None:
        """λ (inf: the description's bodies; None: no prior)."""
        if self.prior is None:
            return None
        w = self.prior.get("weight")
        return math.inf if w is None else float(w)

    def to_dict(self) -> dict[str, Any]:
        d = super().to_dict()
        d.update({"standard": {k: float(v) for k, v in self.standard.items()},
                  "extras": {k: float(v) for k, v in self.extras.items()},
                  "cost": self.cost, "wls_cost": self.wls_cost,
                  "cost_increase_pct": self.cost_increase_pct,
                  "prior": self.prior, "split": self.split,
                  "data_share": None if self.data_share is None else [json_number(v) for v in self.data_share],
                  "least_squares": (None if self.least_squares is None
                                    else [json_number(v) for v in self.least_squares]),
                  "wls_was_consistent": self.wls_was_consistent, "heldout": self.heldout})
        return d

    def table(self) -> str:
        """The estimates with the data's share of each (no σ: the model is not the least squares)."""
        width = max([len("Parameter")] + [len(n) for n in self.names])
        share = self.data_share if self.data_share is not None else np.full(len(self.names), np.nan)
        # Round-off of a value the prior holds at 0 (1e-15 of the largest) printed as the 0 it is.
        tiny = 1e-12 * max(1.0, float(np.max(np.abs(self.values)))) if len(self.values) else 0.0
        lines = ["the identified model (what predicts, exports and monitors): its estimates and the share of each "
                 "the data determined",
                 f"{'Parameter':<{width}}  {'Estimate':>12}  {'from data':>9}"]
        lines += [f"{n:<{width}}  {(v if abs(v) > tiny else 0.0):12.6g}  {_pct(s):>9}"
                  for n, v, s in zip(self.names, self.values, share)]
        lines.append(f"identified model, {len(self.names)} parameters, {self.rows} equations, residual "
                     f"{self.cost_increase_pct:+.2f} % of the least squares'; {self.split}")
        if self.residual_rms.size:
            lines.append("residual RMS per joint (N·m): " + "  ".join(f"{v:.4g}" for v in self.residual_rms))
        moved = self.moved()
        if moved:
            lines.append("held more than 2σ from the least squares by the physical constraints or the prior: "
                         + "; ".join(f"{n} {v:.4g} ({ls:.4g} ± {sd:.2g}, {z:+.1f}σ)" for n, v, ls, sd, z in moved))
        return "\n".join(lines)

    def moved(self, limit: float = 2.0) -> list[tuple[str, float, float, float, float]]:
        """(name, model value, least-squares estimate, σ, z) of every rotor inertia, friction parameter and base
        parameter the data determine (relative σ under DETERMINED_PCT %) that the model holds more than ``limit`` σ
        from the least squares on its columns: where a bound, the physical constraints or the prior override the data."""
        if self.least_squares is None:
            return []
        out = []
        for n, v, ls, sd, rel in zip(self.names, self.values, self.least_squares, self.std, self.rel_std_pct):
            z = (v - ls) / sd if sd > 0 else math.nan
            if np.isfinite(z) and abs(z) > limit and (n.startswith(_DRIVES) or rel < DETERMINED_PCT):
                out.append((str(n), float(v), float(ls), float(sd), float(z)))
        return out

    @property
    def split(self) -> str:
        """What decided the standard parameters the data cannot see (shown in every output)."""
        if self.prior is None:
            return ("no prior: the standard parameters the data cannot see are one physical choice among many "
                    "(give the robot's description as a prior)")
        why = self.prior.get("weight_why") if self.prior.get("choice") is None else None
        return (f"prior {self.prior['source']} ({self.prior['divergence']}), weight λ = {self.prior['weight_label']}"
                + (f" ({why})" if why else ""))

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "ConsistentResult":
        """Inverse of :meth:`to_dict` (no compressed system: it cannot be re-solved)."""
        result = IdentificationResult.from_dict(d)
        standard = d.get("standard")
        if not isinstance(standard, dict):
            raise ValueError("a consistent result without its 'standard' parameters")
        share, least = d.get("data_share"), d.get("least_squares")
        base = {f: getattr(result, f) for f in result.__dataclass_fields__}
        extras = d.get("extras") if isinstance(d.get("extras"), dict) else {}
        return cls(**base, standard={str(k): float(v) for k, v in standard.items()},
                   extras={str(k): float(v) for k, v in extras.items()},
                   cost=float(d.get("cost", float("nan"))), wls_cost=float(d.get("wls_cost", float("nan"))),
                   prior=d.get("prior") if isinstance(d.get("prior"), dict) else None,
                   data_share=None if share is None else np.array([np.nan if v is None else v for v in share]),
                   least_squares=None if least is None else np.array([np.nan if v is None else v for v in least]),
                   wls_was_consistent=bool(d.get("wls_was_consistent", False)),
                   heldout=d.get("heldout") if isinstance(d.get("heldout"), dict) else None)


def _pct(v: float) -> str:
    return "—" if not np.isfinite(v) else f"{100 * v:.0f} %"


def data_share(A: np.ndarray, information: np.ndarray, prior_precision: np.ndarray) -> np.ndarray:
    """Per fit column β_i = a_iᵀ x the share the data determined: 1 − var_post / var_prior, with
    var = a_iᵀ P⁻¹ a_i, P_post = ``information`` + ``prior_precision``, P_prior = ``prior_precision``
    (the quadratic approximation of the cost around the model)."""

    def variances(P: np.ndarray) -> np.ndarray:
        P = 0.5 * (P + P.T)
        d = np.sqrt(np.maximum(np.diag(P), 1e-300))
        lam, V = np.linalg.eigh(P / np.outer(d, d))  # Jacobi-scaled: the units of the variables do not matter
        inv = (V / np.maximum(lam, lam.max() * 1e-15)) @ V.T / np.outer(d, d)
        return np.einsum("ij,jk,ik->i", A, inv, A)

    post, prior = variances(information + prior_precision), variances(prior_precision)
    share = 1.0 - post / np.where(prior > 0, prior, np.inf)
    return np.clip(np.where(np.any(A != 0, axis=1), share, 0.0), 0.0, 1.0)


@one_blas_thread()
def consistent_fit(robot: rx90sym.Robot, wls: IdentificationResult, columns: Any, prior: Any = None,
                   prior_weight: float | str = "auto", factors: Any = None, *, offsets: Sequence[int] = (),
                   margin: float = DEFAULT_MARGIN, solver: str = "CLARABEL", bounds: Mapping[str, Any] | None = None,
                   reference: Mapping[str, float] | None = None, spread: np.ndarray | None = None,
                   still: Sequence[int] = (), weight_why: str | None = None) -> ConsistentResult:
    """The identified model of a (W)LS fit on ``columns`` (module docstring).

    prior: a :class:`~identify.estimation.consistency.body_prior.BodyPrior` (None: the data alone, the
    unseen directions by the tie-break); prior_weight: λ ≥ 0 (inf: the description's bodies) or "auto":
    chosen by the blocked cross-validation on ``factors``; factors: the per-(time block, joint) factors of
    ``columns`` (:class:`~identify.selection.raw_torque_scores.RawFactors`, or
    :func:`~identify.selection.prior_weight.observation_folds`): the model is fitted on them, with a
    torque offset on each joint of ``offsets`` (0-based; its column after the fit's, named OFFj); None:
    on ``wls``'s own weighted system (no offsets added, λ given). bounds: ``mass_bounds``,
    ``total_mass``, ``com_boxes`` of :func:`identify.estimation.consistency.consistent_least_squares`;
    reference: values the tie-break pulls unseen variables toward (e.g. the description's rotor inertias);
    spread: σ of ``wls``'s estimates beside eq. 13's (the segment bootstrap's: their median ratio
    inflates the σ of the least squares on the model's columns); still: the joints (0-based) that never move in
    the fitted rows: their friction and rotor inertia are held at the description's (``reference``; 0
    without), since no row weighs them (a prediction of their motion then carries no friction fitted to noise).
    The base parameters the data determine (relative σ of the least squares on the same columns under
    :data:`DETERMINED_PCT` %, σ the larger of eq. 13's and the block jackknife's) are the data's at any λ:
    a Gaussian prior weighs only the deviations that leave them unchanged
    (identify.estimation.consistency.weighted_fit), and with "auto" no λ is chosen whose model (held
    physical) moves one more than :data:`DATA_BUDGET` σ from its estimate, or further than the data alone
    move it.
    The result's names are the fit's columns then the offsets added.
    """
    from identify.estimation.consistency.errors import ConsistencyError
    from identify.estimation.consistency.weighted_fit import TIE_BREAK, PriorProblem, column_map
    from identify.selection.prior_weight import choose_prior_weight, fold_system, held_back_scores
    from identify.observation.offsets import offset_base
    from rx90sym.urdf_carried import carried_bodies

    check_prior_weight(prior_weight)
    offsets = tuple(int(j) for j in offsets)
    if factors is not None:
        names = tuple(columns.names) + tuple(f"OFF{j + 1}" for j in offsets)
        system = fold_system(factors.fitted, None, factors.n, factors.c, offsets)
        if system is None:
            raise ValueError("the identified model: too few rows to fit")
        R, z, scale = system.R, system.z, system.scale
    else:
        if wls.system is None:
            raise ValueError("the identified model needs a result that still holds its compressed system "
                             "(not one loaded from JSON), or the fit's factors")
        if offsets:
            raise ValueError("offsets need the fit's factors")
        names, system = tuple(wls.names), None
        R, z, scale = wls.system.R, wls.system.z, max(wls.system.rss(wls.values), 1e-300)
    cmap = column_map(robot, offset_base(columns, offsets), names)
    rows = int(sum(system.rows)) if system is not None else wls.rows
    least, least_std = _least_squares(R, z, scale, rows, wls, spread)
    # What the data determine: by eq. 13's σ and by what leaving a time block out changes.
    honest_std = least_std if factors is None else np.fmax(least_std, _block_spread(factors, offsets, least.size))
    with np.errstate(divide="ignore", invalid="ignore"):
        determined = np.flatnonzero((100 * honest_std / np.abs(least) < DETERMINED_PCT) & (least_std > 0))
    carried = {body: p10 for body, (p10, _) in carried_bodies(robot).items()} or None
    extra = _bounds(cmap, bounds)
    held = _still_drives(cmap.names, still, reference)

    def make(fixed: bool, at: float | None = None) -> PriorProblem:
        return PriorProblem(cmap, prior, fixed=fixed, carried=carried, margin=margin, reference=reference,
                            solver=solver, solve_margin=at, bounds=extra, determined=cmap.A[determined],
                            held=held)

    choice = None
    if prior is None:
        weight = 0.0
    elif prior_weight == "auto":
        if factors is None:
            raise ValueError("prior_weight 'auto' needs the cross-validation's factors of the fit's columns")
        free, fixed_problem = make(False), make(True)

        def beta_at(w: float) -> np.ndarray:
            return cmap.beta((fixed_problem if math.isinf(w) else free).solve(R, z, w, scale))

        choice = choose_prior_weight(factors, free, fixed_problem, offsets,
                                     keeps=_data_budget(names, least, honest_std, determined, beta_at))
        weight = choice.chosen
    else:
        weight = float(prior_weight)
    fixed = prior is not None and math.isinf(weight)
    heldout = None
    if factors is not None:  # the model's own held-back errors (the chosen weight's, or the weight given)
        done = (dict(zip(choice.weights, choice.scores))[weight] if choice is not None else
                held_back_scores(factors, {False: make(False), True: make(True)} if prior is not None
                                 else {False: make(False)}, [weight], offsets)[0])
        if not math.isnan(done.score):
            heldout = {"score_pct": done.score, "per_joint_pct": [json_number(v) for v in done.per_joint],
                       "per_block_pct": [[json_number(v) for v in row] for row in done.per_block],
                       "torque_rms": [json_number(v) for v in _torque_rms(factors)]}
    problem = make(fixed)
    x = problem.solve(R, z, weight, scale)
    report = problem.check(x)
    at = problem.solve_margin
    for attempt in (1, 2):  # the solver's error ate the margin: solve again further inside
        if report.ok:
            break
        at *= 10.0 ** attempt
        problem = make(fixed, at)
        x = problem.solve(R, z, weight, scale)
        report = problem.check(x)
    if not report.ok:
        raise ConsistencyError(f"the identified model fails the consistency check at margin {margin:.1e} even when "
                               f"solved with margin {at:.1e}: {'; '.join(report.violations())}",
                               status="external_check_failed", solver=solver)
    beta = cmap.beta(x)
    info = cmap.A.T @ (R.T @ R) @ cmap.A
    tie = np.diag(scale * TIE_BREAK / problem.typical ** 2)
    # λ = ∞: the prior's directions held, as by a weight far above the data's information.
    held = (_HELD * np.trace(info) / max(np.trace(problem.prior_precision(1.0)), 1e-300)) if fixed else weight
    share = data_share(cmap.A, info, problem.prior_precision(held) + tie)
    residual_rms, weights, rows = _residuals(wls, system, beta)
    record = None
    if prior is not None:
        record = {"source": prior.source, "divergence": prior.divergence,
                  "weight": None if math.isinf(weight) else weight,
                  "weight_label": "inf" if math.isinf(weight) else f"{weight:g}",
                  "links": [int(b) for b in prior.links], "notes": list(prior.notes),
                  "divergence_value": json_number(prior.value(dict(zip(cmap.names, x)))),
                  "prior_term": json_number(problem.prior_term(x)),
                  "determined": [names[k] for k in determined],
                  "choice": None if choice is None else choice.to_dict(),
                  "weight_why": choice.reason if choice is not None else weight_why}
    std = least_std
    cost = float(np.sum((R @ beta - z) ** 2))
    wls_cost = float(np.sum((R @ least - z) ** 2))
    return ConsistentResult(
        names=names, values=beta, std=std,
        rel_std_pct=100 * std / np.where(least == 0, np.nan, np.abs(least)),
        sigma_rho=float(np.sqrt(max(cost + scale - wls_cost, 0.0) / max(rows - len(names), 1))), cond=wls.cond,
        cond_unweighted=wls.cond_unweighted, residual_rms=residual_rms, weights=weights, rows=rows,
        method="consistent", covariance=None, system=None, joint_systems=(),
        standard=dict(zip(cmap.names[:cmap.standard], (float(v) for v in x[:cmap.standard]))),
        extras=dict(zip(cmap.names[cmap.standard:], (float(v) for v in x[cmap.standard:]))),
        cost=cost + scale - wls_cost, wls_cost=scale,
        prior=record, data_share=share, least_squares=least, heldout=heldout, wls_was_consistent=_admits_bodies(robot, columns, names, least))


def _least_squares(R: np.ndarray, z: np.ndarray, scale: float, rows: int, wls: IdentificationResult,
                   spread: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """(estimates, σ) of the least squares on the model's own weighted system (eqs. 10-14: σρ² the
    weighted residual over rows − c), σ inflated by √(rows / the fit's rows) where the model's rows are
    more (sampled at the prediction rate: no more independent than the fit's decimated ones), and by the
    median ratio of ``spread`` (the segment bootstrap's σ) to eq. 13's of the fit's ``wls`` where above 1
    (coloured residuals)."""
    import scipy.linalg as sla

    c = R.shape[1]
    beta = np.linalg.lstsq(R, z, rcond=None)[0]
    r_inv = sla.pinv(R)
    std = np.sqrt(np.maximum(np.einsum("ij,ij->i", r_inv, r_inv), 0.0) * scale / max(rows - c, 1))
    std = std * np.sqrt(max(1.0, rows / max(wls.rows, 1)))
    if spread is not None:
        ratios = np.asarray(spread, dtype=float) / np.where(wls.std > 0, wls.std, np.nan)
        ratios = ratios[np.isfinite(ratios)]
        std = std * max(1.0, float(np.median(ratios)) if ratios.size else 1.0)
    return beta, std


def _block_spread(factors: Any, offsets: Sequence[int], c: int) -> np.ndarray:
    """(c,) the block jackknife's σ of the least squares on the model's columns: its estimates with each
    time block left out in turn, √((B − 1)/B Σ (β_b − β̄)²); 0 where a fold cannot be fitted. Where the
    residual is not white noise (a model that misses some of the torque, a short log of few motions),
    eq. 13's σ understates what a block changes; this one does not."""
    from identify.selection.prior_weight import fold_system

    fits = []
    for b in range(factors.span.blocks):
        system = fold_system(factors.fitted, b, factors.n, factors.c, offsets)
        if system is None or system.R.shape[1] != c:
            return np.zeros(c)
        fits.append(np.linalg.lstsq(system.R, system.z, rcond=None)[0])
    if len(fits) < 2:
        return np.zeros(c)
    fits = np.array(fits)
    return np.sqrt((len(fits) - 1) / len(fits) * np.sum((fits - fits.mean(axis=0)) ** 2, axis=0))


def _data_budget(names: Sequence[str], least: np.ndarray, std: np.ndarray, determined: np.ndarray,
                 beta_at: Any) -> Any:
    """``keeps(λ)`` of :func:`~identify.selection.prior_weight.choose_prior_weight`: why the model at λ moves
    a base parameter the data determine (indices ``determined``) more than :data:`DATA_BUDGET` σ from its
    least-squares estimate, and further than the data alone move it (None: it does not)."""
    if determined.size == 0:
        return None
    cache: dict[float, np.ndarray] = {}

    def at(w: float) -> np.ndarray:
        if w not in cache:
            cache[w] = beta_at(w)
        return cache[w]

    def keeps(weight: float) -> str | None:
        from identify.estimation.consistency.errors import ConsistencyError

        try:
            alone, beta = at(0.0), at(weight)
        except ConsistencyError as exc:
            return f"has no solution ({exc})"
        allowed = np.maximum(DATA_BUDGET * std[determined], np.abs(alone - least)[determined])
        over = (np.abs(beta - least)[determined] - allowed) / std[determined]
        k = int(np.argmax(over))
        if over[k] <= 1e-9 * DATA_BUDGET:
            return None
        i = determined[k]
        return (f"moves {names[i]} {abs(beta[i] - least[i]) / std[i]:.1f} σ from its least-squares estimate "
                f"(at most {allowed[k] / std[i]:.1f} σ)")
    return keeps


#: A joint's drive parameters: what a joint that never moves in the fitted rows holds at the description's.
_DRIVES = ("IA", "FV", "FS", "FSP", "FSN", "FST", "FP")


def _still_drives(names: Sequence[str], still: Sequence[int], reference: Mapping[str, float] | None) -> dict:
    """name -> value of the drive parameters (rotor inertia, friction) of the joints ``still`` (0-based)."""
    out = {}
    for j in still:
        for kind in _DRIVES:
            name = f"{kind}{j + 1}"
            if name in names:
                out[name] = float((reference or {}).get(name, 0.0))
    return out


def check_prior_weight(value: Any) -> None:
    """A prior weight λ: "auto" or a number >= 0 (inf allowed); ValueError naming the value otherwise."""
    if isinstance(value, str) and value == "auto":
        return
    try:
        ok = not isinstance(value, bool) and float(value) >= 0
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"prior_weight must be 'auto' or a number >= 0 (inf: the description's bodies), got {value!r}")


def _admits_bodies(robot: rx90sym.Robot, columns: Any, names: Sequence[str], beta: np.ndarray) -> bool:
    """Whether the base parameters of ``beta`` (over ``names``) admit physical bodies (a positive
    consistency margin, identify.estimation.consistency.margin)."""
    from identify.estimation.consistency.errors import ConsistencyError
    from identify.estimation.consistency.margin import consistency_margin
    from identify.estimation.consistency.weighted_fit import _base_of

    base = _base_of(columns)
    values = dict(zip(names, beta))
    try:
        return bool(consistency_margin(np.array([values[n] for n in base.names]), base.K,
                                       robot.parameter_names)[0] > 0)
    except ConsistencyError:  # the margin's solve failed: it says nothing either way (not claimed)
        return False


def _torque_rms(factors: Any) -> np.ndarray:
    """(n,) RMS [N m] of the raw torques the cross-validation scores, per joint (NaN: none scored)."""
    sums = np.array([[float(np.sum(f.R[j][:, -1] ** 2)) for j in range(factors.n)] for f in factors.scored]).sum(0)
    rows = np.array([[int(f.rows[j]) for j in range(factors.n)] for f in factors.scored]).sum(0)
    return np.where(rows > 0, np.sqrt(sums / np.maximum(rows, 1)), np.nan)


def _residuals(wls: IdentificationResult, system: Any, beta: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """(per joint residual RMS [N m], weights, rows) of ``beta`` on the system it was fitted on."""
    if system is None:
        rms = np.array([np.sqrt(js.rss(beta) / js.rows) if js.rows else np.nan for js in wls.joint_systems])
        return rms, wls.weights, wls.rows
    rms = np.array([np.nan if Rj is None else float(np.linalg.norm(Rj @ np.r_[beta, -1.0]) / np.sqrt(r))
                    for Rj, r in zip(system.joints, system.rows)])
    return rms, system.weights, int(sum(system.rows))


def _bounds(cmap: Any, bounds: Mapping[str, Any] | None) -> list:
    """The user's mass, total-mass and CoM-box bounds as builders of constraints on x."""
    if not bounds:
        return []
    from identify.estimation.consistency.lmi import body_indices
    from identify.estimation.consistency.problem import _com_box_constraints, _mass_constraints

    unknown = sorted(set(bounds) - {"mass_bounds", "total_mass", "com_boxes"})
    if unknown:
        raise ValueError(f"bounds: unknown {unknown} (mass_bounds, total_mass, com_boxes)")
    bodies = body_indices(cmap.names[:cmap.standard])
    return [lambda x: _mass_constraints(x, bodies, bounds.get("mass_bounds"), bounds.get("total_mass"))
            + _com_box_constraints(x, bodies, bounds.get("com_boxes"))]
