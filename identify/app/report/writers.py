"""Write the reports of the commands: the JSON record they print, plus the figures of their results."""
from __future__ import annotations

import os
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Mapping

import numpy as np

import rx90sym

from .figures import figure, parameter_figure, residual_figure, torque_figure, trajectory_figure
from .identify_page import identify_page
from .page import write_page
from .payload_pages import gains_page, payload_page
from .rollout_page import rollout_figures


def _prior(robot: rx90sym.Robot, record: Mapping[str, Any]) -> dict[str, float] | None:
    """The standard parameters of the consistent fit's prior (beside its bodies), None without one."""
    prior = record.get("prior")
    if not isinstance(prior, Mapping):
        return None
    source = str(prior.get("source", ""))
    try:
        return rx90sym.nominal_parameters(robot, source if Path(source).is_file() else None)
    except ValueError:
        return None


def write_identify_report(path: str | os.PathLike, robot: rx90sym.Robot, record: Mapping[str, Any],
                          result: Any, recording: Any, validation: Any, fit_prediction: Any,
                          spring_text: str = "") -> Path:
    """The identification report from the JSON ``record`` and the objects behind its figures."""
    figures: dict[str, list] = {"parameters": [figure("fig-parameters", "Base parameters with 2σ bars",
                                                      parameter_figure(result))],
                                "fit": [figure("fig-torques", f"Measured and predicted torques on {fit_prediction.source}",
                                               torque_figure(fit_prediction, fit_prediction.source)),
                                        figure("fig-residuals", "Residuals per joint [N·m]",
                                               residual_figure(fit_prediction, "Residuals"))],
                                "trajectory": [figure("fig-trajectory", f"Joint positions of {recording.source}",
                                                      trajectory_figure(np.asarray(recording.t), np.asarray(recording.q)))]}
    if validation is not None:
        figures["validation"] = [figure("fig-validation", f"Held-out torques on {validation.source} "
                                        "(grey: joint at rest)", torque_figure(validation, validation.source))]
        figures["rollout"] = list(rollout_figures(validation.rollout))
    prior = _prior(robot, record) if record.get("standard") else None
    return write_page(path, identify_page(record, figures, prior, spring_text))


def write_payload_report(path: str | os.PathLike, record: Mapping[str, Any], result: Any) -> Path:
    """The payload report; the figure shows the estimates with 2σ bars beside the a priori values."""
    fig = figure("fig-payload", "Payload parameters with 2σ bars (×: a priori)",
                 parameter_figure(result, result.a_priori, "Payload parameters with 2σ"))
    return write_page(path, payload_page(record, (fig,)))


def write_gains_report(path: str | os.PathLike, record: Mapping[str, Any]) -> Path:
    """The drive-gain report; the figure shows each gain with its 2σ bar."""
    k = np.asarray(record["gains"], dtype=float)
    std = np.array([np.nan if s is None else s for s in record.get("std") or [None] * len(k)], dtype=float)
    shown = SimpleNamespace(names=[f"k{j}" for j in range(1, len(k) + 1)], values=k, std=np.nan_to_num(std))
    fig = figure("fig-gains", "Drive gains with 2σ bars [N·m/A]", parameter_figure(shown, None, "Drive gains with 2σ"))
    return write_page(path, gains_page(record, (fig,)))

