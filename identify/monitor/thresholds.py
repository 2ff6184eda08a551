"""The contact thresholds ``rx90 identify`` stores in the fit file (``contact_thresholds_nm``)."""
from __future__ import annotations

import warnings
from dataclasses import replace
from typing import Any, Sequence

from identify.monitor.log import MonitorInputError, calibrate, check_fit

__all__ = ["with_contact_thresholds"]


def with_contact_thresholds(fit: Any, recordings: Sequence[Any]) -> Any:
    """``fit`` with its contact-monitor thresholds [N·m] computed on ``recordings`` (the held-out
    validation recording when there is one, else the fitted ones: contact-free by assumption) at the
    default observer gain (:func:`identify.monitor.log.calibrate`); unchanged, with a warning, when
    the monitor cannot use the fit (then ``rx90 monitor`` needs --calibrate)."""
    try:
        check_fit(fit)
        return replace(fit, contact_thresholds=calibrate(fit, list(recordings)))
    except (MonitorInputError, RuntimeError) as exc:
        warnings.warn(f"contact thresholds not stored: {exc}", RuntimeWarning, stacklevel=2)
        return fit
