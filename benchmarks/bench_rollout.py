"""Benchmark of the rollout validation (issue 39 item 1, identify.rollout): its time on a 60 s log.

A UR10e twin (its [nominal] parameters as truth, 60 s multisine at 500 Hz, "quantised" profile: the cost
does not depend on the noise) and a consistent fit of it. Timed, best of ``--repeat`` (after one untimed
call), on the same recording in memory:

1. ``roll_out_fit(fit, rec, 0.25)``: what ``rx90 predict --rollout 0.25`` adds (the identified model and
   the nominal one, 0.25 s windows: reading, filtering, loading both MJCFs, 2 x 30,000 MuJoCo steps);
2. ``fit.predict(rec)``: the inverse-dynamics prediction of the same log (what ``rx90 predict`` runs);
3. the stepping alone, per MuJoCo step (the identified model's windows);
4. 1. again with the fit's friction the tanh form on every joint (``Processing(friction="tanh")``, as the
   defaults choose on real logs): the friction applied from the fit at every step, in steps short enough
   for its slope.

Target (issue 39): the rollout of a 60 s log at 0.25 s windows under 2 s. Also printed: the ratio to the
prediction measured in the same run (the machine's load cancels in it) and to real time.

Considered: ``mujoco.rollout`` (C, threads) steps the same windows from their initial states with the
torques as ``qfrc_applied`` controls: 0.067 s against this loop's 0.080 s on the UR10e's 118 windows of
0.25 s (identical states), but it cannot apply the terms computed from the state at every step (a spring,
smooth friction, the coupled wrist's Coulomb form), so there is one loop.

Usage: python benchmarks/bench_rollout.py [--duration 60] [--repeat 3]
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import rx90sym  # noqa: E402
import identify  # noqa: E402
from identify.rollout.run import roll_out_fit  # noqa: E402
from motions import multisine  # noqa: E402
from timing import time_it  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=60.0, help="log length [s] (default 60)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    robot = rx90sym.load_robot("ur10e")
    truth = rx90sym.nominal_parameters(robot)
    rec = rx90sym.twin.simulate(robot, multisine(robot, 0, args.duration), truth, noise="quantised", seed=0,
                                rate=500.0, duration=args.duration)
    fit = identify.fit(robot, [rec], method="consistent")
    out = roll_out_fit(fit, rec, 0.25)
    w = out.windows[0]
    t_roll = time_it(lambda: roll_out_fit(fit, rec, 0.25), args.repeat)
    t_pred = time_it(lambda: fit.predict(rec), args.repeat)
    steps = w.windows * w.samples * out.substeps
    t_step = time_it(lambda: roll_out_fit(fit, rec, 0.25, nominal=False), args.repeat)
    load = os.getloadavg()[0]
    print(f"UR10e twin, {args.duration:g} s at 500 Hz ({rec.n_samples} samples), consistent fit; load {load:.1f} "
          f"on {os.cpu_count()} cores")
    print(f"rollout 0.25 s (identified + nominal): {w.windows} windows scored, {w.skipped_rest} at rest; "
          f"{2 * steps} MuJoCo steps")
    print(f"  roll_out_fit               {t_roll:7.3f} s   ({args.duration / t_roll:6.0f}x real time; target < 2 s: "
          f"{'met' if t_roll < 2.0 else 'NOT met'})")
    print(f"  fit.predict (same log)     {t_pred:7.3f} s   rollout / prediction = {t_roll / t_pred:.2f}")
    print(f"  identified model alone     {t_step:7.3f} s   ({1e6 * t_step / steps:.1f} µs per MuJoCo step, "
          f"reading and filtering included)")
    smooth = identify.fit(robot, [rec], identify.Processing(friction="tanh"), method="consistent")
    out_s = roll_out_fit(smooth, rec, 0.25)
    t_smooth = time_it(lambda: roll_out_fit(smooth, rec, 0.25), args.repeat)
    steps_s = out_s.windows[0].windows * out_s.windows[0].samples * out_s.substeps
    print(f"  the same, tanh friction    {t_smooth:7.3f} s   ({args.duration / t_smooth:6.0f}x real time; target < 2 s: "
          f"{'met' if t_smooth < 2.0 else 'NOT met'}; {out_s.substeps} steps a sample, {2 * steps_s} MuJoCo steps, "
          f"{1e6 * t_smooth / (2 * steps_s):.1f} µs each)")
    print("end-position RMS [mrad] identified " + " ".join(f"{1e3 * v:.3g}" for v in w.rms("identified"))
          + "; guess " + " ".join(f"{1e3 * v:.3g}" for v in w.rms("guess")))
    return 0


if __name__ == "__main__":
    start = time.perf_counter()
    code = main()
    print(f"elapsed {time.perf_counter() - start:.0f} s")
    sys.exit(code)
