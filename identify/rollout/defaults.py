"""Defaults of the rollout validation (standard library only: ``rx90 predict --help`` shows them
without importing MuJoCo or the model)."""
from __future__ import annotations

import math

__all__ = ["DEFAULT_START_VELOCITY", "FIGURE_WINDOWS", "MAX_STEP_S", "START_VELOCITIES", "window_lengths"]

#: Longest MuJoCo step [s] (MuJoCo's own default timestep): a recording's period is divided into the
#: fewest equal steps no longer than this (500 Hz and 1 kHz logs: one step a sample; 100 Hz: five).
MAX_STEP_S = 0.002
#: Where a window's start velocity comes from: "filtered", the derivative of the fit's processing
#: (q filtered at the fit's cut-off, zero phase, central differences, at the recording's own rate);
#: "recorded", the recording's own q̇ column (a controller's, when the log has one).
START_VELOCITIES = ("filtered", "recorded")
DEFAULT_START_VELOCITY = "filtered"
#: Windows per window length whose trajectories are kept for the report's figure.
FIGURE_WINDOWS = 4


def window_lengths(text: str | float | tuple | list) -> tuple[float, ...]:
    """Window lengths [s] from ``"0.25"``, ``"0.25,0.5"`` or numbers: each finite and > 0, in the
    order given, repeats dropped; ValueError naming the value otherwise."""
    items = text.split(",") if isinstance(text, str) else (list(text) if isinstance(text, (tuple, list)) else [text])
    out: list[float] = []
    for item in items:
        try:
            value = float(item)
        except (TypeError, ValueError):
            raise ValueError(f"rollout window: expected seconds like 0.25 or 0.25,0.5, got {item!r}") from None
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"rollout window must be a duration > 0 s, got {str(item).strip()}")
        if value not in out:
            out.append(value)
    if not out:
        raise ValueError("rollout window: no length given (seconds, e.g. 0.25 or 0.25,0.5)")
    return tuple(out)
