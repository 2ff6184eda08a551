"""Defaults and choices of the processing (standard library only: ``rx90 identify --help`` shows
them without importing the observation matrix)."""
from __future__ import annotations

__all__ = ["DEFAULT_DECIMATE_TO", "DEFAULT_DELAY", "DEFAULT_MIN_VELOCITY", "REST_POLICIES", "DEFAULT_REST", "FRICTION_FORMS", "DEFAULT_FRICTION"]

#: Rate after parallel filtering [Hz].
DEFAULT_DECIMATE_TO = 50.0
#: Torque lag behind the positions compensated [s] (its estimate is reported all the same).
DEFAULT_DELAY = 0.0
#: Rest threshold [rad/s]: a joint slower than this is at rest (its Coulomb sign is unknown).
DEFAULT_MIN_VELOCITY = 0.05
#: What rest samples do: their rows are dropped, kept with a Coulomb term of 0, kept with the
#: presliding state of the position history (identify.observation.rest), kept as they are
#: ("none": the Coulomb entry keeps the sign of the filtered speed, as without a rest threshold),
#: or "crossing": as they are through a pass below the threshold shorter than
#: :data:`identify.observation.processing.CROSSING_SECONDS` or travelling
#: :data:`identify.observation.processing.CROSSING_TRAVEL` or more (a reversal or a slow motion:
#: the friction follows it), with Coulomb 0 over a longer, still rest (where the sign of the speed
#: is the sign of noise).
REST_POLICIES = ("drop", "zero-coulomb", "presliding", "none", "crossing")
#: The policy where none is given and none is chosen by cross-validation.
DEFAULT_REST = "zero-coulomb"
#: Friction forms of the moving rows (docs/real-logs.md): "coulomb" FS·sign(q̇); "tanh" the smooth
#: Coulomb FS·tanh(q̇/vs); "stribeck" (FS + (FST − FS)·exp(−(q̇/vs)²))·sign(q̇). The last two are
#: linear in FS (FST) for a given velocity scale vs [rad/s], found by separable least squares
#: (identify.friction.scales). The cross-validation grid iterates this tuple.
FRICTION_FORMS = ("coulomb", "tanh", "stribeck")
DEFAULT_FRICTION = "coulomb"
