"""What ``rx90 identify`` says about the spring it used: given (placeholder or not) or identified."""
from __future__ import annotations

from typing import Any

import rx90sym
from identify.observation.spring_fit import BaseWithSpring, spring_base, spring_summary  # noqa: F401 (re-exported)

from .common import UsageError, progress, spring_notice


def attach_spring(robot: rx90sym.Robot, spring_model: Any, validate: str | None, method: str) -> BaseWithSpring | None:
    """The base parameters plus the spring's coefficients for ``--spring identify``, or None
    (then warns when the robot's spring is a placeholder)."""
    if spring_model is None:
        spring_notice(robot)
        return None
    if method == "consistent":
        raise UsageError("--spring identify works with --method wls or ols (the consistent fit has "
                         "no spring coefficients yet)")
    if validate is None:
        progress("warning: check the identified spring on a held-out motion (--validate FILE): "
                 "its coefficients have sigma bounds, but a basis can also fit noise")
    try:
        return spring_base(robot, spring_model)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
