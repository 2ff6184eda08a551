"""UR10e: the 14-harmonic empty run identified, validated on held-out data; method 3 on the pair
(issue 11, "What it must show").

Data: ../shared/data/ur10e (no licence: read in place, never copied), read by the loader of
benchmarks/ur10e_gains.py (uniform 100 Hz grid). Currents become torques with the source's gains
(README: 10.0, 10.70, 8.46, 9.00, 9.48, 10.12 N·m/A, joint side).

Printed:
1. fit on rows 195..4966 of the empty run with ``identify.fit`` and the defaults of
   ``rx90 identify`` (rest threshold 0.05 rad/s, rest policy zero-coulomb, automatic cut-off,
   decimation to 50 Hz, no delay compensation: the estimate is printed), validated on the whole
   ``ur-20_01_17-p4.csv``. That file is 9.5 s of the robot holding still (recorded velocities 0 on
   every row, positions within 1e-4 rad): a static check, nothing "while moving".
2. the rest policies (none / drop / zero-coulomb; and zero-coulomb with the torque delay
   compensated) with and without torque offsets on that file.
3. a held-out check with motion AND rest: fit on rows 195..2566 of the empty run (~24 s), predict
   rows 2567..5375 (~24 s of motion, then 4.4 s at rest), same policies.
4. the rest threshold (0.005 to 0.2 rad/s; 0.05 is the default) on the split of 3;
5. payload mass by methods 3 (the runs paired by ``identify.signal.pairing``) and 4 on the whole
   14-harmonic pair with the source's gains and with the controller's constants, against the
   weighed 2.805 kg.

Usage: PYTHONPATH=. python benchmarks/ur10e_heldout.py [--data DIR]   (~1 min)
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
from identify import Processing, fit
from identify.io.gains import DriveGains, apply_gains
from identify.observation.processing import friction_label, rest_label


def _sibling(name: str) -> ModuleType:
    """A module of this folder (benchmarks/ is not a package; tests load this file by path)."""
    spec = importlib.util.spec_from_file_location(name, Path(__file__).with_name(f"{name}.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


gains_bench = _sibling("ur10e_gains")
DATA = gains_bench.DATA
EMPTY, LOADED, MASS = gains_bench.EMPTY, gains_bench.LOADED, gains_bench.MASS
SOURCE_GAINS = np.array(gains_bench.SOURCE_GAINS)
HELD_OUT = ("ur-20_01_17-p4.csv", (1, 896))  # the whole file: no bad rows
SECOND_HALF = (2567, 5375)                   # rows of the empty run: motion, then 4.4 s at rest
THRESHOLDS = (0.005, 0.01, 0.02, 0.05, 0.2)  # rad/s, rest thresholds compared in part 4
# The fixed policies with the position-spectrum cut-off (the former defaults: no cross-validation),
# and the defaults (cut-off, decimation and per-joint rest policy cross-validated in the fitted rows).
_FIXED = dict(cross_validate=False)
POLICIES = {"none": dict(min_velocity=None, **_FIXED), "drop": dict(rest="drop", **_FIXED),
            "zero-coulomb": dict(rest="zero-coulomb", **_FIXED),
            "zero-coulomb, delay auto": dict(rest="zero-coulomb", delay="auto", **_FIXED),
            "presliding": dict(rest="presliding", **_FIXED),
            "defaults (cross-validated)": {}}


def torques(path: Path, rows: tuple[int, int], robot: rx90sym.Robot, gains: np.ndarray = SOURCE_GAINS):
    """A UR10e log (rows first..last, 1-based) on the 100 Hz grid, currents turned into torques."""
    return apply_gains(gains_bench.load_run(path, rows), DriveGains(np.asarray(gains), side="joint"), robot)


def robots() -> dict[bool, rx90sym.Robot]:
    robot = gains_bench.ur10e_robot()
    return {False: robot, True: robot.with_options(offsets=True)}


def held_out(robot: rx90sym.Robot, fit_rec, val_rec, **options):
    """(fit, validation) of ``fit_rec`` predicting ``val_rec`` with the fit's processing."""
    options = {"estimate_delay": False, **options}
    f = fit(robot, [fit_rec], Processing(**options))
    return f, f.predict(val_rec)


def policy_table(data: Path, fit_rows: tuple[int, int], val: tuple[str, tuple[int, int]]) -> dict:
    """Validation per (rest policy, offsets) for a fit on ``fit_rows`` of the empty run."""
    out = {}
    for offsets, robot in robots().items():
        fit_rec = torques(data / EMPTY[0], fit_rows, robot)
        val_rec = torques(data / val[0], val[1], robot)
        for name, options in POLICIES.items():
            out[name, offsets] = held_out(robot, fit_rec, val_rec, **options)
    return out


def payload_masses(data: Path) -> dict[str, dict]:
    """Mc (value, std) by methods 3 and 4 on the whole 14-harmonic pair, per set of gains."""
    robot = gains_bench.ur10e_robot()
    empty = gains_bench.load_run(data / EMPTY[0], EMPTY[1])
    loaded = gains_bench.load_run(data / LOADED[0], LOADED[1])
    candidates = {"source (README)": SOURCE_GAINS,
                  "controller constants": gains_bench.controller_constants(empty)}
    return {name: {"gains": k, **gains_bench.held_out_mass(robot, k, empty, loaded)}
            for name, k in candidates.items()}


def errors_on(val, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(relative error %, RMS N·m) per joint of a validation on the samples of ``mask`` (S, n)
    (e.g. the moving samples of another validation with the same filtering)."""
    err, y = val.measured - val.predicted, val.measured
    rel = [100 * np.linalg.norm(err[m, j]) / np.linalg.norm(y[m, j]) if m.any() else np.nan
           for j, m in enumerate(mask.T)]
    rms = [np.sqrt(np.mean(err[m, j] ** 2)) if m.any() else np.nan for j, m in enumerate(mask.T)]
    return np.array(rel), np.array(rms)


def _cells(values: np.ndarray, fmt: str) -> str:
    return "".join(f"{v:{fmt}}" if np.isfinite(v) else f"{'—':>8}" for v in values)


def print_policies(title: str, table: dict) -> None:
    """Relative error [%] and RMS [N·m] per joint on all samples and, where some move, while moving
    (the moving samples of the zero-coulomb run: the same filtering, so the same samples)."""
    print(title)
    print(f"{'rest policy, offsets':<38}{'':>3}" + "".join(f"{'j' + str(j + 1):>8}" for j in range(6)))
    for (name, offsets), (fit, val) in table.items():
        mask = table["zero-coulomb", offsets][1].moving
        if mask.shape != val.moving.shape:  # another decimation: its own moving samples
            mask = val.moving
        label = f"{name}, {'offsets' if offsets else 'no offsets'}"
        if fit.choice is not None:
            form = (fit.model.friction or {}).get("form", "coulomb")
            print(f"  ({name}: cut-off {fit.cutoff:.4g} Hz, decimation to {fit.decimate_to or 0:g} Hz, "
                  f"rest {rest_label(fit.rest)}, friction {friction_label(form)})")
        print(f"{label:<38}%  " + _cells(val.relative_error_pct, "8.1f"))
        print(f"{'  all samples':<38}Nm " + _cells(val.rms_error, "8.3f"))
        if mask.any():
            rel, rms = errors_on(val, mask)
            print(f"{'  while moving':<38}%  " + _cells(rel, "8.1f"))
            print(f"{'':<38}Nm " + _cells(rms, "8.3f"))


def data_folder(argv: list[str] | None, doc: str) -> Path | None:
    """The UR10e data folder from ``--data`` (default ../shared/data/ur10e), None (said on stderr)
    when its runs are not there: one command line for this script and ur10e_prior.py."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA)
    args = ap.parse_args(argv)
    if not (args.data / EMPTY[0]).exists():
        print(f"no UR10e data in {args.data}", file=sys.stderr)
        return None
    return args.data


def main(argv: list[str] | None = None) -> int:
    data = data_folder(argv, __doc__)
    if data is None:
        return 2
    start = time.perf_counter()
    robot = robots()[False]
    fit, val = held_out(robot, torques(data / EMPTY[0], EMPTY[1], robot),
                        torques(data / HELD_OUT[0], HELD_OUT[1], robot), estimate_delay=True)
    print(f"1. Fit: rows {EMPTY[1][0]}..{EMPTY[1][1]} of {EMPTY[0]}, source gains, rx90 identify defaults")
    print(f"   {fit.observation.summary()}".replace("\n", "\n   "))
    if fit.choice is not None:
        print("   " + fit.choice["reason"])
    print(f"   cut-off {fit.cutoff:.4g} Hz, rate {fit.observation.rate:g} Hz, rest {rest_label(fit.rest)}, "
          f"{fit.delay_estimate.summary()} (not compensated)")
    print("   residual RMS per joint [N·m]: " + " ".join(f"{v:.3g}" for v in fit.result.residual_rms))
    print(f"   held out: the whole {HELD_OUT[0]} (robot at rest on every row)")
    print("   " + val.table().replace("\n", "\n   "))

    print()
    print_policies(f"2. Rest policies on {HELD_OUT[0]} (all samples; fit on rows {EMPTY[1][0]}..{EMPTY[1][1]}):",
                   policy_table(data, EMPTY[1], HELD_OUT))
    print()
    half = policy_table(data, (EMPTY[1][0], SECOND_HALF[0] - 1), (EMPTY[0], SECOND_HALF))
    moving = half["zero-coulomb", False][1].moving_fraction
    print_policies(f"3. Fit on rows {EMPTY[1][0]}..{SECOND_HALF[0] - 1}, predict rows "
                   f"{SECOND_HALF[0]}..{SECOND_HALF[1]} of {EMPTY[0]} (moving: "
                   + " ".join(f"{100 * f:.0f}%" for f in moving) + "):", half)

    print("\n4. Rest threshold (zero-coulomb, no offsets) on the split of part 3: error per joint [%]")
    fit_rec = torques(data / EMPTY[0], (EMPTY[1][0], SECOND_HALF[0] - 1), robot)
    val_rec = torques(data / EMPTY[0], SECOND_HALF, robot)
    mask = half["zero-coulomb", False][1].moving
    for threshold in THRESHOLDS:
        _, v = held_out(robot, fit_rec, val_rec, min_velocity=threshold, cross_validate=False)
        rel, _ = errors_on(v, mask)
        print(f"   {threshold:<6g} all samples " + _cells(v.relative_error_pct, "8.1f")
              + f"\n   {'':6s} moving (0.05)" + _cells(rel, "8.1f"))

    print(f"\n5. Payload mass on the whole 14-harmonic pair (weighed {MASS} kg):")
    for name, m in payload_masses(data).items():
        cells = [f"method {k}: {m[k][0]:.3f} ± {m[k][1]:.3f} kg ({100 * (m[k][0] / MASS - 1):+.1f} %)"
                 for k in (3, 4)]
        print(f"   {name:22s}", "   ".join(cells))
        print(f"   {'':22s} gains " + " ".join(f"{k:.4g}" for k in m["gains"]))
    print(f"elapsed {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
