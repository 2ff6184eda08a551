"""How recordings become the rows of the observation matrix: one record, one set of defaults.

Every entry point (:func:`identify.fit`, ``rx90 identify``, the fit file, prediction and
validation, payload runs) takes its signal processing from one :class:`Processing`, so the same
data gives the same result whichever way it enters. The defaults are those of ``rx90 identify``.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import Any

from identify.observation.friction import DEFAULT_FRICTION, FRICTION_FORMS

__all__ = ["Processing", "FRICTION_FORMS", "REST_POLICIES", "DEFAULT_MIN_VELOCITY", "DEFAULT_REST", "DEFAULT_DECIMATE_TO"]

#: Rest threshold [rad/s]: a joint slower than this is at rest (its Coulomb sign is unknown).
DEFAULT_MIN_VELOCITY = 0.05
#: What rest samples do: their rows are dropped, kept with a Coulomb term of 0, or kept with the
#: presliding state of the position history (identify.observation.friction).
REST_POLICIES = ("drop", "zero-coulomb", "presliding")
DEFAULT_REST = "zero-coulomb"
#: Rate after parallel filtering [Hz].
DEFAULT_DECIMATE_TO = 50.0


@dataclass(frozen=True)
class Processing:
    """The signal processing of one identification (defaults: those of ``rx90 identify``).

    cutoff [Hz]: Butterworth cut-off for q (None: chosen on the recordings, then recorded);
    decimate_to [Hz]: rate after parallel filtering (None or 0: no decimation);
    min_velocity [rad/s]: rest threshold (None or 0: no rest handling);
    rest: "drop" (rest rows removed) | "zero-coulomb" (kept with Coulomb term 0) | "presliding"
    (kept with the presliding state times its own magnitude FPj);
    delay: torque lag behind the positions [s] compensated, or "auto" (estimated);
    estimate_delay: estimate the lag even when it is not compensated, to report it (~40
    least-squares fits);
    spring: add the robot's spring torque to the measured torque (False when the spring is
    identified with the other parameters);
    friction: the friction form of the moving rows, one of FRICTION_FORMS ("coulomb"; "tanh",
    "stribeck": velocity scale per joint by separable least squares, identify.estimation.separable);
    cross_validate: choose the cut-off, the decimation and the rest policy on the torques by
    blocked cross-validation (:mod:`identify.observation.cross_validation`; ``cutoff`` must be
    None); the fit records the choice and its candidate table.
    """

    cutoff: float | None = None
    decimate_to: float | None = DEFAULT_DECIMATE_TO
    min_velocity: float | None = DEFAULT_MIN_VELOCITY
    rest: str = DEFAULT_REST
    delay: float | str = 0.0
    estimate_delay: bool = True
    spring: bool = True
    cross_validate: bool = False
    friction: str = DEFAULT_FRICTION

    def __post_init__(self) -> None:
        # 0 means "none" for the rate and the threshold: one spelling inside (None).
        object.__setattr__(self, "decimate_to", self.decimate_to or None)
        object.__setattr__(self, "min_velocity", self.min_velocity or None)
        for name in ("cutoff", "decimate_to", "min_velocity"):
            value = getattr(self, name)
            if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"processing: {name} must be a positive number or None, got {value!r}")
        if self.cross_validate and self.cutoff is not None:
            raise ValueError("processing: a cut-off is given and cross_validate asks to choose one: give one of them")
        if self.friction not in FRICTION_FORMS:
            raise ValueError(f"processing: friction must be one of {FRICTION_FORMS}, got {self.friction!r}")
        if self.rest not in REST_POLICIES:
            raise ValueError(f"processing: rest must be one of {REST_POLICIES}, got {self.rest!r}")
        if not (self.delay == "auto" or (isinstance(self.delay, (int, float)) and math.isfinite(self.delay))):
            raise ValueError(f"processing: delay must be 'auto' or a number of seconds, got {self.delay!r}")

    def observation_options(self) -> dict[str, Any]:
        """Keyword arguments of :func:`identify.observation_matrix` (the delay apart: it may be 'auto')."""
        return {"cutoff": self.cutoff, "decimate_to": self.decimate_to, "min_velocity": self.min_velocity,
                "rest": self.rest, "spring": self.spring}

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_json(cls, d: dict[str, Any], where: str = "processing") -> "Processing":
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(d) - names)
        if unknown:
            raise ValueError(f"{where}: unknown processing field(s) {', '.join(unknown)}")
        return cls(**d)
