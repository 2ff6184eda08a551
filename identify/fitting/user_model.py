"""The model the user had: the description's rigid bodies as written, its friction and offsets fitted.

The second yardstick of every validation, exactly as the project's issue notes define it: Pinocchio's
RNEA with the description's own inertial parameters as written (:func:`rx90sym.nominal_parameters`: a
URDF's inertials, else the robot file's ``[nominal]`` table; a link whose inertials are not physical is
kept as written: a yardstick, not a prior), on the plain baseline's filtered q, q̇, q̈
(:mod:`identify.fitting.baseline`: 4th-order zero-phase Butterworth at 10 Hz at the recording's rate,
``numpy.gradient``), plus per joint [q̇ⱼ, sign q̇ⱼ, 1] fitted by ``numpy.linalg.lstsq(rcond=1e-10)`` to
τⱼ − RNEAⱼ (τ the measured torque plus the description's spring torque, as the baseline adds it) on the
fitted samples, 0.5 s trimmed at both ends of each segment; scored like the plain OLS, on the raw
measured torques. Where the description has no inertial parameters it is not computed, and says why.

RNEA(q, q̇, q̈; θ₀) = Φ θ₀, Φ the baseline's rigid-body regressor (10 columns per link in Pinocchio's
order, equal to Pinocchio's ``computeJointTorqueRegressor``): the model is the baseline's factors of
[W_j | y_j] (:class:`identify.fitting.baseline_factors.BaselineFactors`) solved with the rigid-body columns
fixed at θ₀, a least squares of 3 unknowns per joint; no pass over the data of its own.

Rotor inertia is not included, whatever the description holds: the definition is the description's
*inertial* parameters through RNEA, the 10 of each body; a URDF has no rotor inertia (Pinocchio's model
of it has a zero ``armature``), and the robot files' ``rotor_inertia`` are derived assumptions (N² J_m,
J_m by motor class), not a maker's figures; the coupled wrist's rotor terms (eqs. 16-18) have no RNEA
counterpart; and so both yardsticks have the same columns, fitted on the same factors.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

import rx90sym
from rx90sym.pinocchio_bridge import PINOCCHIO_ORDER

from identify.fitting.baseline import BASELINE_RCOND, LinearYardstick
from identify.fitting.baseline_factors import BaselineFactors

__all__ = ["USER_MODEL_DEFINITION", "UserModel", "described_bodies", "not_computed", "user_model", "user_values"]

USER_MODEL_DEFINITION = ("the model the user had: the description's rigid bodies as written (RNEA, no rotor "
                         "inertia) on q by a 4th-order zero-phase Butterworth at 10 Hz, numpy.gradient, plus "
                         "[dq_j, sign(dq_j), 1] per joint fitted by lstsq(rcond=1e-10) to tau_j - RNEA_j, 0.5 s "
                         "trimmed at both ends")


def described_bodies(robot: rx90sym.Robot) -> tuple[np.ndarray | None, str]:
    """(θ₀, where it comes from): the description's 10 rigid-body parameters of each link in Pinocchio's
    order (M, MX, MY, MZ, XX, XY, YY, XZ, YZ, ZZ; kg, kg m, kg m² in the link's frame) as written; or
    (None, why there are none) when the description has no inertial parameters."""
    described = robot.source or f"robot {robot.name!r}, built in memory"
    where = (f"the inertials of {described}" if getattr(robot, "urdf", None) is not None
             else f"the [nominal] table of {described}")
    try:
        nominal = rx90sym.nominal_parameters(robot)
    except ValueError as exc:
        return None, f"the description's inertial parameters could not be read ({exc})"
    if nominal is None:
        return None, f"the description ({described}) has no inertial parameters (no URDF inertials, no [nominal] table)"
    theta = np.array([float(nominal[f"{p}{j + 1}"]) for j in range(robot.n) for p in PINOCCHIO_ORDER])
    if not np.any(theta):
        return None, f"the description has no inertial parameters ({where}: every link's are 0)"
    return theta, where


def user_values(factors: BaselineFactors, theta: np.ndarray, without: int | None = None) -> tuple[np.ndarray, int]:
    """(values over the baseline's columns, rank): θ₀ in the rigid-body columns, and per joint its [FV, FS, OFF]
    by lstsq (rcond 1e-10) on the factors of every time block but ``without`` (the rank: of the friction
    columns, summed over the joints; 3 n when each joint's are independent)."""
    n, c = factors.n, factors.c
    rigid = theta.size
    values, rank = np.r_[theta, np.zeros(c - rigid)], 0
    for j in range(n):
        S = factors.stacked([j], without)
        own = rigid + 3 * j + np.arange(3)
        x, _, r, _ = np.linalg.lstsq(S[:, own], S[:, c] - S[:, :rigid] @ theta, rcond=BASELINE_RCOND)
        values[own], rank = x, rank + int(r)
    return values, rank


@dataclass(frozen=True, eq=False)
class UserModel(LinearYardstick):
    """The model the user had, fitted: values over ``names`` (:func:`identify.fitting.baseline.baseline_names`:
    the description's rigid bodies, then FVj, FSj, OFFj fitted), the fitted samples, the rank of the friction
    columns (summed over the joints), whether the spring torque was added, per joint residual RMS [N m] on
    the fitted samples, and where the bodies come from."""

    source: str = ""

    def to_json(self) -> dict[str, Any]:
        return {"computed": True, "definition": USER_MODEL_DEFINITION, "bodies_from": self.source,
                **self.fitted_json()}

    @classmethod
    def from_json(cls, d: dict[str, Any] | None) -> "tuple[UserModel | None, str]":
        """(the model, '') or (None, why there is none) from the fit file's ``user_model`` (None: a file
        without one)."""
        if d is None:
            return None, "not in the fit file (written before schema version 5, or without a baseline)"
        if not d.get("computed"):
            return None, str(d.get("reason") or "not computed")
        return cls(*cls.fitted_fields(d), str(d.get("bodies_from", ""))), ""


def not_computed(reason: str) -> dict[str, Any]:
    """The fit file's ``user_model`` where there is none, with the reason."""
    return {"computed": False, "definition": USER_MODEL_DEFINITION, "reason": reason}


def user_model(factors: BaselineFactors, theta: np.ndarray, names: tuple[str, ...], spring: bool,
               source: str) -> UserModel:
    """The model the user had (module docstring) from the baseline's factors and the description's bodies
    θ₀ (:func:`described_bodies`) taken from ``source``."""
    if factors.samples == 0:
        raise ValueError("the model the user had has no sample to fit (every segment shorter than 1 s)")
    values, rank = user_values(factors, theta)
    return UserModel(names, values, factors.samples, rank, bool(spring), factors.residual_rms(values), source)
