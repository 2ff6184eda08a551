"""Is the printed payload sigma honest? UR10e 14-harmonic pair, 2.805 kg (issue 20).

Data: ../shared/data/ur10e (read in place, never copied), loaded and paired as in
benchmarks/ur10e_gains.py (100 Hz grid, rows 195-4966 and 308-5071, paired in time).

Printed:
1. the paired runs cut into four disjoint windows of equal length; the payload mass by methods 3
   and 4 on each window and on all of them together (pooled), with eq. 13's sigma and the segment
   bootstrap's (identify.estimation.bootstrap); for each sigma: how many of the four window
   estimates lie within their own 2 sigma of the pooled estimate (target: at least 3), and the
   ratio of the mean printed sigma to the observed spread (standard deviation of the four window
   estimates; target: at most 3, an inflated sigma does not pass);
2. gains by each method of ``rx90 gains`` (the default marked) fitted on the first half of the
   pair, with eq. 13's and the bootstrap's relative sigma, and the payload mass on the second
   half by methods 3 and 4 (target for the default: within 2 % of 2.805 kg).

Currents become torques with the controller's own constants in 1 (the slope of its logged target
torque on its target current, see docs/drive-gains.md): the window-to-window spread is what is
judged, and any fixed gains scale every window alike.

Usage: PYTHONPATH=. python benchmarks/ur10e_windows.py [--data DIR]   (~1 min)
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from identify.gains.drive_gains import DEFAULT_METHOD, GAIN_METHODS, drive_gains
from identify.io.gains import DriveGains, apply_gains
from identify.payloads.methods import payload
from identify.signal.pairing import pair_runs

WINDOWS = 4


sys.path.insert(0, str(Path(__file__).resolve().parent))  # the sibling benchmark's loader and constants
import ur10e_gains as ug  # noqa: E402


def window_masses(robot, empty, loaded, gains: np.ndarray, method: int) -> dict:
    """Mc (value, eq. 13 sigma, bootstrap sigma) per window and pooled."""
    g = DriveGains(np.asarray(gains), side="joint")
    e, l = apply_gains(empty, g, robot), apply_gains(loaded, g, robot)
    edges = np.linspace(0, min(e.n_samples, l.n_samples), WINDOWS + 1).astype(int)

    def mass(es, ls):
        res = payload(robot, method, empty=es, loaded=ls, min_velocity=ug.MIN_VELOCITY)
        return res["Mc"], float(res.std[-1]), float(res.bootstrap_std[-1])

    windows = [(e.select(slice(a, b)), l.select(slice(a, b))) for a, b in zip(edges[:-1], edges[1:])]
    return {"windows": [mass([we], [wl]) for we, wl in windows],
            "pooled": mass([w[0] for w in windows], [w[1] for w in windows])}


def judge(result: dict, which: int) -> tuple[int, float]:
    """(windows within their 2 sigma of the pooled value, mean sigma / observed spread)."""
    values = np.array([w[0] for w in result["windows"]])
    sigma = np.array([w[which] for w in result["windows"]])
    within = int(np.sum(np.abs(values - result["pooled"][0]) <= 2 * sigma))
    return within, float(np.mean(sigma) / np.std(values, ddof=1))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=ug.DATA)
    args = ap.parse_args(argv)
    if not (args.data / ug.EMPTY[0]).exists():
        print(f"no UR10e data in {args.data}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    robot = ug.ur10e_robot()
    empty = ug.load_run(args.data / ug.EMPTY[0], ug.EMPTY[1])
    loaded = ug.load_run(args.data / ug.LOADED[0], ug.LOADED[1])
    (pair,) = pair_runs(empty, loaded)
    e, l = pair.recordings(empty, loaded)
    constants = ug.controller_constants(empty)
    print(f"{WINDOWS} disjoint windows of {e.n_samples / WINDOWS / ug.RATE:.1f} s; gains: controller constants")
    print(f"{'method':>6s} {'window':>7s} {'Mc kg':>8s} {'2σ eq.13':>9s} {'2σ boot':>8s}")
    for method in (3, 4):
        res = window_masses(robot, e, l, constants, method)
        for k, (v, s, b) in enumerate(res["windows"] + [res["pooled"]], start=1):
            label = str(k) if k <= WINDOWS else "pooled"
            print(f"{method:6d} {label:>7s} {v:8.4f} {2 * s:9.4f} {2 * b:8.4f}")
        spread = np.std([w[0] for w in res["windows"]], ddof=1)
        for name, which in (("eq. 13", 1), ("bootstrap", 2)):
            within, ratio = judge(res, which)
            print(f"  method {method}, σ {name:9s}: {within} of {WINDOWS} windows within their 2σ of the pooled "
                  f"value; mean σ / observed spread {ratio:.2f} (spread {spread:.4f} kg)")
    half = e.n_samples // 2
    rest = (e.select(slice(half, e.n_samples)), l.select(slice(half, l.n_samples)))
    for gain_method in GAIN_METHODS:
        fit = drive_gains(robot, [e.select(slice(0, half))], [l.select(slice(0, half))], ug.MASS,
                          method=gain_method, mass_std=ug.MASS_STD)
        tag = " (the default)" if gain_method == DEFAULT_METHOD else ""
        print(f"gains, {gain_method}{tag}, on the first half: gain, σr eq. 13 %, σr bootstrap %, flagged "
              f"{list(fit.flagged)}")
        print("  " + "  ".join(f"{k:.4g} ({r:.2g}, {b:.2g})" for k, r, b in
                               zip(fit.gains.gains, fit.rel_std_ls_pct, fit.rel_std_boot_pct)))
        for method, (v, s) in ug.held_out_mass(robot, fit.gains.gains, *rest).items():
            print(f"  payload on the second half, method {method}: {v:.4f} ± {s:.4f} kg "
                  f"({100 * (v / ug.MASS - 1):+.2f} % of {ug.MASS} kg)")
    print(f"elapsed {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
