"""Physical consistency: pseudo-inertia LMIs (:mod:`.lmi`), the consistent least-squares
problem (:mod:`.problem`), the fit with its external check (:mod:`.fit`), and the consistency margin (:mod:`.margin`).
"""
from rx90sym.lazy import lazy_package

# Public name -> the module that defines it (imported on first use: a fast start).
_EXPORTS = {
    "INERTIAL_FIELDS": "identify.estimation.consistency.lmi",
    "BodyConsistency": "identify.estimation.consistency.lmi",
    "ConsistencyReport": "identify.estimation.consistency.lmi",
    "body_indices": "identify.estimation.consistency.lmi",
    "consistency_report": "identify.estimation.consistency.lmi",
    "pseudo_inertia": "identify.estimation.consistency.lmi",
    "consistency_margin": "identify.estimation.consistency.margin",
    "ConsistentSolution": "identify.estimation.consistency.fit",
    "consistent_least_squares": "identify.estimation.consistency.fit",
    "ConsistencyError": "identify.estimation.consistency.errors",
    "ConsistentProblem": "identify.estimation.consistency.problem",
    "build_consistent_problem": "identify.estimation.consistency.problem",
}

__all__ = ["INERTIAL_FIELDS", "BodyConsistency", "ConsistencyReport", "body_indices", "consistency_report",
           "pseudo_inertia", "consistency_margin", "ConsistencyError", "ConsistentProblem", "ConsistentSolution",
           "build_consistent_problem", "consistent_least_squares"]

lazy_package(__name__, _EXPORTS)
