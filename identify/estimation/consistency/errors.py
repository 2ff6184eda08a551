"""The errors of a solver that failed (light: the command line catches them without cvxpy)."""
from __future__ import annotations

__all__ = ["SolverError", "ConsistencyError"]


class SolverError(ValueError):
    """A numerical solver that failed (not the user's input): reported, the command line exits 1.

    Attributes:
        status: the solver's word for the failure (cvxpy's status string, ``"not_converged"``, …).
        solver: the solver's name (``"CLARABEL"``, ``"SCS"``, ``"L-BFGS-B"``).
    """

    def __init__(self, message: str, *, status: str, solver: str) -> None:
        super().__init__(message)
        self.status = status
        self.solver = solver


class ConsistencyError(SolverError):
    """The consistent least-squares problem could not be solved to optimality (status: cvxpy's
    ``"infeasible"``, ``"optimal_inaccurate"``, ``"solver_error"``, … or ``"external_check_failed"``)."""
