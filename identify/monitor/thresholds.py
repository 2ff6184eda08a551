"""The contact thresholds ``rx90 identify`` stores in the fit file (``contact_thresholds_nm``)."""
from __future__ import annotations

from dataclasses import replace
from typing import Any, Sequence

from identify.monitor.log import MonitorInputError, calibrate, check_fit

__all__ = ["with_contact_thresholds"]


def with_contact_thresholds(fit: Any, recordings: Sequence[Any]) -> tuple[Any, str]:
    """(``fit`` with its contact-monitor thresholds [N·m] computed on ``recordings`` at the default
    observer gain (:func:`identify.monitor.log.calibrate`: the held-out validation recording when
    there is one, else the fitted ones, contact-free by assumption), ''); or (``fit`` unchanged, the
    reason) when the monitor cannot use the fit (``rx90 monitor`` then needs --calibrate)."""
    try:
        check_fit(fit)
        return replace(fit, contact_thresholds=calibrate(fit, list(recordings))), ""
    except (MonitorInputError, RuntimeError) as exc:  # RuntimeError: no C compiler for the observer
        return fit, str(exc)
