"""Deprecated entry point: use :func:`identify.fit` (one Processing, one Fit).

``identify.identify`` is kept for one release as a thin wrapper with its former defaults
(``min_velocity=None, rest="drop"``); ConsistentResult and consistent_fit live in
identify.estimation.consistent_fit.
"""
from __future__ import annotations

import warnings
from typing import Any, Sequence

import rx90sym

from identify.estimation.consistent_fit import ConsistentResult, consistent_fit  # noqa: F401 (re-exported)
from identify.estimation.results import IdentificationResult
from identify.observation.matrix import Observation
from identify.observation.processing import Processing
from identify.validation import Validation, predict, validate  # noqa: F401 (re-exported)

__all__ = ["ConsistentResult", "consistent_fit", "identify"]


def identify(robot: rx90sym.Robot, recordings: Sequence[Any], method: str = "wls", base: Any = None,
             cutoff: float | None = None, decimate_to: float | None = 50.0,
             min_velocity: float | None = None, spring: bool = True,
             observation: Observation | None = None, rest: str = "drop", delay: float = 0.0,
             **consistent_options: Any) -> IdentificationResult:
    """Deprecated: ``identify.fit(robot, recordings, Processing(...), method).result``."""
    warnings.warn("identify.identify is deprecated: use identify.fit(robot, recordings, Processing(...), "
                  "method).result", DeprecationWarning, stacklevel=2)
    from identify.fitting import fit

    processing = Processing(cutoff=cutoff, decimate_to=decimate_to, min_velocity=min_velocity, rest=rest,
                            delay=delay, estimate_delay=False, spring=spring, cross_validate=False)
    return fit(robot, recordings, processing, method, base=base, observation=observation,
               **consistent_options).result
