"""The defaults against the plain OLS baseline on the unseen-robot trial, one small twin per joint count.

A chirp fitted with ``identify.fit(robot, [rec], Processing())``, a trapezoidal point-to-point motion
with rests predicted, both scored by ``Fit.validate`` against the raw measured torques beside the plain
baseline (identify.fitting.baseline) on the same samples; torque sensor offsets of 0.1-2 N m and a
Stribeck static part in the plant (tests/twin_logs.py). The issue's bound for any single twin run:
the defaults' RMS (all samples scored) at most 1.10x the baseline's on every joint.

Measured, the worst joint's ratio per seed 0..4 (all samples):
- UR5 from its maker-rounded URDF, 100 Hz, 15 s chirp, 10 s predicted: 0.706, 1.057, 0.820, 0.871,
  0.728 with the grid's 10 Hz floor; 0.706, 0.606, 1.273, 0.904, 0.755 with the former 2 Hz floor
  (seed 2 chose 2 Hz: 1.06x on joint 2, 1.27x on joint 4; the case below);
- Panda, 200 Hz, 12 s chirp, 8 s predicted: 0.586, 0.854, 1.000, 0.487, 0.773 (seed 0 below).
The full trial (6 and 7 joints, 100 Hz and 1 kHz, with and without a static part, 5 seeds) is
benchmarks/defaults_vs_yardsticks.py --twins.
"""
from __future__ import annotations

import numpy as np
import pytest

from identify import Processing, fit
from twin_logs import STATIC_PART, TwinCase, twin_logs

BOUND = 1.10


@pytest.mark.slow
@pytest.mark.parametrize("case, seed", [(TwinCase("ur5-small", "ur5", 100.0, STATIC_PART, fit_s=15.0, predict_s=10.0), 2),
                                        (TwinCase("panda-small", "panda", 200.0, STATIC_PART, fit_s=12.0, predict_s=8.0), 0)],
                         ids=["6-joints-ur5-100Hz", "7-joints-panda-200Hz"])
def test_the_defaults_predict_another_motion_within_1_10x_the_plain_baseline(tmp_path, case, seed):
    logs = twin_logs(case, seed, tmp_path)
    f = fit(logs.robot, [logs.fitted], Processing())
    v = f.validate(logs.predicted)
    ratio = v.rms_error / v.baseline_rms_error
    assert v.baseline_rms_error is not None and np.all(np.isfinite(ratio))
    assert np.all(ratio <= BOUND), f"defaults / baseline per joint: {np.round(ratio, 3)} ({f.cutoff:.3g} Hz)"
    # the torque offsets drawn (0.1-2 N m) are among the columns the defaults chose
    assert f.model.offset_joints is not None and len(f.model.offset_joints) >= logs.robot.n - 1
