"""One identification as a user runs it on a real log: rest mask, torque delay, one filtering.

:func:`fit_recordings` chains the steps of ``rx90 identify`` (delay estimate, observation matrix
with the rest policy, least squares) and returns what ``predict``/``validate`` need to process a
held-out recording exactly like the fitted ones (:meth:`Fit.filtering`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import rx90sym

from identify.signal.delay import DelayEstimate, estimate_delay
from identify.identification import identify
from identify.observation.matrix import DEFAULT_MIN_VELOCITY, DEFAULT_REST, Observation, observation_matrix
from identify.estimation.results import IdentificationResult

__all__ = ["Fit", "fit_recordings"]


@dataclass(frozen=True, eq=False)
class Fit:
    """result: the identification; observation: its W, Y and filtering (cut-off, rate, notes);
    delay_estimate: the lag found (None when not estimated); delay [s]: the lag compensated;
    decimate_to [Hz] (None: none), min_velocity [rad/s] (None: no rest mask), rest."""

    result: IdentificationResult
    observation: Observation
    delay_estimate: DelayEstimate | None
    delay: float
    decimate_to: float | None
    min_velocity: float | None
    rest: str

    @property
    def cutoff(self) -> float:
        return self.observation.cutoffs[0]

    def filtering(self, spring: bool = True) -> dict[str, Any]:
        """Keyword arguments of :func:`identify.predict` that reuse this fit's processing."""
        return {"cutoff": self.cutoff, "decimate_to": self.decimate_to, "min_velocity": self.min_velocity,
                "delay": self.delay, "spring": spring, "rest": self.rest}


def fit_recordings(robot: rx90sym.Robot, recordings: Sequence[Any], method: str = "wls", base: Any = None,
                   cutoff: float | None = None, decimate_to: float | None = 50.0,
                   min_velocity: float | None = DEFAULT_MIN_VELOCITY, rest: str = DEFAULT_REST,
                   delay: float | str = 0.0, spring: bool = True, estimate: bool = False,
                   **consistent_options: Any) -> Fit:
    """Identify ``robot`` on ``recordings`` with the real-data steps.

    cutoff [Hz] (None: chosen on the recordings), decimate_to [Hz] (None or 0: none),
    min_velocity [rad/s] (None or 0: no rest mask), rest ("drop" | "zero-coulomb"),
    delay: torque lag [s] to compensate, or "auto" (the estimate); estimate: estimate the lag
    even when it is not compensated (to report it; ~40 least-squares fits). Other keyword arguments go to
    :func:`identify.identify` (method "consistent").
    """
    if not (delay == "auto" or isinstance(delay, (int, float))):
        raise ValueError(f"delay must be 'auto' or a number of seconds, got {delay!r}")
    base = base if base is not None else rx90sym.base_parameters(robot)
    decimate_to = decimate_to or None
    min_velocity = min_velocity or None
    common = dict(base=base, cutoff=cutoff, decimate_to=decimate_to, min_velocity=min_velocity,
                  rest=rest, spring=spring)
    found = estimate_delay(robot, recordings, **common) if (estimate or delay == "auto") else None
    lag = found.delay if delay == "auto" else float(delay)
    obs = observation_matrix(robot, recordings, delay=lag, **common)
    result = identify(robot, recordings, method=method, base=base, observation=obs, **consistent_options)
    return Fit(result, obs, found, lag, decimate_to, min_velocity, rest)
