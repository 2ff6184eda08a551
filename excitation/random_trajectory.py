"""Random feasible trajectories: the baseline an optimised trajectory is compared with."""
from __future__ import annotations

import time

import numpy as np

from .constraints import Margins, check_limits, range_centre
from .model import ExcitationModel
from .optimiser import kinematic_room
from .options import MAX_COND, OptimiserOptions, check_request
from .trajectory import Form, SolveInfo, Trajectory, sample_times
from .criterion import condition_number

_SHRINK = 0.9        # amplitude factor per attempt when torque or Cartesian limits fail
_ATTEMPTS = 60       # 0.9^60 ~ 2e-3: below that the motion no longer excites anything


def random_feasible(model: ExcitationModel, form: Form, seed: int = 0,
                    options: OptimiserOptions | None = None) -> Trajectory:
    """Random rest-to-rest trajectory about the centre of the joint ranges, scaled down until every
    limit holds on the fine grid (positions, velocities, accelerations exactly, then torques and
    heights by shrinking the amplitude). Raises ValueError if no scale works."""
    options = options or OptimiserOptions()
    check_request(model, form, options)
    t_start = time.perf_counter()
    rng = np.random.default_rng(seed)
    centre = range_centre(model)
    motion = form.random_free(rng, model.n)
    fine = sample_times(form.duration, options.verify_rate, closed=True)
    # Kinematic limits are linear in the amplitude: scale each joint to its room exactly.
    scales = kinematic_room(model, form, motion, centre, fine, Margins(0.0, 0.0, 0.0, 0.0, 0.0))
    report = None
    for _ in range(_ATTEMPTS):
        coefficients = form.rest_basis() @ (form.constant(centre) + motion * scales)
        q, qd, qdd = form.evaluate(coefficients, fine)
        report = check_limits(model, q, qd, qdd, options.verify_rate)
        if report.feasible:
            break
        scales = scales * _SHRINK
    if report is None or not report.feasible:
        raise ValueError(f"random trajectory: no amplitude holds every limit "
                         f"({'; '.join(report.violations[:3]) if report else 'no attempt'})")
    t = sample_times(form.duration, options.cond_rate)
    cond = condition_number(model.regressor, t, *form.evaluate(coefficients, t))
    if not cond <= MAX_COND:
        raise ValueError(f"random trajectory: the motion that holds every limit leaves W rank "
                         f"deficient (cond {cond:.3g})")
    info = SolveInfo("random", int(seed), starts=1, feasible_starts=1,
                     time_s=time.perf_counter() - t_start)
    return Trajectory(form, coefficients, cond, "none (random)", model.controller_offsets, report, info,
                      options.cond_rate, model.names)
