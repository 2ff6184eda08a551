"""The physically consistent refit of a (W)LS result (standard parameters through cvxpy's LMIs)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

import rx90sym

from identify.estimation.consistency import ConsistentSolution, consistency_margin, consistent_least_squares
from identify.estimation.results import IdentificationResult

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

    @property
    def cost_increase_pct(self) -> float:
        """How much the constraints cost in residual, % of the WLS residual sum of squares."""
        return 100.0 * (self.cost - self.wls_cost) / self.wls_cost

    def to_dict(self) -> dict[str, Any]:
        d = super().to_dict()
        d.update({"standard": {k: float(v) for k, v in self.standard.items()},
                  "cost": self.cost, "wls_cost": self.wls_cost,
                  "cost_increase_pct": self.cost_increase_pct,
                  "wls_was_consistent": self.wls_was_consistent})
        return d



def consistent_fit(robot: rx90sym.Robot, wls: IdentificationResult, base: Any, **options: Any) -> ConsistentResult:
    """Physically consistent refit of a (W)LS result on its compressed weighted system."""
    system = wls.system
    if system is None:
        raise ValueError("consistent fit needs a result that still holds its compressed system "
                         "(not one loaded from JSON)")
    if tuple(wls.names) != tuple(base.names):
        raise ValueError("consistent fit needs a result on the full base parameter set")
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
        wls_was_consistent=was_consistent, solution=sol)
