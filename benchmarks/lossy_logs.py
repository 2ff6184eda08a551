"""A host-logged 1 kHz stream of a 7-joint arm (Panda twin, closed loop, realistic noise) with
5 % stale rows, bursts of 5-40 lost packets every 2-4 s and ±0.15 period clock jitter, read with
``resample`` alone: the share of base parameters within 3 sigma of the truth, against the same
run's clean recording (the reference, measured in the same run), per seed.

Usage: python benchmarks/lossy_logs.py [--seeds 5] [--duration 20]
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]  # run from a checkout; the twin's motions and truth

import rx90sym  # noqa: E402
from identify import read_log  # noqa: E402
from identify import Processing, fit  # noqa: E402
from motions import multisine, panda_truth  # noqa: E402
from rx90sym.host_log import HostFaults, host_log, write_host_log  # noqa: E402


def within_3_sigma(robot: rx90sym.Robot, base, truth: np.ndarray, rec) -> float:
    """Share of the base parameters whose WLS estimate lies within 3 sigma of the truth."""
    res = fit(robot, [rec], Processing(estimate_delay=False), base=base).result
    values, std = dict(zip(res.names, res.values)), dict(zip(res.names, res.std))
    return float(np.mean([abs(values[n] - v) <= 3 * std[n] for n, v in zip(base.names, truth)]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--duration", type=float, default=20.0)
    args = ap.parse_args()
    warnings.simplefilter("ignore")  # the twin's gear-ratio note for a robot file without gears
    robot = rx90sym.load_robot("panda")
    base = rx90sym.base_parameters(robot)
    truth = base.beta(robot.parameter_vector(panda_truth(robot)))
    print(f"{'seed':>4} {'stale':>6} {'gaps':>5} {'bridged':>8} {'clean':>7} {'lossy':>7} {'ratio':>6}")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(args.seeds):
            rec = rx90sym.twin.simulate(robot, multisine(robot, seed, duration=args.duration),
                                        params=panda_truth(robot), duration=args.duration, rate=1000.0,
                                        noise="realistic", seed=seed)
            table, _, _ = host_log(rec, HostFaults(), seed)
            path = Path(tmp) / f"host{seed}.csv"
            cols = write_host_log(path, table)
            log = read_log(path, robot, cols, resample=1000.0, convention="model")
            clean, lossy = within_3_sigma(robot, base, truth, rec), within_3_sigma(robot, base, truth, log)
            meta = log.meta["log"]
            long_gaps = sum(g["periods"] >= 5 for g in meta["gaps"]["gaps"])
            rows.append((clean, lossy))
            print(f"{seed:>4} {meta['stale_rows']:>6} {long_gaps:>5} {meta['bridged_samples']:>8} {clean:>7.3f} "
                  f"{lossy:>7.3f} {lossy / clean:>6.3f}")
    clean, lossy = np.mean(rows, axis=0)
    print(f"mean {'':>6} {'':>5} {'':>8} {clean:>7.3f} {lossy:>7.3f} {lossy / clean:>6.3f}")


if __name__ == "__main__":
    main()
