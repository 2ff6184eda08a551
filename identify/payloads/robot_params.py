"""The robot's known parameters of payload method 1 (eq. 22): from a fit, a fit file, its result, or values.

A :class:`~identify.fitting.fit_result.Fit` (or its file) brings its identified model (``Fit.model_result``:
its columns, the torque offsets and friction columns with it) and its processing (cut-off, decimation, rest threshold and
policy, torque delay, spring; its drive gains and angle convention for files): method 1 then moves
exactly the fit's model of the robot to the right-hand side, on the rows that fit was made of. A
result, or a dict of base or standard parameter values, brings values only: the columns are the
symbolic base parameters with the torque offsets OFFj it names, the processing the one given.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

import rx90sym

from identify.fitting.fit_result import Fit, load_fit
from identify.fitting.validation import base_vector
from identify.observation.offsets import offset_base

__all__ = ["KnownRobot", "known_robot"]


@dataclass(frozen=True, eq=False)
class KnownRobot:
    """The known part of eq. 22: the columns ``base``, their values ``beta``, and, from a fit, its
    ``processing`` (keyword arguments of :func:`identify.payload`), ``gains`` and ``convention``."""

    base: Any
    beta: np.ndarray
    processing: dict[str, Any] | None = None
    gains: Any = None
    convention: str | None = None


def _of_fit(robot: rx90sym.Robot, fit: Fit, where: str) -> KnownRobot:
    name = fit.model.robot
    if name != robot.name or fit.robot.n != robot.n:
        raise ValueError(f"robot_params {where}: a fit of robot {name!r} ({fit.robot.n} joints), not of "
                         f"{robot.name!r} ({robot.n} joints)")
    processing = {"cutoff": fit.cutoff, "decimate_to": fit.decimate_to, "min_velocity": fit.min_velocity,
                  "rest": fit.rest, "delay": fit.delay, "spring": fit.processing.spring}
    model = fit.model_result  # the identified model: what predicts, and what the payload is set against
    columns = fit.columns_of(model)
    return KnownRobot(columns, base_vector(model, columns, fit.robot), processing, fit.gains, fit.model.convention)


def _of_values(robot: rx90sym.Robot, base: Any, values: dict[str, float]) -> KnownRobot:
    if set(values) <= set(robot.parameter_names) and not set(values) <= set(base.names):
        return KnownRobot(base, base.K @ robot.parameter_vector(values, strict=False))
    # Torque offsets a fit's cross-validated choice gave (OFFj beyond the robot's own base).
    offsets = [int(n[3:]) - 1 for n in values
               if n.startswith("OFF") and n[3:].isdigit() and n not in base.names and 1 <= int(n[3:]) <= robot.n]
    base = offset_base(base, offsets)
    unknown = set(values) - set(base.names)
    if unknown:
        raise ValueError(f"robot_params: {sorted(unknown)[:5]} are not base parameters of {robot.name!r} (nor torque "
                         f"offsets OFFj); a fit with other columns (a friction form's) is given as the Fit or its file")
    # Parameters of the base set left out (e.g. an essential set) count as 0.
    return KnownRobot(base, np.array([values.get(n, 0.0) for n in base.names]))


def known_robot(robot: rx90sym.Robot, base: Any, robot_params: Any) -> KnownRobot:
    """Method 1's known part from ``robot_params``: a Fit, a fit file (path), an IdentificationResult or
    a dict of base (with OFFj) or standard parameter values; ``base``: the symbolic base of a result or
    a dict."""
    if robot_params is None:
        raise ValueError("method 1 needs the robot's parameters (robot_params): a Fit, a fit file, its result, "
                         "or a dict of base or standard parameter values")
    if isinstance(robot_params, Fit):
        return _of_fit(robot, robot_params, "(a Fit)")
    if isinstance(robot_params, (str, os.PathLike)):
        return _of_fit(robot, load_fit(robot_params), str(robot_params))  # its own robot: its own columns
    values = robot_params.as_dict() if hasattr(robot_params, "as_dict") else dict(robot_params)
    return _of_values(robot, base, values)
