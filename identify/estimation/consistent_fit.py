"""The physically consistent refit of a (W)LS result (standard parameters through cvxpy's LMIs)."""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

import rx90sym
from rx90sym.threads import one_blas_thread

from identify.estimation.results import IdentificationResult

if TYPE_CHECKING:  # cvxpy is imported by the consistent fit only, not by every fit that loads this module
    from identify.estimation.consistency import ConsistentSolution

__all__ = ["ConsistentResult", "consistent_fit"]


@dataclass(frozen=True, eq=False)
class ConsistentResult(IdentificationResult):
    """A physically consistent identification: base values beta = K chi of a consistent chi.

    std / rel_std_pct are those of the unconstrained WLS fit (the constraints only shrink the
    feasible set; they are reported as the data's information on each parameter).
    standard: the standard parameters chi found (dict name -> value);
    cost, wls_cost: weighted residual sum of squares of the consistent and of the WLS fit;
    wls_was_consistent: whether the WLS estimate itself admits a consistent chi (then both costs
    agree to the solver's accuracy).
    """

    standard: dict = field(default_factory=dict)
    cost: float = float("nan")
    wls_cost: float = float("nan")
    wls_was_consistent: bool = False
    solution: ConsistentSolution | None = field(default=None, repr=False)
    prior: dict | None = None   # where the unseen directions come from (None: arbitrary split)

    @property
    def cost_increase_pct(self) -> float:
        """How much the constraints cost in residual, % of the WLS residual sum of squares."""
        return 100.0 * (self.cost - self.wls_cost) / self.wls_cost

    def to_dict(self) -> dict[str, Any]:
        d = super().to_dict()
        d.update({"standard": {k: float(v) for k, v in self.standard.items()},
                  "cost": self.cost, "wls_cost": self.wls_cost,
                  "cost_increase_pct": self.cost_increase_pct,
                  "wls_was_consistent": self.wls_was_consistent,
                  "prior": self.prior, "split": self.split})
        return d

    def table(self) -> str:
        """The estimates without a spread: eq. 13's σ is the unconstrained fit's, not this one's
        (the constraints and the prior change the estimator); the file keeps it as the data's
        information on each parameter."""
        width = max([len("Parameter")] + [len(n) for n in self.names])
        lines = [f"{'Parameter':<{width}}  {'Estimate':>12}  {'2σ':>10}"]
        lines += [f"{n:<{width}}  {v:12.6g}  {'—':>10}" for n, v in zip(self.names, self.values)]
        lines.append(f"method consistent, {len(self.names)} parameters, {self.rows} equations, σρ = "
                     f"{self.sigma_rho:.4g}; no σ is printed for a consistent estimate (eq. 13's is the "
                     f"unconstrained fit's)")
        if self.residual_rms.size:
            lines.append("residual RMS per joint (N·m): " + "  ".join(f"{v:.4g}" for v in self.residual_rms))
        return "\n".join(lines)

    @property
    def split(self) -> str:
        """What decided the standard parameters the data cannot see (shown in every output)."""
        if self.prior is None:
            return ("arbitrary: no prior; the standard parameters the data cannot see are one physical "
                    "choice among many (give the robot's nominal parameters as a prior)")
        return f"from the prior: {self.prior['source']}"

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "ConsistentResult":
        """Inverse of :meth:`to_dict` (no compressed system, no solution: it cannot be re-solved)."""
        result = super().from_dict(d)
        standard = d.get("standard")
        if not isinstance(standard, dict):
            raise ValueError("a consistent result without its 'standard' parameters")
        return replace(result, standard={str(k): float(v) for k, v in standard.items()},
                       cost=float(d.get("cost", float("nan"))), wls_cost=float(d.get("wls_cost", float("nan"))),
                       wls_was_consistent=bool(d.get("wls_was_consistent", False)),
                       prior=d.get("prior") if isinstance(d.get("prior"), dict) else None)



@one_blas_thread()
def consistent_fit(robot: rx90sym.Robot, wls: IdentificationResult, base: Any, physical_prior: Any = None,
                   covariance: np.ndarray | None = None, **options: Any) -> ConsistentResult:
    """Physically consistent refit of a (W)LS result on its compressed weighted system.

    physical_prior: an identify.estimation.consistency.prior.PhysicalPrior: the directions the data
    cannot see come from it (prior_fit: within PRIOR_BUDGET standard deviations of the best fit,
    ``covariance`` of the base parameters, e.g. the segment bootstrap's; eq. 13's without);
    without one the split is arbitrary (ConsistentResult.split says so). Other options go to
    consistent_least_squares.
    BLAS on one thread inside the call, the caller's count back after it (rx90sym.threads)."""
    system = wls.system
    if system is None:
        raise ValueError("consistent fit needs a result that still holds its compressed system "
                         "(not one loaded from JSON)")
    if tuple(wls.names) != tuple(base.names):
        raise ValueError("consistent fit needs a result on the full base parameter set")
    from identify.estimation.consistency import consistency_margin, consistent_least_squares

    prior_record = None
    # A URDF link's lumped hand is written apart on export: the link minus it stays physical too.
    from rx90sym.urdf_carried import carried_bodies

    options.setdefault("carried", {body: p10 for body, (p10, _) in carried_bodies(robot).items()} or None)
    if physical_prior is not None:
        from identify.estimation.consistency.prior_fit import PRIOR_BUDGET, prior_fit

        sol = prior_fit(system.R, system.z, base.K, robot.parameter_names, physical_prior,
                        rss_outside=system.rss_outside, rows=system.rows, covariance=covariance, **options)[1]
        prior_record = {"source": physical_prior.source, "budget_sigma": PRIOR_BUDGET,
                        "covariance": "segment bootstrap" if covariance is not None else "eq. 13",
                        "ellipsoid_scale": physical_prior.ellipsoid_scale, "mass_floor": physical_prior.mass_floor,
                        "rotor_ratio": physical_prior.rotor_ratio}
    else:
        sol = consistent_least_squares(system.R, system.z, base.K, robot.parameter_names,
                                       rss_outside=system.rss_outside, rows=system.rows, **options)
    wls_cost = system.rss(wls.values)
    c = len(wls.names)
    sigma_rho = float(np.sqrt(sol.cost / max(system.rows - c, 1)))
    residual_rms = np.array([np.sqrt(js.rss(sol.beta) / js.rows) for js in wls.joint_systems])
    # Exact test: does some consistent chi reproduce the WLS beta? (margin > 0)
    was_consistent = bool(consistency_margin(wls.values, base.K, robot.parameter_names)[0] > 0)
    return ConsistentResult(
        names=wls.names, values=sol.beta, std=wls.std,
        rel_std_pct=100 * wls.std / np.where(sol.beta == 0, np.nan, np.abs(sol.beta)),
        sigma_rho=sigma_rho, cond=wls.cond, cond_unweighted=wls.cond_unweighted,
        residual_rms=residual_rms, weights=wls.weights, rows=wls.rows, method="consistent",
        covariance=wls.covariance, system=system, joint_systems=wls.joint_systems,
        standard=dict(zip(robot.parameter_names, sol.chi)), cost=sol.cost, wls_cost=wls_cost,
        wls_was_consistent=was_consistent, solution=sol, prior=prior_record)
