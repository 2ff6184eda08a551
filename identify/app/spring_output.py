"""What ``rx90 identify`` says about the spring it used: given (placeholder or not) or identified."""
from __future__ import annotations

from typing import Any

import numpy as np

import rx90sym
from identify.observation.spring_fit import SpringBase, spring_base, spring_torque

from .common import UsageError, progress, spring_notice


def attach_spring(robot: rx90sym.Robot, spring_model: Any, validate: str | None, method: str) -> SpringBase | None:
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


def spring_summary(robot: rx90sym.Robot, sb: SpringBase | None, res: Any, recs: list) -> tuple[dict, str]:
    """JSON entry and printed lines describing the spring the identification used."""
    if sb is None:
        if robot.spring is None:
            return {"mode": "none"}, "spring: none"
        return {"mode": "given", **robot.spring.describe()}, robot.spring.label()
    values = dict(zip(res.names, res.values))
    stds = dict(zip(res.names, res.std))
    coefficients = {n: {"value": float(values[n]), "std": float(stds[n])} for n in sb.kept}
    j = sb.model.joint
    angles = np.concatenate([r.q[:, j] for r in recs])
    grid = np.linspace(angles.min(), angles.max(), 41)
    tau, sigma = spring_torque(res, sb, grid)
    entry = {"mode": "identified", "joint": j + 1, "model": type(sb.model).__name__,
             "coefficients": coefficients, "grouped": list(sb.grouped),
             "grouped_note": "spanned by the rigid-body model: their part of the spring torque is "
                             "held by the base parameters (e.g. the first harmonic by MX2R/MY2)",
             "torque_on_visited_range": {"angle_rad": grid.tolist(), "torque": tau.tolist(),
                                         "std": sigma.tolist()}}
    lines = [f"spring on joint {j + 1}, identified ({type(sb.model).__name__}; grouped with the "
             f"rigid-body parameters: {', '.join(sb.grouped) or 'none'})"]
    lines += [f"  {n:10s} {c['value']:12.5g} +- {c['std']:.3g}" for n, c in coefficients.items()]
    lines.append(f"  torque on the visited range [{grid[0]:.3g}, {grid[-1]:.3g}] rad: max sigma "
                 f"{sigma.max():.3g} N m (without the grouped terms)")
    return entry, "\n".join(lines)
