"""A fit's identified model where users need it: a URDF, an MJCF (rx90sym.write_urdf / write_mjcf).

The model of a fit is :func:`identify.rollout.model.simulator_parameters` (the one place that says
which parameters a fit's simulator model holds: what the rollout validation rolls out is what is
exported); the exported model is driven by the recordings' (controller) joint angles.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from identify.rollout.model import simulator_parameters

__all__ = ["export_mjcf", "export_urdf", "model_text", "not_identified"]


def not_identified(fit: Any) -> list[str]:
    """What the exported model holds that the fit did not identify, in words: a joint whose torque the fit
    left out (not logged) keeps its friction, rotor inertia and offset from the prior (the companion's
    ``not_identified``; ``rx90 export`` prints it)."""
    left = getattr(fit.model, "torque_left_out", None) or ()
    return [f"joint {j}: its torque was not in the fit (not logged): its friction, rotor inertia and offset are "
            f"not identified (the description's, or 0), its link's body only as the other joints' torques see it"
            for j in left]


def model_text(fit: Any, kind: str, path: str | Path, payload: Mapping[str, float] | None = None) -> tuple[str, dict]:
    """(text, companion) of the fit's model as ``kind`` "urdf" or "mjcf" for ``path``; nothing written.
    payload: XXc..Mc on the flange. The companion says what the fit did not identify."""
    from rx90sym.mjcf_export import mjcf_export
    from rx90sym.urdf_export import urdf_export

    text, side = (urdf_export if kind == "urdf" else mjcf_export)(*simulator_parameters(fit), path, payload)
    return text, {**side, "not_identified": not_identified(fit)}


def export_urdf(fit: Any, path: str | Path, payload: Mapping[str, float] | None = None) -> list[Path]:
    """The fit's robot as a URDF (and its companion JSON): rx90sym.write_urdf's files; payload: XXc..Mc."""
    from rx90sym.model_export import write_model

    return write_model(path, *model_text(fit, "urdf", path, payload))


def export_mjcf(fit: Any, path: str | Path, payload: Mapping[str, float] | None = None) -> list[Path]:
    """The fit's robot as MJCF (and its companion JSON): rx90sym.write_mjcf's files; payload: XXc..Mc."""
    from rx90sym.model_export import write_model

    return write_model(path, *model_text(fit, "mjcf", path, payload))
