"""A fit's identified model where users need it: a URDF, an MJCF (rx90sym.write_urdf / write_mjcf).

Every fit's identified model holds bodies a simulator accepts: its standard parameters; the exported
model is driven by the recordings' (controller) joint angles.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import rx90sym

__all__ = ["export_mjcf", "export_urdf", "fit_standard"]


def fit_standard(fit: Any) -> dict[str, float]:
    """The standard parameters of ``fit``'s identified model (identify.Fit), checked against its robot.

    Raises ValueError for a fit without one (a fit file written before the identified model)."""
    model = getattr(fit, "model_result", fit.result)
    standard = getattr(model, "standard", None)
    if not standard:
        raise ValueError(f"this {fit.result.method} fit holds base parameters only, no physical bodies (a fit file "
                         f"written before the identified model): identify again to export a model")
    names = set(fit.robot.parameter_names)
    return rx90sym.nominal_parameters(fit.robot, {k: v for k, v in standard.items() if k in names})


def export_urdf(fit: Any, path: str | Path, payload: Mapping[str, float] | None = None) -> list[Path]:
    """The fit's robot as a URDF (and its companion JSON): rx90sym.write_urdf; payload: XXc..Mc."""
    return rx90sym.write_urdf(fit.robot, fit_standard(fit), path, payload=payload)


def export_mjcf(fit: Any, path: str | Path, payload: Mapping[str, float] | None = None) -> list[Path]:
    """The fit's robot as MJCF (and its companion JSON): rx90sym.write_mjcf; payload: XXc..Mc."""
    return rx90sym.write_mjcf(fit.robot, fit_standard(fit), path, payload=payload)
