"""The covariance a consistent fit's prior is measured in: eq. 13's, inflated by the segment bootstrap.

Eq. 13 assumes white residuals; coloured ones make it optimistic. The prior fit
(:func:`identify.estimation.consistency.prior_fit.prior_fit`) keeps the unseen directions within a
budget of standard deviations of the best fit, so its covariance is eq. 13's times the square of the
median ratio of the segment bootstrap's σ to eq. 13's when that ratio is above 1 (white residuals
leave it as it is). The whole-signal fit and the block-by-block fit compute it alike: the bootstrap
of the toolkit's blocks (:data:`identify.estimation.bootstrap.BLOCK_S`), draws and seed 0, on W held
in memory or fed block by block (:class:`identify.estimation.bootstrap.SegmentBootstrap`).
"""
from __future__ import annotations

from typing import Any, Mapping

import numpy as np

__all__ = ["HONEST_SEED", "Fanout", "honest_covariance", "needs_honest_covariance"]

#: Seed of the segment bootstrap behind the honest covariance (whatever the fit's own bootstrap seed).
HONEST_SEED = 0


def honest_covariance(result: Any, bootstrap_std: np.ndarray) -> np.ndarray:
    """Eq. 13's covariance of ``result`` (an IdentificationResult: ``covariance``, ``std``) times the
    square of the median ratio ``bootstrap_std / std`` when above 1 (no finite ratio: eq. 13's, e.g. a
    recording too short for two bootstrap blocks)."""
    ratios = np.asarray(bootstrap_std, dtype=float) / np.where(result.std > 0, result.std, np.nan)
    ratios = ratios[np.isfinite(ratios)]
    return result.covariance * max(1.0, float(np.median(ratios)) if ratios.size else 1.0) ** 2


def needs_honest_covariance(method: str, options: Mapping[str, Any]) -> bool:
    """Whether a fit by ``method`` with the consistent fit's ``options`` needs the honest covariance: a
    consistent fit with a physical prior and no covariance given."""
    return method == "consistent" and options.get("physical_prior") is not None and "covariance" not in options


class Fanout:
    """Several :class:`~identify.estimation.bootstrap.SegmentBootstrap` fed the same rows (None left out)."""

    def __init__(self, *boots: Any) -> None:
        self.boots = [b for b in boots if b is not None]

    def add(self, joint: int, samples: np.ndarray, W: np.ndarray, Y: np.ndarray) -> None:
        for b in self.boots:
            b.add(joint, samples, W, Y)
