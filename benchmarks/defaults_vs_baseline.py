"""The toolkit's defaults against the plain OLS baseline, per joint, on the raw measured torques.

The baseline is the one of the project's definition (identify.fitting.baseline, benchmarks/plain_ls.py):
10 Hz zero-phase Butterworth on q at the recording's rate, numpy.gradient, rigid-body regressor plus
[q̇j, sign q̇j, 1] per joint, lstsq(rcond=1e-10), 0.5 s trimmed at both ends. Both are fitted on the
same samples and scored by ``Fit.validate`` on the same raw samples of the held-out part (the
toolkit's prediction interpolated onto the recording's time stamps).

Records:
1. TX40 (the record shipped in the package, 5 kHz, motor side): the first 6 s fitted, the rest
   predicted; robot file as shipped.
2. UR10e (../shared/data/ur10e; skipped when absent; joint side): the 14-harmonic run fitted (rows
   195..4966), the whole p4 file predicted (the arm holds still there); and the first half of the
   14-harmonic run fitted (rows 195..2566), the second half predicted (motion and rest); with the
   source's gains (a, b), then with the gains ``rx90 gains`` identifies with its defaults from the
   empty/loaded pair (c, d).
3. The time of the default identification on a 50 s, 100 Hz, 6-joint log (UR10e twin, seed 0), and
   of the baseline's own fit in it.

Target: defaults <= 1.02 x baseline (RMS on all samples scored) on every joint.

Usage: PYTHONPATH=. python benchmarks/defaults_vs_baseline.py [--skip-ur10e] [--skip-timing]
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import rx90sym
from identify import Processing, fit

TARGET = 1.02
FIT_SECONDS = 6.0


def _sibling(name: str):
    spec = importlib.util.spec_from_file_location(name, Path(__file__).with_name(f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def compare(label: str, robot: rx90sym.Robot, fit_rec, test_rec) -> bool:
    """Print the per-joint table of one split; True when the target holds on every joint."""
    start = time.perf_counter()
    f = fit(robot, [fit_rec], Processing())
    seconds = time.perf_counter() - start
    v = f.validate(test_rec)
    n = robot.n
    ratio, ratio_m = v.rms_error / v.baseline_rms_error, v.rms_error_moving / v.baseline_rms_error_moving
    form = (f.model.friction or {}).get("form", "coulomb")
    offsets = ", ".join(map(str, f.model.offset_joints or ())) or "none"
    dec = "none" if f.decimate_to is None else f"{f.decimate_to:.4g} Hz"
    print(f"\n{label}\n  defaults: cut-off {f.cutoff:.4g} Hz, decimation {dec}, rest {f.rest}, "
          f"friction {form}, offsets on joints {offsets}; fit {seconds:.1f} s wall; {v.t.size} raw samples scored")
    print(f"  {'RMS [N·m]':<28}" + "".join(f"{'j' + str(j + 1):>8}" for j in range(n)))
    rows = (("defaults, all samples", v.rms_error), ("baseline, all samples", v.baseline_rms_error),
            ("ratio", ratio), ("defaults, moving", v.rms_error_moving), ("baseline, moving", v.baseline_rms_error_moving),
            ("ratio moving", ratio_m))
    for name, values in rows:
        print(f"  {name:<28}" + "".join(f"{x:8.3f}" for x in values))
    ok = bool(np.all(ratio <= TARGET))
    above = [f"j{j + 1} {r:.3f}" for j, r in enumerate(ratio) if r > TARGET]
    print(f"  target (<= {TARGET} x baseline, all samples) on every joint: {'yes' if ok else 'NO: ' + ', '.join(above)}")
    return ok


def tx40() -> bool:
    bench = _sibling("tx40_heldout")
    robot = rx90sym.load_robot("tx40")
    rec = bench.load(None, robot)
    k = int(round(FIT_SECONDS / bench.PERIOD))
    return compare(f"1. TX40: first {FIT_SECONDS:g} s fitted, the rest predicted", robot, rec.select(slice(0, k)),
                   rec.select(slice(k, None)))


def ur10e() -> list[bool]:
    bench = _sibling("ur10e_heldout")
    if not (bench.DATA / bench.EMPTY[0]).exists():
        print(f"\n2. UR10e: no data in {bench.DATA} (skipped)")
        return []
    robot = bench.robots()[False]
    empty = bench.torques(bench.DATA / bench.EMPTY[0], bench.EMPTY[1], robot)
    p4 = bench.torques(bench.DATA / bench.HELD_OUT[0], bench.HELD_OUT[1], robot)
    first, second = bench.EMPTY[1][0], bench.SECOND_HALF
    half = bench.torques(bench.DATA / bench.EMPTY[0], (first, second[0] - 1), robot)
    rest = bench.torques(bench.DATA / bench.EMPTY[0], second, robot)
    out = [compare(f"2a. UR10e: 14-harmonic run fitted, {bench.HELD_OUT[0]} predicted (at rest)", robot, empty, p4),
           compare(f"2b. UR10e: rows {first}..{second[0] - 1} fitted, rows {second[0]}..{second[1]} predicted",
                   robot, half, rest)]
    # The gains a user gets from `rx90 gains` with its defaults (identify.drive_gains on the empty/loaded pair).
    from identify.gains.drive_gains import drive_gains

    g = bench.gains_bench
    pair = (g.load_run(bench.DATA / g.EMPTY[0], g.EMPTY[1]), g.load_run(bench.DATA / g.LOADED[0], g.LOADED[1]))
    k = drive_gains(robot, [pair[0]], [pair[1]], g.MASS, mass_std=g.MASS_STD).gains.gains
    print(f"\n  gains from rx90 gains' defaults [N·m/A]: {np.round(k, 3)} (the source's: {bench.SOURCE_GAINS})")
    ours = {name: bench.torques(bench.DATA / f, rows, robot, gains=k)
            for name, f, rows in (("empty", *bench.EMPTY), ("p4", *bench.HELD_OUT),
                                  ("half", bench.EMPTY[0], (first, second[0] - 1)), ("rest", bench.EMPTY[0], second))}
    out += [compare(f"2c. UR10e, gains from rx90 gains: 14-harmonic run fitted, {bench.HELD_OUT[0]} predicted",
                    robot, ours["empty"], ours["p4"]),
            compare(f"2d. UR10e, gains from rx90 gains: rows {first}..{second[0] - 1} fitted, the rest predicted",
                    robot, ours["half"], ours["rest"])]
    return out


def timing() -> None:
    from identify.fitting.baseline import fit_baseline

    robot = rx90sym.load_robot("ur10e")
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from motions import multisine

    rec = rx90sym.twin.simulate(robot, multisine(robot, 0, duration=50.0), duration=50.0, rate=100.0,
                                noise="quantised", seed=0)
    fit(robot, [rec.select(slice(0, 500))], Processing(cutoff=5.0))  # compile and warm up
    start = time.process_time()
    fit(robot, [rec], Processing())
    total = time.process_time() - start
    start = time.process_time()
    fit_baseline(robot, [rec])
    base = time.process_time() - start
    print(f"\n3. Default identification of a 50 s, 100 Hz, 6-joint log (UR10e twin): {total:.2f} s CPU (process "
          f"time: the machine is shared), of which the plain baseline's fit {base:.2f} s ({100 * base / total:.1f} %)")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--skip-ur10e", action="store_true")
    ap.add_argument("--skip-tx40", action="store_true")
    ap.add_argument("--skip-timing", action="store_true")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    results = []
    if not args.skip_tx40:
        results.append(tx40())
    if not args.skip_ur10e:
        results += ur10e()
    if not args.skip_timing:
        timing()
    print(f"\ntarget met on every joint of every split: {'yes' if all(results) else 'NO'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
