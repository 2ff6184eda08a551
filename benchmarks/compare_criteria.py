"""Which excitation criterion serves identification best on the twin (issue 15).

For each seed: a random feasible trajectory and one optimised trajectory per criterion, all 20 s,
5 harmonics, same limits; each is run on the twin (realistic noise, that seed) and identified by
WLS. A parameter's relative sigma is sigma_i / max(|nominal_i|, 0.1 max_group |nominal|)
(excitation.reference_magnitudes); the table gives, per group, the median over parameters, then
the median over seeds. One start per criterion and seed (--starts to change) to keep the runtime
to a few minutes on 2 cores.

    PYTHONPATH=. python benchmarks/compare_criteria.py [--seeds 5] [--starts 1] [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

CRITERIA = ("cond", "cond-nominal", "cond-columns", "logdet", "sigma")


def group_medians(robot, bp, traj, seed: int, reference: np.ndarray) -> dict[str, float]:
    import identify
    import rx90sym
    from excitation.objective import parameter_group

    rec = rx90sym.twin.simulate(robot, traj, noise="realistic", seed=seed)
    res = identify.fit(robot, [rec], identify.Processing(min_velocity=0.1, rest="drop", estimate_delay=False), base=bp).result
    index = {n: i for i, n in enumerate(bp.names)}
    groups: dict[str, list[float]] = {}
    for name, std in zip(res.names, res.std):
        groups.setdefault(parameter_group(name), []).append(100.0 * std / reference[index[name]])
    return {g: float(np.median(v)) for g, v in groups.items()}


def predicted_group_medians(robot, bp, traj, chi, reference: np.ndarray, noise_fraction: float = 0.015
                            ) -> dict[str, float]:
    """Median predicted relative sigma % per group from the information matrix alone (no twin
    noise draw): torque noise per joint = noise_fraction x the RMS of its nominal torque on this
    motion (the twin's realistic profile), samples at 250 Hz."""
    from excitation.criterion import regressor_samples
    from excitation.objective import Objective, numeric_information, parameter_group

    t, q, qd, qdd = traj.sample(250.0)
    phi = regressor_samples(bp.regressor, q, qd, qdd)
    tau = np.einsum("kji,i->kj", phi, bp.beta(chi))
    noise = noise_fraction * np.sqrt(np.mean(tau ** 2, axis=0))
    g = numeric_information(phi, Objective("logdet", noise), traj.duration)
    rel = 100.0 * np.sqrt(Objective.predicted_variance(g)) / reference
    groups: dict[str, list[float]] = {}
    for name, value in zip(bp.names, rel):
        groups.setdefault(parameter_group(name), []).append(value)
    return {g: float(np.median(v)) for g, v in groups.items()}


def compare(seeds: int = 5, starts: int = 1, criteria=CRITERIA, duration: float = 20.0,
            harmonics: int = 5, stream=sys.stderr, first_seed: int = 0) -> dict:
    import excitation
    import rx90sym
    from excitation.objective import GROUPS

    robot = rx90sym.load_robot("rx90")
    bp = rx90sym.base_parameters(robot)
    chi = robot.parameter_vector(rx90sym.default_parameters(robot))
    reference = excitation.reference_magnitudes(bp.beta(chi), bp.names)
    rows: dict[str, list] = {label: [] for label in ("random", *criteria)}
    for seed in range(first_seed, first_seed + seeds):
        rnd = excitation.random_trajectory(robot, duration, harmonics, seed=seed + 100,
                                           chi_nominal=chi, base=bp)
        rows["random"].append({"cond": rnd.cond, "time_s": 0.0,
                               "groups": group_medians(robot, bp, rnd, seed, reference)})
        print(f"seed {seed} {'random':13s} cond {rnd.cond:7.2f} {0.0:6.1f} s "
              + " ".join(f"{rows['random'][-1]['groups'][g]:7.3f}" for g in GROUPS), file=stream, flush=True)
        for name in criteria:
            t0 = time.perf_counter()
            traj = excitation.optimise(robot, duration, harmonics, seed=seed, chi_nominal=chi, base=bp,
                                       starts=starts, criterion=name, progress=False, envelope=None)
            elapsed = time.perf_counter() - t0
            try:
                groups = group_medians(robot, bp, traj, seed, reference)
            except ValueError as exc:  # identification refused the recording: counted as a failure
                print(f"seed {seed} {name}: identification failed ({exc})", file=stream, flush=True)
                groups = {g: float("nan") for g in GROUPS}
            rows[name].append({"cond": traj.cond, "time_s": elapsed, "groups": groups})
            print(f"seed {seed} {name:13s} cond {traj.cond:7.2f} {elapsed:6.1f} s "
                  + " ".join(f"{rows[name][-1]['groups'][g]:7.3f}" for g in GROUPS), file=stream, flush=True)
    return rows


def table(rows: dict) -> str:
    from excitation.objective import GROUPS

    lines = [f"{'trajectory':14s} {'cond':>7s} " + " ".join(f"{g[:20]:>20s}" for g in GROUPS)
             + f" {'s/start':>8s}"]
    base = {g: np.nanmedian([r["groups"][g] for r in rows["random"]]) for g in GROUPS}
    for label, runs in rows.items():
        med = {g: np.nanmedian([r["groups"][g] for r in runs]) for g in GROUPS}
        cells = " ".join(f"{med[g]:9.3g} ({med[g] / base[g]:5.2f}x)" for g in GROUPS)
        lines.append(f"{label:14s} {np.median([r['cond'] for r in runs]):7.2f} {cells} "
                     f"{np.median([r['time_s'] for r in runs]):8.1f}")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--starts", type=int, default=1)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--criteria", default=",".join(CRITERIA))
    parser.add_argument("--json")
    args = parser.parse_args()
    rows = compare(args.seeds, args.starts, tuple(args.criteria.split(",")), first_seed=args.first_seed)
    print("median relative sigma % per group (median over seeds; ratio to random)")
    print(table(rows))
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(rows, handle, indent=1)


if __name__ == "__main__":
    main()
