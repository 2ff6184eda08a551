"""The toolkit's defaults against the two yardsticks, per joint, on the raw measured torques.

The yardsticks are the project's (identify.fitting.yardsticks): the plain OLS baseline (10 Hz
zero-phase Butterworth on q at the recording's rate, numpy.gradient, rigid-body regressor plus
[q̇j, sign q̇j, 1] per joint, lstsq(rcond=1e-10), 0.5 s trimmed at both ends) and the model the user
had (the description's rigid bodies as written, on the same filtered signals, with [q̇j, sign q̇j, 1]
per joint fitted to the rest). Both are fitted on the same samples as the defaults
(``identify.fit(robot, recordings, Processing())``) and scored by ``Fit.validate`` on the same raw
samples of the held-out part. Per record and joint: the defaults' held-out RMS, the plain OLS's, the
user model's and the ratio defaults / the better of the two, on all samples scored and while the
joint moves (a held pose: all samples only); target (the issue's "never worse"): at most 1.02x on
every joint. Where the fit ran its blocked cross-validation, the same comparison inside the fitted
data follows: the chosen processing's held-back error per joint (relative, %) beside the
yardsticks' on the same time blocks (identify.fitting.yardsticks.yardstick_folds; the blocks rebuilt
from the choice's candidates and the fit's delay).

Records (one function each; a record that fails prints its error and the others run):
- tx40: the TX40 record shipped in the package (5 kHz, motor side), the first 6 s fitted, the rest
  predicted, robot file as shipped;
- ur10e-halves, ur10e-halves-reverse, ur10e-p4 (../shared/data/ur10e; skipped when absent): the
  14-harmonic run's rows 195..2566 <-> 2567..5375, and the run (rows 195..4966) -> the whole p4 file
  (a held pose, scored on all samples); currents through the controller's own constants (its target
  torque on its target current, 11.76 / 11.74 / 10.23 / 9.611 / 10.98 / 10.54 N·m/A; --ur10e-gains
  source: the gains published with the data, identified: those ``rx90 gains`` identifies with its
  defaults from the empty/loaded pair);
- gen3-run-to-joint2, gen3-joint2-to-run (../shared/data/kinova_gen3, the URDF as it came with the
  logs): the 1.9 s run of every joint <-> the 2.8 s run of joint 2 alone, motor currents through the
  logger's constants (9.13 N·m/A on joints 1-4, 5.852 on 5-7);
- gen3-sensors: the 1.9 s run's joint torque sensors (joint 1's column is 0: not logged), fitted; no
  other run has sensor torques, so only the comparison inside the fitted data is shown;
- twins (``--twins``): the unseen-robot trial of tests/twin_logs.py (a chirp fitted, a trapezoidal
  point-to-point motion with rests predicted; UR5 from its maker's URDF at 100 Hz, Panda at 1 kHz;
  with and without a Stribeck static part; seeds 0..4): per case and joint the ratio defaults / the
  better yardstick, median over the seeds and maximum (targets: median <= 1.02, every run <= 1.10, on
  all samples and while moving);
- timing (``--timing``): the default identification of a 50 s, 100 Hz, 6-joint log (UR10e twin), and
  the yardsticks' pass in it.

BLAS runs on one thread unless OPENBLAS_NUM_THREADS / OMP_NUM_THREADS are set.

Usage: PYTHONPATH=. python benchmarks/defaults_vs_yardsticks.py [--records tx40,ur10e-halves,...]
       [--ur10e-gains controller|source|identified] [--gen3-urdf FILE] [--twins [--seeds 5] [--cases ...]]
       [--timing]
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import sys
import tempfile
import time
import traceback
import warnings
from pathlib import Path
from types import SimpleNamespace

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

import rx90sym  # noqa: E402
from identify import Processing, fit, read_log  # noqa: E402
from identify.estimation.defaults import DEFAULT_DIVERGENCE, DIVERGENCES  # noqa: E402

TARGET = 1.02
#: Twins: the median over the seeds and any single run, per joint.
TWIN_MEDIAN, TWIN_MAX = 1.02, 1.10
FIT_SECONDS = 6.0
ROOT = Path(__file__).resolve().parents[1]
GEN3 = ROOT.parent / "shared" / "data" / "kinova_gen3"
#: The Gen3 logger's current-to-torque constants, joint side [N·m/A].
GEN3_GAINS = "9.13,9.13,9.13,9.13,5.852,5.852,5.852"
#: Its 78 columns: Time (a sample count: the period is 1 ms), Position, Velocity, Torque (computed, not
#: measured), TorqueSm (the sensors), TorqueCur, Temp, Cur, then the commanded signals.
GEN3_CURRENTS = "_,q1..q7,qd1..qd7,_*7,_*7,_*7,_*7,i1..i7,_*28"
GEN3_SENSORS = "_,q1..q7,qd1..qd7,_*7,tau1..tau7,_*7,_*7,_*7,_*28"


def _sibling(name: str):
    spec = importlib.util.spec_from_file_location(name, Path(__file__).with_name(f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def chosen(f) -> str:
    """What the defaults chose: cut-off, decimation, rest policy, friction form, offsets."""
    form = (f.model.friction or {}).get("form", "coulomb")
    offsets = ",".join(map(str, f.model.offset_joints or ())) or "none"
    dec = "none" if f.decimate_to is None else f"{f.decimate_to:.4g} Hz"
    rest = f.rest if isinstance(f.rest, str) else "/".join(r.replace("zero-coulomb", "zc") for r in f.rest)
    return f"cut-off {f.cutoff:.4g} Hz, decimation {dec}, rest {rest}, friction {form}, offsets on joints {offsets}"


def _row(name: str, values, fmt: str = "8.3f") -> str:
    # a figure too wide for its column (a yardstick that cannot predict) in 3 significant digits, apart
    return f"  {name:<30}" + "".join("       -" if v is None or not np.isfinite(v) else
                                     f"{v:{fmt}}" if abs(v) < 1e4 else f" {v:7.2g}" for v in values)


def compare(label: str, robot: rx90sym.Robot, fitted: list, held, moving: bool = True) -> dict:
    """Fit the defaults on ``fitted``, predict ``held``; print the per-joint table (and the comparison inside
    the fitted data). Returns {"all": ratios, "moving": ratios or None} to the better yardstick."""
    start = time.perf_counter()
    f = fit(robot, fitted, Processing(), divergence=DIVERGENCE[0])
    seconds = time.perf_counter() - start
    v = f.validate(held)
    sticks = v.yardsticks()
    if not sticks:
        print(f"\n{label}\n  no yardstick could be fitted ({v.user_model_note or 'the baseline needs a rate above 20 Hz'})")
        return {}
    print(f"\n{label}\n  defaults: {chosen(f)}; fit {seconds:.1f} s wall; {v.t.size} raw samples scored"
          + (f"\n  the model the user had: not computed ({v.user_model_note})" if v.user_model_note else ""))
    print(f"  {'RMS [N·m]':<30}" + "".join(f"{'j' + str(j + 1):>8}" for j in range(robot.n)))
    out = {}
    for suffix, key in (("all samples", False), ("moving", True)):
        if key and not moving:
            continue
        own = v.rms_error_moving if key else v.rms_error
        ratio, better = v.yardstick_ratio(key)
        print(_row(f"defaults, {suffix}", own))
        for name, values in v.yardsticks(key).items():
            print(_row(f"{name}, {suffix}", values))
        print(_row(f"defaults / better, {suffix}", ratio))
        print(f"  {'better yardstick':<30}" + "".join(f"{ {'plain OLS': 'OLS', 'user model': 'user'}.get(b, '-'):>8}"
                                                      for b in better))
        out["moving" if key else "all"] = ratio
    above = [f"j{j + 1} {name} {r:.3f}" for name, r_all in out.items() for j, r in enumerate(r_all) if r > TARGET]
    print(f"  target (<= {TARGET} x the better of {len(sticks)} yardstick(s), "
          f"{'all samples and while moving' if moving else 'all samples'}): {'yes' if not above else 'NO: ' + ', '.join(above)}")
    inside_fitted_data(f, fitted)
    return out


def inside_fitted_data(f, fitted: list) -> None:
    """The chosen processing's held-back error per joint (its blocked cross-validation, relative %) beside the
    yardsticks' on the same time blocks, each fitted on the other blocks."""
    if f.choice is None:
        return
    from identify.selection.raw_torque_scores import raw_span
    from identify.selection.processing_choice import scans_for_choice
    from identify.fitting.yardsticks import yardstick_folds
    from identify.io.blocks import block_source

    choice = f.choice
    if choice.get("skipped"):
        print(f"  inside the fitted data: not cross-validated ({choice['skipped']})")
        return
    held = f.identified.heldout if f.identified is not None else None
    own = (held["per_joint_pct"] if held is not None else
           (choice["offset_candidate"] if choice.get("offsets") else choice["chosen"])["per_joint_pct"])
    grid = [SimpleNamespace(cutoff=c["cutoff_hz"], decimate_to=c["decimate_to_hz"]) for c in choice["candidates"]]
    sources = [block_source(r, f.robot, f.model.convention, f.gains) for r in fitted]
    scans = scans_for_choice(sources, f.block)
    folds = yardstick_folds(f.robot, sources, scans, raw_span(scans, grid, choice["blocks"], f.delay),
                            f.processing.spring, f.block)
    print(f"  inside the fitted data ({choice['blocks']}-block cross-validation, held-back error [%]):")
    print(_row("defaults (identified model)" if held is not None else "defaults (chosen processing)",
               [np.nan if v is None else v for v in own]))
    best = None
    for kind in ("plain", "user"):
        try:
            per_joint = np.array(folds.scores(kind)[1])
        except ValueError:
            continue
        print(_row("plain OLS" if kind == "plain" else "user model", per_joint))
        best = per_joint if best is None else np.fmin(best, per_joint)
    print(_row("defaults / better", np.array([np.nan if v is None else v for v in own], dtype=float) / best))


# ----------------------------------------------------------------------------------------------- records
def tx40(_: str) -> list[dict]:
    bench = _sibling("tx40_heldout")
    robot = rx90sym.load_robot("tx40")
    rec = bench.load(None, robot)
    k = int(round(FIT_SECONDS / bench.PERIOD))
    return [compare(f"TX40: first {FIT_SECONDS:g} s fitted, the rest predicted", robot, [rec.select(slice(0, k))],
                    rec.select(slice(k, None)))]


def _ur10e(gains: str):
    bench = _sibling("ur10e_heldout")
    if not (bench.DATA / bench.EMPTY[0]).exists():
        raise FileNotFoundError(f"no UR10e data in {bench.DATA}")
    robot = bench.robots()[False]
    g = bench.gains_bench
    if gains == "controller":
        k = g.controller_constants(g.load_run(bench.DATA / bench.EMPTY[0], bench.EMPTY[1]))
    elif gains == "identified":  # what `rx90 gains` identifies with its defaults from the empty/loaded pair
        from identify.gains.drive_gains import drive_gains

        pair = (g.load_run(bench.DATA / g.EMPTY[0], g.EMPTY[1]), g.load_run(bench.DATA / g.LOADED[0], g.LOADED[1]))
        k = drive_gains(robot, [pair[0]], [pair[1]], g.MASS, mass_std=g.MASS_STD).gains.gains
    else:
        k = bench.SOURCE_GAINS
    print(f"\n  UR10e gains ({gains}) [N·m/A]: {' / '.join(f'{x:.4g}' for x in k)}")
    first, second = bench.EMPTY[1][0], bench.SECOND_HALF

    def rows(name, r):
        return bench.torques(bench.DATA / name, r, robot, gains=k)
    return bench, robot, rows, first, second


def ur10e_halves(gains: str) -> list[dict]:
    bench, robot, rows, first, second = _ur10e(gains)
    a, b = rows(bench.EMPTY[0], (first, second[0] - 1)), rows(bench.EMPTY[0], second)
    return [compare(f"UR10e ({gains} gains): rows {first}..{second[0] - 1} fitted, rows {second[0]}..{second[1]} "
                    f"predicted", robot, [a], b)]


def ur10e_halves_reverse(gains: str) -> list[dict]:
    bench, robot, rows, first, second = _ur10e(gains)
    a, b = rows(bench.EMPTY[0], (first, second[0] - 1)), rows(bench.EMPTY[0], second)
    return [compare(f"UR10e ({gains} gains): rows {second[0]}..{second[1]} fitted, rows {first}..{second[0] - 1} "
                    f"predicted", robot, [b], a)]


def ur10e_p4(gains: str) -> list[dict]:
    bench, robot, rows, _, _ = _ur10e(gains)
    run, p4 = rows(*bench.EMPTY), rows(*bench.HELD_OUT)
    return [compare(f"UR10e ({gains} gains): the 14-harmonic run fitted, {bench.HELD_OUT[0]} predicted (a held "
                    f"pose: all samples)", robot, [run], p4, moving=False)]


#: The prior's divergence of every fit (--divergence; the library's default unless given).
DIVERGENCE = [DEFAULT_DIVERGENCE]
#: The Gen3's description: the URDF as it came with the logs (--gen3-urdf: another one, e.g. with its inertials made
#: physical while the toolkit refuses those that are not).
GEN3_URDF = [GEN3 / "gen3.urdf"]


def _gen3(columns: str, name: str, gains: str | None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the URDF's missing acceleration and joint limits
        robot = rx90sym.load_robot(str(GEN3_URDF[0]))
    return robot, read_log(GEN3 / name, robot, columns, header=True, period=0.001, gains=gains)


def gen3_run_to_joint2(_: str) -> list[dict]:
    robot, run = _gen3(GEN3_CURRENTS, "RunTrajectory1.csv", GEN3_GAINS)
    _, joint2 = _gen3(GEN3_CURRENTS, "joint_2_trapez.csv", GEN3_GAINS)
    return [compare("Gen3 (currents, the logger's constants): the 1.9 s run of every joint fitted, the run of "
                    "joint 2 alone predicted", robot, [run], joint2)]


def gen3_joint2_to_run(_: str) -> list[dict]:
    robot, run = _gen3(GEN3_CURRENTS, "RunTrajectory1.csv", GEN3_GAINS)
    _, joint2 = _gen3(GEN3_CURRENTS, "joint_2_trapez.csv", GEN3_GAINS)
    return [compare("Gen3 (currents, the logger's constants): the run of joint 2 alone fitted, the 1.9 s run "
                    "predicted", robot, [joint2], run)]


def gen3_sensors(_: str) -> list[dict]:
    robot, run = _gen3(GEN3_SENSORS, "RunTrajectory1.csv", None)
    start = time.perf_counter()
    f = fit(robot, [run], Processing(), divergence=DIVERGENCE[0])
    print(f"\nGen3 (joint torque sensors, joint 1 not logged): the 1.9 s run fitted\n  defaults: {chosen(f)}; "
          f"fit {time.perf_counter() - start:.1f} s wall")
    inside_fitted_data(f, [run])
    return []


RECORDS = {"tx40": tx40, "ur10e-halves": ur10e_halves, "ur10e-halves-reverse": ur10e_halves_reverse,
           "ur10e-p4": ur10e_p4, "gen3-run-to-joint2": gen3_run_to_joint2, "gen3-joint2-to-run": gen3_joint2_to_run,
           "gen3-sensors": gen3_sensors}


def timing() -> None:
    from identify.fitting.yardsticks import fit_yardsticks

    robot = rx90sym.load_robot("ur10e")
    sys.path.insert(0, str(ROOT / "tests"))
    from motions import multisine

    rec = rx90sym.twin.simulate(robot, multisine(robot, 0, duration=50.0), duration=50.0, rate=100.0,
                                noise="quantised", seed=0)
    fit(robot, [rec.select(slice(0, 500))], Processing(cutoff=5.0))  # compile and warm up
    start = time.process_time()
    fit(robot, [rec], Processing())
    total = time.process_time() - start
    start = time.process_time()
    fit_yardsticks(robot, [rec])
    base = time.process_time() - start
    print(f"\nDefault identification of a 50 s, 100 Hz, 6-joint log (UR10e twin): {total:.2f} s CPU (process "
          f"time: the machine is shared), of which the yardsticks' pass {base:.2f} s ({100 * base / total:.1f} %)")


def twins(seeds: int, names: list[str] | None, short: bool = False) -> bool:
    """Per case the per-joint ratios to the better yardstick over the seeds; True when both twin targets hold.
    short: the short point-to-point twins with the descriptions users hold (tests/twin_logs.py SHORT_CASES)."""
    sys.path.insert(0, str(ROOT / "tests"))
    from short_twins import SHORT_CASES, short_logs
    from twin_logs import CASES, twin_logs

    cases = [c for c in (SHORT_CASES if short else CASES) if names is None or c.name in names]
    ok_all = True
    what = ("short point-to-point motion fitted, another predicted; the description exact, 50 % off or not physical"
            if short else "chirp fitted, trapezoidal point-to-point motion predicted")
    print(f"\nTwins: {what}; seeds 0..{seeds - 1}; targets per "
          f"joint: median ratio to the better yardstick <= {TWIN_MEDIAN}, every run <= {TWIN_MAX}")
    with tempfile.TemporaryDirectory() as work:
        for case in cases:
            runs = {False: [], True: []}
            lines = []
            for seed in range(seeds):
                logs = (short_logs if short else twin_logs)(case, seed, Path(work))
                f = fit(logs.robot, [logs.fitted], Processing(), divergence=DIVERGENCE[0])
                v = f.validate(logs.predicted)
                for moving in runs:
                    runs[moving].append(v.yardstick_ratio(moving)[0])
                better = v.yardstick_ratio()[1]
                lines.append(f"    seed {seed}: {chosen(f)}; better yardstick per joint "
                             + " ".join("OLS" if b == "plain OLS" else "user" for b in better))
            ratios, moving = np.array(runs[False]), np.array(runs[True])
            n = ratios.shape[1]
            med, top = np.median(ratios, axis=0), ratios.max(axis=0)
            med_m, top_m = np.nanmedian(moving, axis=0), np.nanmax(moving, axis=0)
            ok = bool(np.all(np.r_[med, med_m] <= TWIN_MEDIAN) and np.all(np.r_[top, top_m] <= TWIN_MAX))
            ok_all &= ok
            print(f"\n  {case.name}: {logs.robot.n} joints, {case.rate:g} Hz, "
                  + (f"description {case.kind}, fit {case.fit_s:g} s, predict {case.predict_s:g} s" if short else
                     f"Stribeck static part {case.stribeck:g} x FS, fit {case.fit_s:g} s chirp, predict "
                     f"{case.predict_s:g} s point-to-point"))
            print(f"  {'defaults / better':<30}" + "".join(f"{'j' + str(j + 1):>8}" for j in range(n)))
            for name, values in (("all samples, median", med), ("all samples, max", top),
                                 ("moving, median", med_m), ("moving, max", top_m)):
                print(_row(name, values))
            above = [f"j{j + 1} {what} (median {m[j]:.3f}, max {t[j]:.3f})" for what, m, t in
                     (("all samples", med, top), ("moving", med_m, top_m)) for j in range(n)
                     if m[j] > TWIN_MEDIAN or t[j] > TWIN_MAX]
            print(f"  targets on every joint: {'yes' if ok else 'NO: ' + ', '.join(above)}")
            print("  defaults chose:\n" + "\n".join(lines))
    return ok_all


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", default=",".join(RECORDS), help=f"comma-separated (default all: {', '.join(RECORDS)})")
    ap.add_argument("--ur10e-gains", choices=("controller", "source", "identified"), default="controller")
    ap.add_argument("--twins", action="store_true", help="the twin cases (tests/twin_logs.py)")
    ap.add_argument("--short-twins", action="store_true", help="the short point-to-point twins with the descriptions "
                    "users hold (tests/twin_logs.py SHORT_CASES)")
    ap.add_argument("--divergence", choices=DIVERGENCES, default=DEFAULT_DIVERGENCE,
                    help=f"the prior's divergence D of every fit (default {DEFAULT_DIVERGENCE})")
    ap.add_argument("--seeds", type=int, default=5, help="twins: seeds 0..N-1 (default 5)")
    ap.add_argument("--cases", default=None, help="twins: comma-separated case names (default: all)")
    ap.add_argument("--timing", action="store_true", help="the default identification's time and the yardsticks'")
    ap.add_argument("--gen3-urdf", type=Path, default=GEN3_URDF[0], help="the Gen3's description (default: the "
                    "URDF as it came with the logs)")
    args = ap.parse_args()
    GEN3_URDF[0] = args.gen3_urdf
    DIVERGENCE[0] = args.divergence
    names = [r for r in args.records.split(",") if r]
    unknown = sorted(set(names) - set(RECORDS))
    if unknown:
        ap.error(f"unknown record(s) {', '.join(unknown)}; known: {', '.join(RECORDS)}")
    warnings.simplefilter("ignore")
    met, failed = [], []
    for name in names:
        try:
            met += [bool(np.all(np.nan_to_num(r, nan=0.0) <= TARGET)) for out in RECORDS[name](args.ur10e_gains)
                    for r in out.values()]
        except Exception as exc:  # a record that cannot run today: its error, and the others run
            failed.append(name)
            print(f"\n{name}: not run: {type(exc).__name__}: {exc}")
            traceback.print_exc(limit=-2, file=sys.stdout)
    if args.timing:
        timing()
    if args.twins:
        met.append(twins(args.seeds, args.cases.split(",") if args.cases else None))
    if args.short_twins:
        met.append(twins(args.seeds, args.cases.split(",") if args.cases else None, short=True))
    print(f"\ntarget met on every joint of every record run{' and twin case' if args.twins or args.short_twins else ''}: "
          f"{'yes' if all(met) else 'NO'}" + (f"; not run: {', '.join(failed)}" if failed else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
