"""Benchmark of the contact monitor (issue 30, identify.monitor).

1. ``ContactMonitor.update`` cost per sample, 6 joints (RX90: coupling, spring) and 7 (Panda):
   median and p99 over many calls (time.perf_counter_ns around each call), beside the reference
   measured in the same run: the same observer step called through CasADi's own Python interface
   (its virtual machine, DM conversions), what a monitor without the compiled C path would cost.
2. ``monitor_log`` (what ``rx90 monitor`` runs) on a long synthetic 1 kHz log: the RX90 twin's
   20 s multisine (periodic, "quantised" profile) repeated, served block by block by a generator
   (no file: the reader's cost is not the monitor's): throughput as a multiple of real time, for
   10 min and for ``--long`` minutes (default 60), and the peak of Python's allocations
   (tracemalloc: NumPy's buffers included) for both; the ratio says whether memory grows with
   the log's duration. Its thresholds are 1e6 N·m (no event possible: the cost of the monitor,
   not its false alarms, which benchmarks/monitor_false_alarms.py counts on an hour of different runs).

Targets (issue 30): update median < 50 µs; rx90 monitor ≥ 20× real time on 1 h at 1 kHz; peak memory at
1 h within 10 % of that at 10 min.

Usage: python benchmarks/bench_monitor.py [--calls 20000] [--long 60]
"""
from __future__ import annotations

import argparse
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import rx90sym  # noqa: E402
from identify import ContactMonitor  # noqa: E402
from identify.io.blocks import BlockSource  # noqa: E402
from identify.monitor.log import monitor_log  # noqa: E402
from monitor_twin import twin_fit  # noqa: E402
from motions import multisine  # noqa: E402
from rx90sym.recording import Recording  # noqa: E402


def update_cost(name: str, calls: int) -> tuple[float, float, float, float]:
    """(median, p99) µs of update(), then (median, p99) of the reference CasADi call."""
    F = twin_fit(name)
    robot = F.robot
    rec = rx90sym.twin.simulate(robot, multisine(robot, 1, duration=8.0), duration=8.0, noise="quantised", seed=1)
    qd = np.gradient(rec.q, rec.t, axis=0)
    mon = ContactMonitor(F, rec.rate, thresholds=1e6)
    rows = list(zip(rec.t, rec.q, qd, rec.tau))
    N = len(rows)
    for k in range(min(N, 2000)):
        mon.update(*rows[k])
    times = np.empty(calls)
    clock = time.perf_counter_ns
    for k in range(calls):
        t, q, v, e = rows[k % N]
        start = clock()
        mon.update(t + (k // N) * 8.0, q, v, e)
        times[k] = clock() - start
    step, params = mon.model.step, mon._params
    state = mon.model.initial_state()
    ref = np.empty(min(calls, 5000))
    for k in range(ref.size):
        t, q, v, e = rows[k % N]
        start = clock()
        state = step(q, v, e, state, 1.0 / rec.rate, params).full().ravel()
        ref[k] = clock() - start
    return (float(np.median(times)) / 1e3, float(np.percentile(times, 99)) / 1e3,
            float(np.median(ref)) / 1e3, float(np.percentile(ref, 99)) / 1e3)


class TiledSource(BlockSource):
    """A recording repeated (time running on) to ``duration`` seconds, block by block, no file."""

    def __init__(self, rec: Recording, robot: rx90sym.Robot, duration: float) -> None:
        super().__init__(robot, None)
        self.rec, self.duration, self.source = rec, duration, "tiled"
        self.period = rec.t[-1] - rec.t[0] + (rec.t[1] - rec.t[0])

    def scan(self, block: int):
        n0, total = self.rec.n_samples, int(round(self.duration * self.rec.rate))
        for start in range(0, total, block):
            idx = np.arange(start, min(start + block, total))
            t = idx / self.rec.rate
            k = idx % n0
            yield Recording(t=t, q=self.rec.q[k], tau=self.rec.tau[k], dq=self.rec.dq[k], source="tiled",
                            robot=self.rec.robot, meta={"new_from": 0})


def long_log(minutes: float) -> tuple[float, float, int]:
    """(seconds, peak MB of tracemalloc, events) of monitor_log on ``minutes`` of 1 kHz log."""
    F = twin_fit("rx90")
    robot = F.robot
    rec = rx90sym.twin.simulate(robot, multisine(robot, 2, duration=20.0), duration=20.0, noise="quantised",
                                seed=2, rate=1000.0)
    rec = Recording(t=rec.t, q=rec.q, tau=rec.tau, dq=np.gradient(rec.q, rec.t, axis=0), source="tile", robot=rec.robot)
    monitor_log(F, TiledSource(rec, robot, 5.0), 1e6)  # compiled before timing
    tracemalloc.start()
    start = time.perf_counter()
    res = monitor_log(F, TiledSource(rec, robot, 60.0 * minutes), 1e6)
    elapsed = time.perf_counter() - start
    peak = tracemalloc.get_traced_memory()[1] / 1e6
    tracemalloc.stop()
    return elapsed, peak, len(res.events)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=20000)
    ap.add_argument("--long", type=float, default=60.0, help="minutes of the long log (default 60)")
    args = ap.parse_args()
    print("ContactMonitor.update, per sample [µs]")
    print(f"{'robot':<6} {'joints':>6} {'median':>8} {'p99':>8} {'CasADi call median':>19} {'p99':>8} {'ratio':>6}")
    for name in ("rx90", "panda"):
        med, p99, rmed, rp99 = update_cost(name, args.calls)
        print(f"{name:<6} {rx90sym.load_robot(name).n:>6} {med:8.2f} {p99:8.2f} {rmed:19.2f} {rp99:8.2f} "
              f"{rmed / med:6.1f}")
    print("\nmonitor_log on a 1 kHz log (RX90 twin tiled), tracemalloc peak")
    print(f"{'minutes':>8} {'seconds':>8} {'× real time':>12} {'peak MB':>8}")
    runs = {}
    for minutes in (10.0, args.long):
        runs[minutes] = long_log(minutes)
        s, peak, events = runs[minutes]
        print(f"{minutes:8.1f} {s:8.2f} {60 * minutes / s:12.1f} {peak:8.2f}")
    print(f"peak ratio {args.long:g} min / 10 min: {runs[args.long][1] / runs[10.0][1]:.3f}")


if __name__ == "__main__":
    main()
