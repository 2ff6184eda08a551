"""The error of a consistent fit that failed (light: the command line catches it without cvxpy)."""
from __future__ import annotations

__all__ = ["ConsistencyError"]


class ConsistencyError(ValueError):
    """The consistent least-squares problem could not be solved to optimality.

    Attributes:
        status: cvxpy status string (``"infeasible"``, ``"optimal_inaccurate"``,
            ``"solver_error"``, …) or ``"external_check_failed"``.
        solver: solver name (``"CLARABEL"``, ``"SCS"``).
    """

    def __init__(self, message: str, *, status: str, solver: str) -> None:
        super().__init__(message)
        self.status = status
        self.solver = solver
