"""A fit's identified model where users need it: a URDF, an MJCF (rx90sym.write_urdf / write_mjcf).

Only a physically consistent fit (method "consistent") holds bodies a simulator accepts: its
standard parameters; the exported model is driven by the recordings' (controller) joint angles.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import rx90sym

__all__ = ["export_mjcf", "export_urdf", "fit_standard"]


def fit_standard(fit: Any) -> dict[str, float]:
    """The standard parameters of a consistent ``fit`` (identify.Fit), checked against its robot.

    Raises ValueError for another method's fit (base parameters, no bodies)."""
    method = fit.result.method
    standard = getattr(fit.result, "standard", None)
    if method != "consistent" or not standard:
        raise ValueError(f"a {method} fit holds base parameters, not physical bodies: identify with the "
                         f"consistent method to export a model")
    return rx90sym.nominal_parameters(fit.robot, dict(standard))


def export_urdf(fit: Any, path: str | Path, payload: Mapping[str, float] | None = None) -> list[Path]:
    """The fit's robot as a URDF (and its companion JSON): rx90sym.write_urdf; payload: XXc..Mc."""
    return rx90sym.write_urdf(fit.robot, fit_standard(fit), path, payload=payload)


def export_mjcf(fit: Any, path: str | Path, payload: Mapping[str, float] | None = None) -> list[Path]:
    """The fit's robot as MJCF (and its companion JSON): rx90sym.write_mjcf; payload: XXc..Mc."""
    return rx90sym.write_mjcf(fit.robot, fit_standard(fit), path, payload=payload)
