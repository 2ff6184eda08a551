"""Friction forms and the presliding rest policy on the twin, the TX40 and the UR10e (issue 21, item 4).

Printed, per (friction form, rest policy):

1. twin stop-and-go (RX90, 30 s at 200 Hz, 1 s moves and 1 s holds, true friction a Dahl
   presliding state of 5 mrad times FSj, 1 % torque noise; tests/test_presliding.py's twin): fit on
   the first 2/3, all-sample held-out error [%] of the last third, per seed;
2. TX40 (bundled file, offsets): fit on the first 6 s, held-out RMS while moving and on all samples
   [N·m] (benchmarks/tx40_heldout.py's split and part 2a; today's zero-coulomb Coulomb while moving:
   1.806 / 1.761 / 1.171 / 0.563 / 1.041 / 0.691);
3. UR10e 14-harmonic run: fit on rows 195..2566, held-out rows 2567..5375 (motion, then 4.4 s at
   rest; benchmarks/ur10e_heldout.py part 3): errors [%] on all samples and while moving (the
   moving samples of the zero-coulomb run), and on the static ur-20_01_17-p4.csv the RMS error
   [N·m] beside the identified FSj (the check: error within FSj).

Usage: OPENBLAS_NUM_THREADS=1 PYTHONPATH=. python benchmarks/friction_forms.py [--seeds 3] [--skip twin,tx40,ur10e]
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
import time
from pathlib import Path
from types import ModuleType

import numpy as np

import rx90sym
from identify import Processing, fit, split
from rx90sym.recording import Recording

#: (label, friction form, Processing options of the rest handling).
CASES = (("coulomb, zero-coulomb", "coulomb", {"rest": "zero-coulomb"}),
         ("coulomb, presliding", "coulomb", {"rest": "presliding"}),
         ("tanh, zero-coulomb", "tanh", {"rest": "zero-coulomb"}),
         ("tanh, no rest handling", "tanh", {"min_velocity": None}),
         ("tanh, presliding", "tanh", {"rest": "presliding"}),
         ("stribeck, no rest handling", "stribeck", {"min_velocity": None}))


def _load(name: str, folder: str = "benchmarks") -> ModuleType:
    path = Path(__file__).resolve().parent.parent / folder / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"_ff_{name}", path)
    module = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(path.parent))
    spec.loader.exec_module(module)
    return module


def _row(label: str, values: np.ndarray, fmt: str = "7.2f") -> str:
    return f"  {label:<30}" + "".join(f"{v:{fmt}}" for v in values)


def _friction_note(f) -> str:
    """The velocity scales [rad/s] and presliding travels [mrad] a fit found."""
    found = f.model.friction or {}
    note = f"  vs {np.round(found['velocity_scale'], 4).tolist()}" if "velocity_scale" in found else ""
    if "presliding_travel" in found:
        note += "  δ " + " ".join("-" if d is None else f"{1e3 * d:g}" for d in found["presliding_travel"])
    return note


def twin(seeds: int) -> None:
    t_mod = _load("test_presliding", "tests")
    robot = rx90sym.load_robot("rx90")
    base = rx90sym.base_parameters(robot)
    chi = robot.parameter_vector(rx90sym.twin.default_parameters(robot))
    print("1. Twin stop-and-go, Dahl presliding 5 mrad: all-sample held-out error [%] per joint")
    for seed in range(seeds):
        t, q, qd, qdd = t_mod.stop_and_go(robot, seed)
        fit_part, held = split(Recording(t=t, q=q, tau=t_mod.presliding_torques(robot, chi, q, qd, qdd, seed),
                                         dq=qd, robot=robot.name), 2 / 3)
        for label, form, rest in CASES:
            f = fit(robot, [fit_part], Processing(friction=form, estimate_delay=False, **rest), base=base)
            print(_row(f"seed {seed} {label}", f.predict(held).relative_error_pct) + _friction_note(f))


def tx40() -> None:
    bench = _load("tx40_heldout")
    robot = rx90sym.load_robot("tx40", offsets=True)   # as tx40_heldout.py's part 2
    rec = bench.load(None, robot)
    print("2. TX40, fit on the first 6 s: held-out RMS [N·m] while moving | all samples")
    for label, form, rest in CASES:
        start = time.perf_counter()
        moving, every, f = bench.heldout(robot, rec, friction=form, **rest)
        scales = _friction_note(f)
        print(_row(label, moving, "7.3f") + " |" + "".join(f"{v:7.3f}" for v in every)
              + f"  ({time.perf_counter() - start:.0f} s){scales}")


def ur10e() -> None:
    bench = _load("ur10e_heldout")
    if not (bench.DATA / bench.EMPTY[0]).exists():
        print(f"3. UR10e: no data in {bench.DATA}: skipped")
        return
    robot = bench.robots()[False]
    fit_rec = bench.torques(bench.DATA / bench.EMPTY[0], (bench.EMPTY[1][0], bench.SECOND_HALF[0] - 1), robot)
    val_rec = bench.torques(bench.DATA / bench.EMPTY[0], bench.SECOND_HALF, robot)
    static = bench.torques(bench.DATA / bench.HELD_OUT[0], bench.HELD_OUT[1], robot)
    print("3. UR10e 14-harmonic, held-out rows 2567..5375: error [%] all samples | while moving; "
          "static p4: RMS error [N·m] / FSj")
    mask = None
    for label, form, rest in CASES:
        f, v = bench.held_out(robot, fit_rec, val_rec, friction=form, **rest)
        mask = v.moving if mask is None else mask   # the zero-coulomb run's moving samples
        moving, _ = bench.errors_on(v, mask)
        values = dict(zip(f.result.names, f.result.values))
        fs = np.array([values[f"FS{j}"] for j in range(1, 7)])
        p4 = f.predict(static).rms_error
        scales = _friction_note(f)
        fp = [values.get(f"FP{j}", np.nan) for j in range(1, 7)]
        print(_row(label, v.relative_error_pct, "6.1f") + " |" + "".join(f"{x:6.1f}" for x in moving) + scales)
        print(_row("  p4 error / FS", p4 / fs, "6.2f") + "   FP " + " ".join(f"{x:.2f}" for x in fp))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--skip", default="", help="comma-separated parts to skip: twin, tx40, ur10e")
    args = ap.parse_args(argv)
    skip = set(filter(None, args.skip.split(",")))
    start = time.perf_counter()
    for name, part in (("twin", lambda: twin(args.seeds)), ("tx40", tx40), ("ur10e", ur10e)):
        if name not in skip:
            part()
            print()
    print(f"elapsed {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
