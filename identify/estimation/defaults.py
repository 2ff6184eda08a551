"""Defaults of the identified model (standard library only: ``rx90 identify --help`` shows them
without importing the estimators)."""
from __future__ import annotations

__all__ = ["DIVERGENCES", "DEFAULT_DIVERGENCE", "DEFAULT_PRIOR"]

#: How the identified model's bodies are weighed against the prior's
#: (identify.estimation.consistency.body_prior): a per-link scaled Gaussian on the standard
#: parameters, or the log-det divergence of the pseudo-inertias.
DIVERGENCES = ("gaussian", "entropic")
DEFAULT_DIVERGENCE = "gaussian"
#: The identified model's prior: the robot's own description (URDF inertials, robot-file [nominal]).
DEFAULT_PRIOR = "description"
