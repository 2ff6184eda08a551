"""Benchmark of the excitation optimiser (issue 7) on the RX90.

One optimisation of a 20 s, 5-harmonic Fourier trajectory (single start, seed 0, nominal limits,
torque limits with the bundled nominal parameters), timed on this machine against a target of
60 s. References measured in the same run: the time of one evaluation of cond(W) at 250 Hz
(5000 samples, W is 30000 x 54) and the cond of a random feasible trajectory. Every limit of the
result is checked again, independently, on a 2 kHz grid.

    python benchmarks/bench_excitation.py [--seed 0] [--starts 1] [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np

from timing import time_it


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--starts", type=int, default=1)
    parser.add_argument("--json", help="also write the figures to this JSON file")
    args = parser.parse_args()

    import excitation
    import rx90sym

    robot = rx90sym.load_robot("rx90")
    bp = rx90sym.base_parameters(robot)
    chi = robot.parameter_vector(rx90sym.default_parameters(robot))

    t0 = time.perf_counter()
    rand = excitation.random_trajectory(robot, 20.0, 5, seed=args.seed, chi_nominal=chi, base=bp)
    t_random = time.perf_counter() - t0
    t, q, qd, qdd = rand.sample(250.0)
    t_cond = time_it(lambda: excitation.condition_number(bp.regressor, t, q, qd, qdd))

    t0 = time.perf_counter()
    traj = excitation.optimise(robot, 20.0, 5, seed=args.seed, starts=args.starts, chi_nominal=chi,
                               base=bp, criterion="cond", progress=True, envelope=None)
    t_opt = time.perf_counter() - t0

    # independent check: a grid twice as fine as the optimiser's own, no margins
    model = excitation.model_from_robot(robot, chi, bp)
    t2, q2, qd2, qdd2 = traj.sample(2000.0, closed=True)
    check = excitation.check_limits(model, q2, qd2, qdd2, 2000.0)
    n_samples = traj.sample(250.0)[0].size
    rows = [
        ("one optimisation, 20 s, L=5", f"{t_opt:.1f} s", "< 60 s", f"{t_opt / 60.0:.2f} of target"),
        ("  IPOPT iterations (all stages)", f"{traj.info.iterations}", "", ""),
        ("  cond at 250 Hz (W 6x%d x %d)" % (n_samples, bp.nb), f"{traj.cond:.2f}", "<= 30 (aim 20)",
         f"{traj.cond / 30.0:.2f} of target"),
        ("  limits at 2 kHz (independent)", "hold" if check.feasible else "VIOLATED", "hold",
         f"max usage {max(np.nanmax(getattr(check, k)) for k in ('position', 'velocity', 'acceleration', 'torque')):.3f}"),
        ("ref: one cond evaluation, 250 Hz", f"{t_cond * 1e3:.0f} ms", "",
         f"optimisation = {t_opt / t_cond:.0f} x"),
        ("ref: random feasible trajectory", f"{rand.cond:.1f}", "", f"optimised/random = {traj.cond / rand.cond:.2f}"),
        ("ref: random trajectory, time", f"{t_random:.2f} s", "", ""),
    ]
    print(f"\n{'figure':36s} {'value':>10s}  {'target':15s} ratio")
    for name, value, target, ratio in rows:
        print(f"{name:36s} {value:>10s}  {target:15s} {ratio}")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as handle:
            json.dump({"time_s": t_opt, "iterations": traj.info.iterations, "cond": traj.cond,
                       "limits_hold_2khz": check.feasible, "cond_eval_s": t_cond,
                       "random_cond": rand.cond, "seed": args.seed, "starts": args.starts}, handle, indent=2)


if __name__ == "__main__":
    main()
