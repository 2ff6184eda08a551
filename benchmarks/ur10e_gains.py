"""UR10e drive gains from the 14-harmonic pair with a 2.805 kg payload (issue 12), and the payload
mass they give on held-out data (methods 3 and 4).

Data: ../shared/data/ur10e (no licence: read in place, never copied). The excitation runs are
used from row 195 to 4966 (empty) and 308 to 5071 (loaded), as the source repository did, put on
a uniform 100 Hz grid (positions by cubic Hermite with the recorded velocities, the rest linearly).

Printed:
1. the gains by both methods on the whole pair, with sigma (weighing error 5 g);
2. the controller's own constants: its logged target current regressed on its logged target
   torque, per joint (the target torque is the controller's model, not a measurement);
3. no circular check: gains fitted on the first 25 s of the paired runs, the payload mass by
   methods 3 and 4 on the remaining ~25 s, for the identified gains, the controller's constants
   and the gains published with the data (README);
4. friction empty vs loaded (each run identified alone with the identified gains): the methods
   assume it unchanged.

Usage: python benchmarks/ur10e_gains.py [--data DIR] [--split 25]
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import rx90sym
from identify import Processing, fit
from identify.gains.drive_gains import drive_gains
from identify.io.gains import DriveGains, apply_gains
from identify import read_log
from identify.io.recordings import RecordingWarning
from identify.signal.pairing import pair_runs
from identify.payloads.methods import payload
from rx90sym.recording import Recording

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "ur10e"
EMPTY = ("ur-20_02_19_14harm50sec.csv", (195, 4966))
LOADED = ("ur-20_02_19_14harm50secLoad.csv", (308, 5071))
MASS, MASS_STD = 2.805, 0.005  # kg (README; weighing error assumed 5 g)
SOURCE_GAINS = (10.0, 10.70, 8.46, 9.00, 9.48, 10.12)  # N·m/A, README (source repository)
RATE = 100.0  # Hz, uniform grid of the irregular 8-12 ms log
MIN_VELOCITY = 0.05  # rad/s, rest threshold of the fits


def ur10e_robot() -> rx90sym.Robot:
    """The bundled UR10e (rx90sym/robots/ur10e.toml): UR's standard DH (README) in Khalil's modified
    DH, frame j>1 taking alpha and a of standard row j-1 and d of row j; the angles are the
    controller's (no offsets). See docs/bundled-robots.md."""
    return rx90sym.load_robot("ur10e")


COLUMNS = "t,q1..q6,qd1..qd6,i1..i6,x:i_target1..x:i_target6,x:tau_target1..x:tau_target6"  # README


def load_run(path: Path, rows: tuple[int, int], rate: float = RATE) -> Recording:
    """Lines first..last (1-based) of a UR10e log on a uniform grid (identify.read_log: positions
    by cubic Hermite with the recorded velocities, the rest linearly); currents kept, no gains."""
    with warnings.catch_warnings():  # ur-20_01_17-p4.csv is at rest throughout: read on purpose
        warnings.simplefilter("ignore", RecordingWarning)
        return read_log(path, ur10e_robot(), COLUMNS, rows=rows, resample=rate)


def controller_constants(rec: Recording) -> np.ndarray:
    """Per joint: slope of tau_target on i_target (N·m/A), by least squares with an intercept."""
    return np.array([1.0 / np.polyfit(rec.aux[f"tau_target{j}"], rec.aux[f"i_target{j}"], 1)[0]
                     for j in range(1, rec.n_joints + 1)])


def held_out_mass(robot: rx90sym.Robot, gains: np.ndarray, empty: Recording, loaded: Recording,
                  methods: tuple[int, ...] = (3, 4)) -> dict:
    """Mc (value, std) by ``methods`` (3 and 4) with the given joint-side gains."""
    g = DriveGains(np.asarray(gains), side="joint")
    e, l = apply_gains(empty, g, robot), apply_gains(loaded, g, robot)
    out = {}
    for m in methods:
        res = payload(robot, m, empty=[e], loaded=[l], min_velocity=MIN_VELOCITY)
        out[m] = (res["Mc"], float(res.std[-1]))
    return out


def figures(data: Path = DATA, split: float = 25.0) -> dict:
    robot = ur10e_robot()
    empty, loaded = load_run(data / EMPTY[0], EMPTY[1]), load_run(data / LOADED[0], LOADED[1])
    (pair,) = pair_runs(empty, loaded)
    out: dict = {"pair": pair, "whole": {}, "part": {}, "mass": {}}
    for method in ("same-motion", "global"):
        out["whole"][method] = drive_gains(robot, [empty], [loaded], MASS, method=method, mass_std=MASS_STD)
    out["controller"] = controller_constants(empty)
    out["controller_loaded"] = controller_constants(loaded)
    cut = int(round(split * RATE))
    e, l = pair.recordings(empty, loaded)
    first = (e.select(slice(0, cut)), l.select(slice(0, cut)))
    rest = (e.select(slice(cut, e.n_samples)), l.select(slice(cut, l.n_samples)))
    candidates = {"source (README)": np.array(SOURCE_GAINS), "controller constants": out["controller"]}
    for method in ("same-motion", "global"):
        res = drive_gains(robot, [first[0]], [first[1]], MASS, method=method, mass_std=MASS_STD)
        out["part"][method] = res
        candidates[f"identified, {method}"] = res.gains.gains
    for name, k in candidates.items():
        out["mass"][name] = held_out_mass(robot, k, *rest)
    g = DriveGains(out["whole"]["global"].gains.gains, side="joint")
    rob = robot.with_options(offsets=True)
    out["friction"] = [fit(rob, [apply_gains(r, g, robot)], Processing(min_velocity=MIN_VELOCITY, rest="drop", estimate_delay=False)).result
                       for r in (e, l)]
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA)
    ap.add_argument("--split", type=float, default=25.0, help="seconds used to fit the gains (default 25)")
    args = ap.parse_args(argv)
    if not (args.data / EMPTY[0]).exists():
        print(f"no UR10e data in {args.data}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    f = figures(args.data, args.split)
    print(f["pair"].summary())
    for method, res in f["whole"].items():
        print(res.table())
    print("controller constants (target current on target torque), N·m/A:")
    print("  empty run  ", "  ".join(f"{k:.4g}" for k in f["controller"]))
    print("  loaded run ", "  ".join(f"{k:.4g}" for k in f["controller_loaded"]))
    for method, res in f["part"].items():
        print(f"gains fitted on the first {args.split:g} s ({method}):",
              "  ".join(f"{k:.4g} ± {s:.2g}" for k, s in zip(res.gains.gains, res.gains.std)),
              f"flagged {list(res.flagged)}")
    print(f"payload mass on the remaining samples (true {MASS} kg):")
    for name, m in f["mass"].items():
        cells = [f"method {k}: {v:.3f} ± {s:.3f} kg ({100 * (v / MASS - 1):+.1f} %)" for k, (v, s) in m.items()]
        print(f"  {name:24s}", "   ".join(cells))
    fe, fl = f["friction"]
    print("friction, empty vs loaded (identified gains, global):")
    for n in fe.names:
        if n.startswith(("FV", "FS")):
            i, k = fe.names.index(n), fl.names.index(n)
            print(f"  {n:6s} {fe.values[i]:8.3f} ± {fe.std[i]:.3f}   {fl.values[k]:8.3f} ± {fl.std[k]:.3f}"
                  f"   ({100 * (fl.values[k] / fe.values[i] - 1):+.0f} %)")
    print(f"elapsed {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
