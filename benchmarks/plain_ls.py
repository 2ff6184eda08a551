"""The baseline a user writes in 40 lines, as the project defines it (identify.fitting.baseline):
q by a 4th-order zero-phase Butterworth at 10 Hz at the recording's rate (no decimation), q̇ and q̈ by
numpy.gradient, the rigid-body regressor plus [q̇j, sign q̇j, 1] per joint, numpy.linalg.lstsq with
rcond 1e-10, 0.5 s trimmed at both ends; errors against the raw measured torques.

The benchmarks call these two functions; the toolkit's validation prints the same baseline."""
from __future__ import annotations

from typing import Any

import numpy as np

import rx90sym
from identify.fitting.baseline import BASELINE_CUTOFF_HZ, PlainBaseline
from identify.fitting.baseline_factors import fit_baseline

#: The fixed cut-off of the baseline, Hz.
PLAIN_CUTOFF = BASELINE_CUTOFF_HZ


def plain_ls(robot: rx90sym.Robot, rec: Any) -> PlainBaseline:
    """The plain OLS baseline fitted on ``rec`` (one recording or a list)."""
    return fit_baseline(robot, rec if isinstance(rec, (list, tuple)) else [rec])


def plain_prediction(robot: rx90sym.Robot, baseline: PlainBaseline, rec: Any) -> tuple[np.ndarray, np.ndarray]:
    """(predicted joint torques (S, n) [N m], the samples of ``rec`` they belong to: a boolean mask, 0.5 s
    from each segment's ends, measured)."""
    p = baseline.predict(robot, rec)
    return p.predicted[p.scored], p.scored
