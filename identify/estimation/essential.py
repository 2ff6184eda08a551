"""Essential parameters by backward elimination (paper §II-B, end; reference [1]).

At each iteration the parameter with the largest relative standard deviation (eq. 15) is
removed, the reduced model is solved again, and σ_pe, the residual standard deviation of the
reduced model (eq. 12 with r − c_k degrees of freedom), is recomputed. The paper stops when
σ_pe ≥ 1.02·σρ0 (σρ0: the base-parameter model); the set kept is the last one for which
σ_pe < threshold·σρ0.

Every re-solve uses the compressed weighted system stored in the result
(``‖W[:, k]·x − y‖² = ‖R[:, k]·x − z‖² + rss_outside``), never the raw data; the joint
weights stay those of the base-parameter identification.
"""

from __future__ import annotations

import math

import numpy as np

from identify.estimation.least_squares import (
    RANK_RCOND,
    CompressedSystem,
    relative_std_pct,
    solve_compressed,
    solve_system,
    stack_systems,
)
from identify.estimation.results import EliminationStep, IdentificationResult

__all__ = ["DEFAULT_THRESHOLD", "essential_parameters"]

#: Stop ratio σ_pe / σρ0 of the paper.
DEFAULT_THRESHOLD = 1.02


def _trial(system: CompressedSystem, keep: list[int]) -> tuple[float, np.ndarray]:
    """σ_pe (eq. 12, r − c_k dof) and relative σ % (eq. 15) of the model on columns ``keep``."""
    x, cov, sigma_pe = solve_compressed(system.select(keep))
    return sigma_pe, relative_std_pct(x, np.sqrt(np.diag(cov)))


def essential_parameters(
    result: IdentificationResult,
    threshold: float = DEFAULT_THRESHOLD,
    *,
    min_parameters: int = 1,
    rcond: float = RANK_RCOND,
) -> IdentificationResult:
    """Reduce a base-parameter identification to its essential parameters.

    Args:
        result: an OLS/WLS result that still holds its compressed system (``result.system``).
        threshold: stop ratio: a removal is refused once σ_pe ≥ threshold·σρ0 (paper: 1.02).
        min_parameters: never go below this many parameters.
        rcond: rank tolerance passed to the final solve.

    Returns:
        IdentificationResult of the kept parameters (original order), method "essential",
        σρ = σ_pe of the kept set, same joint weights, and ``history`` listing every trial
        (the last one is the refused removal, unless the procedure ran out of parameters).

    Raises:
        ValueError: no compressed system in ``result`` (e.g. loaded from JSON), or bad threshold.
    """
    if result.system is None:
        raise ValueError("essential_parameters needs result.system (results loaded from JSON cannot be re-solved)")
    if not (math.isfinite(threshold) and threshold > 0):
        raise ValueError(f"threshold must be a finite positive ratio, got {threshold}")
    if min_parameters < 1:
        raise ValueError(f"min_parameters must be >= 1, got {min_parameters}")
    system, sigma0 = result.system, result.sigma_rho
    keep = list(range(len(result.names)))
    rel = np.asarray(result.rel_std_pct, dtype=float)
    history: list[EliminationStep] = []
    while len(keep) > min_parameters:
        worst = keep[int(np.argmax(rel))]  # largest relative σ (inf first)
        trial = [j for j in keep if j != worst]
        sigma_pe, trial_rel = _trial(system, trial)
        accepted = sigma_pe < threshold * sigma0
        history.append(EliminationStep(result.names[worst], sigma_pe, sigma_pe / sigma0, len(trial), accepted))
        if not accepted:
            break
        keep, rel = trial, trial_rel
    return _final(result, keep, history, rcond)


def _final(result: IdentificationResult, keep: list[int], history: list[EliminationStep], rcond: float) -> IdentificationResult:
    """Full result (statistics, per-joint residuals) of the kept columns."""
    names = [result.names[j] for j in keep]
    joint_systems = [s.select(keep) for s in result.joint_systems]
    if joint_systems and result.weights.size == len(joint_systems):
        system = stack_systems(joint_systems, result.weights)
    else:
        system = result.system.select(keep)
    return solve_system(
        system,
        names,
        joint_systems=joint_systems,
        weights=result.weights if joint_systems else None,
        method="essential",
        history=tuple(history),
        rcond=rcond,
    )
