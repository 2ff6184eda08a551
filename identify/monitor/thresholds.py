"""The contact thresholds ``rx90 identify`` stores in the fit file (``contact_thresholds_nm``).

On data the fit has not seen: the held-out validation recording when there is one, else the
held-out blocks of the fitted recordings (the cross-validation's blocks: their time span cut into
:data:`HELD_OUT_BLOCKS` contiguous blocks of equal duration; per block, the fit's columns refitted
by its weighted least squares on the other blocks' rows of its own observation matrix, and the
observer of that fold's fit run over the block). The fitted data's own residual is smaller than
another motion's (the fit absorbed part of its noise and model error): on the Panda twin,
thresholds calibrated on the fitted run were 0.46-0.88 × those of another run and gave false
events on contact-free motion (docs/contact-monitor.md).
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any, Sequence

import numpy as np

from identify.io.blocks import BlockSource, MemorySource, block_source
from identify.monitor.contact import CALIBRATION_MARGIN, CALIBRATION_QUANTILE
from identify.monitor.defaults import DEFAULT_MONITOR_BLOCK
from identify.monitor.log import MonitorInputError, calibrate, check_fit, excess
from identify.selection.cross_validation import DEFAULT_BLOCKS
from identify.estimation.least_squares import IdentificationError, weighted_least_squares
from identify.selection.folds import time_folds

__all__ = ["HELD_OUT_BLOCKS", "held_out_thresholds", "with_contact_thresholds"]

#: Blocks of the held-out thresholds: the cross-validation's (identify.selection.cross_validation).
HELD_OUT_BLOCKS = DEFAULT_BLOCKS


def held_out_thresholds(fit: Any, recordings: Sequence[Any], blocks: int = HELD_OUT_BLOCKS,
                        quantile: float = CALIBRATION_QUANTILE, margin: float = CALIBRATION_MARGIN) -> np.ndarray:
    """Thresholds per joint [N·m] from the fitted ``recordings`` (those of ``fit``, whose observation
    matrix it holds; recordings or recording files): ``quantile`` of (|r_j| − d_j)⁺ over every held-out block, the residual of each
    block from the fit refitted (its columns, its weighted least squares; WLS for a consistent fit)
    without that block's rows,
    times ``margin`` (as :func:`identify.monitor.log.calibrate`)."""
    obs = fit.observation
    if obs is None or obs.t is None:
        raise MonitorInputError("the fit holds no observation matrix (fitted block by block): give a contact-free "
                                "recording to calibrate on")
    if list(obs.names) != list(fit.result.names):
        raise MonitorInputError("the fit's values do not follow its observation matrix's columns")
    sources = [block_source(rec, fit.robot, fit.model.convention, fit.gains) for rec in recordings]
    times = [_times(src) for src in sources]
    start = min(float(t[0]) for t in times)
    span = max(float(t[-1]) for t in times) - start + 1e-9  # the cross-validation's folds (cv_scoring.time_blocks)
    ids = time_folds(obs.t[obs.samples], start, span, blocks)
    mags = []
    for b in range(blocks):
        keep = ids != b
        try:  # the fit's own estimator (WLS; OLS for an OLS fit) on the other blocks' rows
            beta = weighted_least_squares(obs.W[keep], obs.Y[keep], obs.joint[keep], obs.names,
                                          weighted=fit.result.method != "ols").values
        except (IdentificationError, ValueError) as exc:
            raise MonitorInputError(f"held-out block {b + 1} of {blocks}: the fit without it fails ({exc})") from None
        fold = replace(fit, result=replace(fit.result, values=np.asarray(beta, dtype=float)))
        for src, t in zip(sources, times):
            rows = np.flatnonzero(time_folds(t, start, span, blocks) == b)
            if rows.size >= 3:  # the held-out block's samples (a file: read again, that block only)
                mags.append(excess(fold, next(src.windows([(int(rows[0]), int(rows[-1]) + 1)]))))
    return margin * np.quantile(np.concatenate(mags), quantile, axis=0)


def _times(src: BlockSource) -> np.ndarray:
    """The time stamps of a recording [s] (a file: its time column, read block by block)."""
    if isinstance(src, MemorySource):
        return np.asarray(src.rec.t, dtype=float)
    return np.concatenate([np.asarray(b.t[b.meta["new_from"]:], dtype=float) for b in src.scan(DEFAULT_MONITOR_BLOCK)])


def with_contact_thresholds(fit: Any, recordings: Sequence[Any], validation: Any = None) -> tuple[Any, str]:
    """(``fit`` with its contact-monitor thresholds [N·m] computed at the default observer gain on
    data it has not seen: :func:`identify.monitor.log.calibrate` on the ``validation`` recording when
    given, else :func:`held_out_thresholds` on the fitted ``recordings`` (contact-free by
    assumption; a fit made block by block holds no observation matrix: calibrate on the recordings
    themselves), ''); or (``fit`` unchanged, the reason) when the monitor cannot use the fit
    (``rx90 monitor`` then needs --calibrate)."""
    try:
        check_fit(fit)
        if validation is not None:
            T = calibrate(fit, [validation])
        elif getattr(fit, "observation", None) is None:  # fitted block by block (long logs): far more data than
            T = calibrate(fit, list(recordings))          # parameters, its own residual is what others' would be
        else:
            T = held_out_thresholds(fit, list(recordings))
        zero = [j + 1 for j in np.flatnonzero(~(np.asarray(T) > 0))]
        if zero:  # a recording at rest (e.g. a held pose): its residual stays within the friction slack
            where = f"the validation recording {getattr(validation, 'source', validation)}" if validation is not None \
                else "the fitted recordings"
            return fit, (f"{where} give a threshold of 0 N·m on joint(s) {', '.join(map(str, zero))}: the residual "
                         f"never leaves the friction slack there (does the arm move?)")
        return replace(fit, contact_thresholds=T), ""
    except (MonitorInputError, RuntimeError) as exc:  # RuntimeError: no C compiler for the observer
        return fit, str(exc)
