"""The description as a prior: the bodies θ₀ a fit is weighed against, and the divergence D(θ ‖ θ₀).

The identified model minimises the fit's weighted residual plus λ·D(θ ‖ θ₀) over physically
consistent standard parameters θ (:mod:`identify.estimation.consistency.weighted_fit`). The prior
holds the description's rigid bodies — the links with physical inertials (or the nearest physical
body, the description says which) — and nothing else: rotor inertias, friction and torque offsets
are the data's (λ → ∞ is the description's rigid bodies with the drives fitted). A link the
description leaves without a body (no mass, or no inertial) contributes nothing.

Two divergences, one per link b with pseudo-inertia J_b (Wensing, Kim & Slotine 2017):

- ``"gaussian"``: Σ_k ((θ_k − θ₀_k) / s_k)² over the ten inertial parameters, s_k the prior's
  uncertainty (10 % of the mass m₀ for M, 20 % of m₀·l for the first moments, 100 % of m₀·l² for
  the inertias, l the prior's radius of gyration, at least 5 cm);
- ``"entropic"``: the log-det (Bregman) divergence of the pseudo-inertias,
  −log det(J₀⁻¹ J) + tr(J₀⁻¹ J) − 4 (Lee, Wensing & Park 2020), invariant to the link's frame and
  units, infinite at the boundary of physical bodies.

Both are 0 at θ₀, convex, and near θ₀ quadratic: :meth:`BodyPrior.hessian` gives that quadratic
form, from which the data's share of each base parameter follows.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import cvxpy as cp
import numpy as np

from rx90sym.physical import DEFAULT_MARGIN, INERTIAL_FIELDS, nearest_physical_body
from rx90sym.rigid_body import RigidBody, physical_problem
from rx90sym.rigid_body import pseudo_inertia as numeric_pseudo_inertia

from identify.estimation.consistency.lmi import _PSEUDO_INERTIA_MAP, pseudo_inertia
from identify.estimation.defaults import DEFAULT_DIVERGENCE, DIVERGENCES

__all__ = ["DIVERGENCES", "DEFAULT_DIVERGENCE", "BodyPrior", "body_prior"]

#: Relative uncertainty of the Gaussian's scales per kind (module docstring).
UNCERTAINTY = {"M": 0.1, "MX": 0.2, "XX": 1.0}
#: Margin of a prior body [kg m², kg]: inside the identified model's own solve margin (ten times the
#: consistency margin), so that λ = ∞ — the prior's bodies themselves — is a feasible model.
PRIOR_MARGIN = 100 * DEFAULT_MARGIN
MIN_GYRATION = 0.05  # m


@dataclass(frozen=True)
class BodyPrior:
    """The description's bodies as a prior.

    values: standard parameters of the informed links (name -> value, SI; physical);
    links: the informed links ("1".."n"); divergence: one of :data:`DIVERGENCES`;
    source: where the bodies come from (shown in every output); notes: what the description said
    (links left out, bodies replaced by the nearest physical one).
    """

    values: Mapping[str, float]
    links: tuple[str, ...]
    divergence: str = DEFAULT_DIVERGENCE
    source: str = "description"
    notes: tuple[str, ...] = ()
    scales: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.divergence not in DIVERGENCES:
            raise ValueError(f"divergence must be one of {DIVERGENCES}, got {self.divergence!r}")

    def names(self) -> tuple[str, ...]:
        """The standard parameters the prior informs, link by link in eq. 4's order."""
        return tuple(f"{p}{b}" for b in self.links for p in INERTIAL_FIELDS)

    def body(self, link: str) -> RigidBody:
        return RigidBody.from_vector(np.array([self.values[f"{p}{link}"] for p in INERTIAL_FIELDS]))

    def with_divergence(self, divergence: str) -> "BodyPrior":
        return BodyPrior(self.values, self.links, divergence, self.source, self.notes, self.scales)

    # ------------------------------------------------------------------ D and its quadratic form
    def expression(self, x: cp.Expression, index: Mapping[str, int]) -> cp.Expression:
        """D(θ ‖ θ₀) of the decision variable ``x`` (``index``: name -> position in x)."""
        terms = []
        for b in self.links:
            idx = np.array([index[f"{p}{b}"] for p in INERTIAL_FIELDS])
            theta0 = np.array([self.values[f"{p}{b}"] for p in INERTIAL_FIELDS])
            if self.divergence == "gaussian":
                s = np.array([self.scales[f"{p}{b}"] for p in INERTIAL_FIELDS])
                terms.append(cp.sum_squares(cp.multiply(1.0 / s, x[idx] - theta0)))
            else:
                J0 = numeric_pseudo_inertia(self.body(b))
                inv = np.linalg.inv(J0)
                J = pseudo_inertia(x[idx])
                _, logdet0 = np.linalg.slogdet(J0)
                terms.append(-cp.log_det(J) + cp.trace(inv @ J) + (logdet0 - 4.0))
        return cp.sum(cp.hstack(terms)) if terms else cp.Constant(0.0)

    def value(self, values: Mapping[str, float]) -> float:
        """D(θ ‖ θ₀) of standard parameters ``values`` (inf outside the physical bodies for "entropic")."""
        total = 0.0
        for b in self.links:
            theta = np.array([values[f"{p}{b}"] for p in INERTIAL_FIELDS])
            theta0 = np.array([self.values[f"{p}{b}"] for p in INERTIAL_FIELDS])
            if self.divergence == "gaussian":
                s = np.array([self.scales[f"{p}{b}"] for p in INERTIAL_FIELDS])
                total += float(np.sum(((theta - theta0) / s) ** 2))
            else:
                J0 = numeric_pseudo_inertia(self.body(b))
                M = np.linalg.solve(J0, numeric_pseudo_inertia(RigidBody.from_vector(theta)))
                sign, logdet = np.linalg.slogdet(M)
                total += np.inf if sign <= 0 else float(-logdet + np.trace(M) - 4.0)
        return total

    def hessian(self, names: Sequence[str]) -> np.ndarray:
        """(p, p) Hessian of D at θ₀ over the variables ``names`` (zero rows and columns for the
        parameters the prior does not inform): D ≈ ½ Δᵀ H Δ near θ₀."""
        index = {n: i for i, n in enumerate(names)}
        H = np.zeros((len(names), len(names)))
        for b in self.links:
            idx = np.array([index[f"{p}{b}"] for p in INERTIAL_FIELDS])
            if self.divergence == "gaussian":
                s = np.array([self.scales[f"{p}{b}"] for p in INERTIAL_FIELDS])
                H[np.ix_(idx, idx)] += np.diag(2.0 / s ** 2)
            else:
                # d²/dθ² of -log det J(θ): L^T (J0^-1 ⊗ J0^-1) L with vec(J) = L θ (J symmetric)
                inv = np.linalg.inv(numeric_pseudo_inertia(self.body(b)))
                L = _PSEUDO_INERTIA_MAP
                H[np.ix_(idx, idx)] += L.T @ np.kron(inv, inv) @ L
        return H


def _scales(body: RigidBody, link: str) -> dict[str, float]:
    _, I = body.com_inertia()
    gyration = max(float(np.sqrt(max(np.trace(I), 0.0) / (2 * body.m))), MIN_GYRATION)
    out = {f"M{link}": UNCERTAINTY["M"] * body.m}
    out.update({f"{k}{link}": UNCERTAINTY["MX"] * body.m * gyration for k in ("MX", "MY", "MZ")})
    out.update({f"{k}{link}": UNCERTAINTY["XX"] * body.m * gyration ** 2 for k in ("XX", "XY", "XZ", "YY", "YZ", "ZZ")})
    return out


def body_prior(values: Mapping[str, float] | None, n: int, source: str, divergence: str = DEFAULT_DIVERGENCE,
               notes: Sequence[str] = (), carried: Mapping[str, np.ndarray] | None = None) -> BodyPrior | None:
    """The prior of the links 1..n from standard parameters ``values`` (the description's): a link with a
    mass above 0 is informed, its body made physical with :data:`PRIOR_MARGIN` where it is not (the
    nearest physical body with its mass and centre of mass, said in the notes); any other link contributes
    nothing (named in the notes); None when no link is informed. ``notes``: the description's own;
    ``carried``: link -> XX..M of what it carries besides its own body (rx90sym.urdf_carried.carried_bodies):
    the own body (the link's minus it) is the one made physical, as the consistent fit checks it."""
    if values is None:
        return None
    links, notes, scales, kept = [], list(notes), {}, {}
    for j in range(1, n + 1):
        key = str(j)
        try:
            body = RigidBody.from_vector(np.array([float(values[f"{p}{j}"]) for p in INERTIAL_FIELDS]))
        except KeyError:
            notes.append(f"link {j}: no inertial in the description: no prior")
            continue
        if not body.m > PRIOR_MARGIN:
            notes.append(f"link {j}: no mass in the description: no prior")
            continue
        extra = RigidBody.from_vector(np.asarray((carried or {}).get(key, np.zeros(10)), dtype=float))
        own = RigidBody.from_vector(body.vector() - extra.vector())
        if own.m > PRIOR_MARGIN and physical_problem(own, PRIOR_MARGIN):
            problem = physical_problem(own, 0.0)
            body = RigidBody.from_vector(nearest_physical_body(own, PRIOR_MARGIN).vector() + extra.vector())
            if problem:
                notes.append(f"link {j}: not a physical body ({problem}): the nearest physical body is the prior")
        links.append(key)
        scales.update(_scales(body, key))
        kept.update(zip((f"{p}{key}" for p in INERTIAL_FIELDS), (float(v) for v in body.vector())))
    if not links:
        return None
    return BodyPrior(kept, tuple(links), divergence, source, tuple(dict.fromkeys(notes)), scales)
