"""Friction at rest from the position history: a presliding state instead of Coulomb = 0.

At rest a joint is held by static friction anywhere in [-FS, FS]; the sign of a noisy speed says
nothing, so the ``zero-coulomb`` policy predicts 0 there. A real joint stopped after a motion keeps
(part of) the friction of that motion: the UR10e's joint 6 shows -2 N·m for seconds. The
``presliding`` policy replaces the Coulomb entry sign(q̇) at rest by a state z in [-1, 1] driven by
the positions only (never by the torque it is judged against): the *play operator*

    z_k = clip(z_{k-1} + (q_k - q_{k-1}) / delta, -1, 1),

a Dahl model with a sharp knee: z follows the direction of the last motion once the joint has
travelled ``delta`` rad in it, holds it at rest, and swings through 0 over ``delta`` rad when the
motion reverses. While moving, z = sign(q̇) after ``delta`` of travel: the moving rows keep the
Coulomb entry unchanged.
"""
from __future__ import annotations

import numpy as np

__all__ = ["PRESLIDING_TRAVEL", "presliding_state"]

#: Travel (rad) over which the presliding state goes from one sign to the other (docs/real-logs.md).
PRESLIDING_TRAVEL = 2e-3


def presliding_state(q: np.ndarray, travel: float = PRESLIDING_TRAVEL) -> np.ndarray:
    """z (N,) of the play operator (module docstring) along the positions ``q`` (N,) [rad]; z_0 = 0."""
    if not travel > 0:
        raise ValueError(f"presliding travel must be a positive angle in rad, got {travel!r}")
    steps = np.diff(np.asarray(q, dtype=float)) / travel
    z = np.empty(steps.size + 1)
    z[0] = 0.0
    for k, s in enumerate(steps, start=1):
        z[k] = min(1.0, max(-1.0, z[k - 1] + s))
    return z
