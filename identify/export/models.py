"""A fit's identified model where users need it: a URDF, an MJCF (rx90sym.write_urdf / write_mjcf).

The model of a fit is :func:`identify.rollout.model.simulator_parameters` (the one place that says
which parameters a fit's simulator model holds: what the rollout validation rolls out is what is
exported); the exported model is driven by the recordings' (controller) joint angles.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import rx90sym

from identify.rollout.model import simulator_parameters

__all__ = ["export_mjcf", "export_urdf"]


def export_urdf(fit: Any, path: str | Path, payload: Mapping[str, float] | None = None) -> list[Path]:
    """The fit's robot as a URDF (and its companion JSON): rx90sym.write_urdf; payload: XXc..Mc."""
    return rx90sym.write_urdf(*simulator_parameters(fit), path, payload=payload)


def export_mjcf(fit: Any, path: str | Path, payload: Mapping[str, float] | None = None) -> list[Path]:
    """The fit's robot as MJCF (and its companion JSON): rx90sym.write_mjcf; payload: XXc..Mc."""
    return rx90sym.write_mjcf(*simulator_parameters(fit), path, payload=payload)
