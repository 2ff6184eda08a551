"""How recordings become the rows of the observation matrix: one record, one set of defaults.

Every entry point (:func:`identify.fit`, ``rx90 identify``, the fit file, prediction and
validation, payload runs) takes its signal processing from one :class:`Processing`, so the same
data gives the same result whichever way it enters. The defaults are those of ``rx90 identify``.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace
from typing import Any

from identify.observation.defaults import (DEFAULT_DECIMATE_TO, DEFAULT_DELAY, DEFAULT_FRICTION, DEFAULT_MIN_VELOCITY,
                                           DEFAULT_REST, FRICTION_FORMS, REST_POLICIES)

__all__ = ["Processing", "FRICTION_FORMS", "REST_POLICIES", "CROSSING_SECONDS", "CROSSING_TRAVEL",
           "DEFAULT_MIN_VELOCITY", "DEFAULT_REST", "DEFAULT_DECIMATE_TO", "RestPolicy", "rest_per_joint",
           "drops_rest", "has_policy", "predicted_rest", "rest_label", "FrictionForm", "friction_label",
           "has_smooth_friction", "uniform"]

#: Longest pass below the rest threshold [s] that "crossing" treats as a motion (docs/real-logs.md).
CROSSING_SECONDS = 0.5
#: Position range [rad] over which a longer pass below the threshold is a slow motion, not a rest.
CROSSING_TRAVEL = 5e-4
#: One policy for every joint, or one per joint (joint 1 first).
RestPolicy = str | tuple[str, ...]


def rest_per_joint(rest: RestPolicy | None, n: int) -> tuple[str, ...]:
    """The policy of each of ``n`` joints (None: :data:`DEFAULT_REST` on every joint)."""
    rest = DEFAULT_REST if rest is None else rest
    policies = (rest,) * n if isinstance(rest, str) else tuple(rest)
    if len(policies) != n:
        raise ValueError(f"rest: {len(policies)} policies given for {n} joints")
    return policies


def has_policy(rest: RestPolicy | None, name: str) -> bool:
    """Whether some joint follows policy ``name``."""
    return rest == name or (not isinstance(rest, str) and rest is not None and name in rest)


def drops_rest(rest: RestPolicy | None) -> bool:
    """Whether some joint's rest rows are dropped (its rows then follow ``FilteredMotion.usable``)."""
    return has_policy(rest, "drop")


def predicted_rest(rest: RestPolicy | None) -> RestPolicy:
    """The policy a prediction uses: every sample is predicted, so a dropped joint's rest samples
    take Coulomb = 0; the other policies stay."""
    swap = {"drop": "zero-coulomb"}
    rest = DEFAULT_REST if rest is None else rest
    return swap.get(rest, rest) if isinstance(rest, str) else tuple(swap.get(r, r) for r in rest)


def rest_label(rest: RestPolicy | None) -> str:
    """The policy in words: "zero-coulomb", or "j1 none, j2 presliding, ..." per joint."""
    rest = DEFAULT_REST if rest is None else rest
    if isinstance(rest, str) or len(set(rest)) == 1:
        return rest if isinstance(rest, str) else rest[0]
    return ", ".join(f"j{j} {r}" for j, r in enumerate(rest, start=1))


def _check_rest(rest: Any, where: str) -> RestPolicy | None:
    if rest is None or (isinstance(rest, str) and rest in REST_POLICIES):
        return rest
    if isinstance(rest, (list, tuple)) and rest and all(isinstance(r, str) and r in REST_POLICIES for r in rest):
        return tuple(rest)
    raise ValueError(f"{where}: rest must be one of {REST_POLICIES} or one of them per joint, got {rest!r}")
#: One friction form for every joint, or one per joint (joint 1 first), like :data:`RestPolicy`.
FrictionForm = str | tuple[str, ...]


def uniform(values: FrictionForm | None) -> FrictionForm | None:
    """One name where a per-joint tuple holds the same name on every joint (one spelling inside)."""
    return values[0] if isinstance(values, tuple) and values and len(set(values)) == 1 else values


def has_smooth_friction(friction: FrictionForm | None) -> bool:
    """Whether some joint's friction form has a velocity scale (anything but Coulomb)."""
    forms = (friction,) if isinstance(friction, str) or friction is None else friction
    return any(f not in (None, DEFAULT_FRICTION) for f in forms)


def friction_label(friction: FrictionForm | None) -> str:
    """The form in words: "tanh", or "j1 tanh, j2 coulomb, ..." per joint."""
    friction = uniform(DEFAULT_FRICTION if friction is None else friction)
    return friction if isinstance(friction, str) else ", ".join(f"j{j} {f}" for j, f in enumerate(friction, start=1))


def _check_friction(friction: Any, where: str) -> FrictionForm | None:
    if friction is None or (isinstance(friction, str) and friction in FRICTION_FORMS):
        return friction
    if (isinstance(friction, (list, tuple)) and friction
            and all(isinstance(f, str) and f in FRICTION_FORMS for f in friction)):
        return uniform(tuple(friction))
    raise ValueError(f"{where}: friction must be one of {FRICTION_FORMS} or one of them per joint, got {friction!r}")


@dataclass(frozen=True)
class Processing:
    """The signal processing of one identification (defaults: those of ``rx90 identify``).

    cutoff [Hz]: Butterworth cut-off for q (None: chosen on the recordings, then recorded);
    decimate_to [Hz]: rate after parallel filtering (None or 0: no decimation);
    min_velocity [rad/s]: rest threshold (None or 0: no rest handling);
    rest: "drop" (rest rows removed) | "zero-coulomb" (kept with Coulomb term 0) | "presliding"
    (kept with the presliding state times its own magnitude FPj) | "none" (kept as they are) |
    "crossing" (see REST_POLICIES), or a tuple of them, one per joint; None: open (chosen per joint
    by the cross-validation, else :data:`DEFAULT_REST`);
    delay: torque lag behind the positions [s] compensated, or "auto" (estimated);
    estimate_delay: estimate the lag even when it is not compensated, to report it (~40
    least-squares fits);
    spring: add the robot's spring torque to the measured torque (False when the spring is
    identified with the other parameters);
    friction: the friction form of the moving rows, one of FRICTION_FORMS ("coulomb"; "tanh",
    "stribeck": velocity scale per joint by separable least squares, identify.friction.scales),
    or a tuple of them, one per joint (the same on every joint is kept as one name); None: open
    (chosen per joint by the cross-validation, :mod:`identify.friction.choice`, else
    :data:`DEFAULT_FRICTION`);
    cross_validate: choose the cut-off, the decimation and (where ``rest`` is None) the rest
    policy per joint on the torques by blocked cross-validation
    (:mod:`identify.selection.cross_validation`; ``cutoff`` must be None); None (default): on
    whenever no cut-off is given (:attr:`cross_validates`); the fit records the choice and its
    candidate table.
    """

    cutoff: float | None = None
    decimate_to: float | None = DEFAULT_DECIMATE_TO
    min_velocity: float | None = DEFAULT_MIN_VELOCITY
    rest: RestPolicy | None = None
    delay: float | str = DEFAULT_DELAY
    estimate_delay: bool = True
    spring: bool = True
    cross_validate: bool | None = None
    friction: FrictionForm | None = None

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
        object.__setattr__(self, "friction", _check_friction(self.friction, "processing"))
        object.__setattr__(self, "rest", _check_rest(self.rest, "processing"))
        if not (self.delay == "auto" or (isinstance(self.delay, (int, float)) and math.isfinite(self.delay))):
            raise ValueError(f"processing: delay must be 'auto' or a number of seconds, got {self.delay!r}")

    def observation_options(self) -> dict[str, Any]:
        """Keyword arguments of :func:`identify.observation_matrix` (the delay apart: it may be 'auto')."""
        return {"cutoff": self.cutoff, "decimate_to": self.decimate_to, "min_velocity": self.min_velocity,
                "rest": DEFAULT_REST if self.rest is None else self.rest, "spring": self.spring}

    def chosen(self, **values: Any) -> "Processing":
        """This processing with what was open now chosen (``cutoff`` [Hz], ``decimate_to`` [Hz], ``rest``,
        ``delay`` [s], ``friction``: the values a fit's passes use), nothing left to choose again."""
        return replace(self, cross_validate=False, **values)

    @property
    def friction_form(self) -> FrictionForm:
        """The friction form asked for (one, or one per joint), :data:`DEFAULT_FRICTION` where it is left open."""
        return DEFAULT_FRICTION if self.friction is None else self.friction

    @property
    def cross_validates(self) -> bool:
        """Whether the fit chooses its processing by cross-validation: as asked, else whenever no
        cut-off is given."""
        return self.cutoff is None if self.cross_validate is None else self.cross_validate

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_json(cls, d: dict[str, Any], where: str = "processing") -> "Processing":
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(d) - names)
        if unknown:
            raise ValueError(f"{where}: unknown processing field(s) {', '.join(unknown)}")
        return cls(**d)
