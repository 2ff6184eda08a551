"""Physical consistency: pseudo-inertia LMIs (:mod:`.lmi`), the consistent least-squares
problem (:mod:`.problem`), the fit with its external check (:mod:`.fit`), and the consistency margin (:mod:`.margin`)."""
from identify.estimation.consistency.lmi import (INERTIAL_FIELDS, BodyConsistency, ConsistencyReport, body_indices, consistency_report,
                  pseudo_inertia)
from identify.estimation.consistency.margin import consistency_margin
from identify.estimation.consistency.fit import ConsistentSolution, consistent_least_squares
from identify.estimation.consistency.problem import ConsistencyError, ConsistentProblem, build_consistent_problem

__all__ = ["INERTIAL_FIELDS", "BodyConsistency", "ConsistencyReport", "body_indices", "consistency_report",
           "pseudo_inertia", "consistency_margin", "ConsistencyError", "ConsistentProblem", "ConsistentSolution",
           "build_consistent_problem", "consistent_least_squares"]
