"""The excitation criteria's names and defaults (standard library only: ``rx90 excite --help``
shows them without importing CasADi)."""
from __future__ import annotations

__all__ = ["OBJECTIVES", "DEFAULT_CRITERION", "FALLBACK_CRITERION"]

#: Criteria of :func:`excitation.objective.make_objective` (module docstring of excitation.objective).
OBJECTIVES = ("cond", "cond-nominal", "cond-columns", "logdet", "sigma")
DEFAULT_CRITERION = "sigma"         # chosen with benchmarks/compare_criteria.py (docs/excitation.md)
FALLBACK_CRITERION = "cond-columns"  # the default when no nominal parameters are known
