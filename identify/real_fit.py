"""Deprecated: :func:`fit_recordings` is :func:`identify.fit` with a :class:`Processing`."""
from __future__ import annotations

import warnings
from typing import Any, Sequence

import rx90sym

from identify.fitting import Fit, fit
from identify.observation.processing import DEFAULT_MIN_VELOCITY, Processing

__all__ = ["Fit", "fit_recordings"]


def fit_recordings(robot: rx90sym.Robot, recordings: Sequence[Any], method: str = "wls", base: Any = None,
                   cutoff: float | None = None, decimate_to: float | None = 50.0,
                   min_velocity: float | None = DEFAULT_MIN_VELOCITY, rest: str | None = None,
                   delay: float | str = 0.0, spring: bool = True, estimate: bool = False,
                   **consistent_options: Any) -> Fit:
    """Deprecated: ``identify.fit(robot, recordings, Processing(...), method, base=base)``."""
    warnings.warn("identify.fit_recordings is deprecated: use identify.fit(robot, recordings, "
                  "Processing(...), method)", DeprecationWarning, stacklevel=2)
    processing = Processing(cutoff=cutoff, decimate_to=decimate_to, min_velocity=min_velocity, rest=rest,
                            delay=delay, estimate_delay=estimate, spring=spring)
    return fit(robot, recordings, processing, method, base=base, **consistent_options)
