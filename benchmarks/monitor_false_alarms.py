"""False alarms of the contact monitor on contact-free motion (issue 30: "no event in 1 h").

Per robot (RX90, 6 joints; Panda, 7 joints), the realistic twin: ``--hours`` of contact-free motion
made of different 20 s runs (tests/monitor_twin.free_run: a multisine of its own seed, every third
run with rests), each monitored on its own (the observer reset between runs: no run is one run
repeated). Two fits: "3 runs", on three different 20 s multisines (monitor_twin.free_fit, what the
suite's false-alarm test uses), and "1 run", the pulse tests' fit on one 20 s multisine
(monitor_twin.twin_fit: under-excited for other motions). Per fit, two sets of thresholds, both made
by the toolkit (monitor_twin.toolkit_thresholds):

- identify: what ``rx90 identify --json`` stores without --validate
  (identify.monitor.thresholds.with_contact_thresholds: the held-out blocks of the fitted runs);
- calibrate: identify.monitor.log.calibrate on one other contact-free run, what
  ``rx90 monitor --calibrate`` and ``rx90 identify --validate`` do.

Printed per robot and set: hours monitored, events (target 0; while moving / at rest), and the
margin per joint: the largest |r_j| / (T_j + d_j) over every sample (d_j: the friction slack), below
1 when no joint was ever active, with the joint's speed there (below the fit's rest threshold,
0.05 rad/s: at rest or at a reversal). With --cache DIR the simulated runs are kept (npz) and reused.

Usage: python benchmarks/monitor_false_alarms.py [--hours 1] [--robots rx90,panda] [--cache DIR]
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import monitor_twin  # noqa: E402
from monitor_twin import (FREE_CALIBRATION_SEED, FREE_FIT_SEEDS, FreeScan, free_fit, scan_free_motion,  # noqa: E402
                          toolkit_thresholds, twin_fit)
from rx90sym.recording import Recording  # noqa: E402

RUN_S = 20.0


def cached_runs(cache: Path) -> None:
    """Make monitor_twin.free_run keep its recordings in ``cache`` (npz per robot and run)."""
    make = monitor_twin.free_run

    def free_run(name: str, k: int, duration: float = RUN_S) -> Recording:
        path = cache / f"{name}-{k}-{duration:g}.npz"
        if path.exists():
            z = np.load(path)
            return Recording(t=z["t"], q=z["q"], tau=z["tau"], source=f"free {name} {k}", robot=name)
        rec = make(name, k, duration)
        np.savez(path, t=rec.t, q=rec.q, tau=rec.tau)
        return rec

    monitor_twin.free_run = free_run


def fits(name: str) -> list[tuple[str, object, dict[str, np.ndarray]]]:
    """(label, fit, thresholds) of the two fits of ``name``."""
    F3, F1 = free_fit(name), twin_fit(name)
    return [("3 runs", F3, toolkit_thresholds(name, F3, FREE_FIT_SEEDS, FREE_CALIBRATION_SEED)),
            ("1 run", F1, toolkit_thresholds(name, F1, (100,), 101))]


def report(name: str, label: str, T: np.ndarray, scan: FreeScan) -> None:
    moving = sum(1 for _, _, mv in scan.events if mv)
    print(f"{name:<13} {label:<10} {scan.seconds / 3600:6.3f} {len(scan.events):7d} {moving:7d} "
          f"{len(scan.events) - moving:5d}  " + " ".join(f"{v:5.2f}" for v in scan.margin))
    print(f"{'':<13} {'T [N·m]':<10} {'':>6} {'':>7} {'':>7} {'':>5}  " + " ".join(f"{v:5.2f}" for v in T))
    print(f"{'':<13} {'|q̇| there':<10} {'':>6} {'':>7} {'':>7} {'':>5}  "
          + " ".join(f"{w[2]:5.2f}" for w in scan.where) + "  [rad/s] at the largest ratio")
    for k, e, mv in scan.events[:8]:
        print(f"{'':<15}run {k:4d} {e.start_s:7.3f}-{e.end_s:7.3f} s joints {','.join(map(str, e.joints))} "
              f"peak {max((e.peak_nm[j - 1] for j in e.joints), key=abs):6.2f} N·m {'moving' if mv else 'at rest'}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=1.0, help="contact-free motion per robot [h] (default 1)")
    ap.add_argument("--robots", default="rx90,panda")
    ap.add_argument("--cache", type=Path, help="keep the simulated runs here (npz) and reuse them")
    args = ap.parse_args()
    warnings.simplefilter("ignore", UserWarning)  # the Panda twin's assumed gear ratio, said once per run
    if args.cache:
        args.cache.mkdir(parents=True, exist_ok=True)
        cached_runs(args.cache)
    runs = int(round(args.hours * 3600 / RUN_S))
    print(f"{runs} contact-free runs of {RUN_S:g} s per robot, observer reset between runs")
    print(f"{'robot':<6} {'fit':<6} {'thresholds':<10} {'hours':>6} {'events':>7} {'moving':>7} {'rest':>5}  "
          f"margin max |r_j| / (T_j + d_j) per joint")
    for name in args.robots.split(","):
        for fit_label, F, T in fits(name):
            start = time.perf_counter()
            scans = scan_free_motion(name, F, T, range(runs), RUN_S)
            for label, scan in scans.items():
                report(f"{name:<6} {fit_label:<6}", label, T[label], scan)
            print(f"{'':<13} ({time.perf_counter() - start:.0f} s for {runs} runs: simulated, or read from --cache)")


if __name__ == "__main__":
    main()
