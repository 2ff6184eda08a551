"""UR10e: believable bodies with the description as the prior (the identified model of the defaults).

Data: ../shared/data/ur10e (no licence: read in place, never copied), read by the loader of
benchmarks/ur10e_heldout.py (uniform 100 Hz grid); currents -> torques with the controller's own
constants (its target torque on its target current: 11.76, 11.74, 10.23, 9.611, 10.98, 10.54 N m/A;
``--gains source`` for the ones published with the data).

1. Bodies: fit rows 195..4966 of the 14-harmonic empty run with the defaults of ``rx90 identify``: per
   link the identified mass beside UR's (the UR10e [nominal] table, the prior), the whole arm, the
   prior weight λ chosen.
2. Held out: fit rows 195..2566, predict rows 2567..5375 (motion, then 4.4 s at rest): per joint the
   RMS of the identified model and of the fit's WLS estimates, all samples and while moving, their
   ratio; ``--sweep``: the same at every λ of the grid.

Usage: PYTHONPATH=. python benchmarks/ur10e_prior.py [--data DIR] [--gains controller|source] [--sweep]  (~20 s)
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

import rx90sym
from identify import fit
from identify.selection.prior_weight import WEIGHT_GRID
from ur10e_heldout import DATA, EMPTY, SOURCE_GAINS, gains_bench, torques   # this folder (the script's own)

CONTROLLER_GAINS = (11.76, 11.74, 10.23, 9.611, 10.98, 10.54)
BODY_ROWS, FIT_ROWS, HELD_ROWS = (195, 4966), (195, 2566), (2567, 5375)


def moving_rms(val) -> np.ndarray:
    err = val.measured - val.predicted
    return np.array([np.sqrt(np.mean(err[val.moving[:, j], j] ** 2)) for j in range(err.shape[1])])


def held_out(f, held) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(model all, model moving, WLS all, WLS moving) RMS per joint [N m]."""
    model, wls = f.predict(held), f.predict(held, f.least_squares)
    return model.rms_error, moving_rms(model), wls.rms_error, moving_rms(wls)


def _row(label: str, values) -> str:
    return f"  {label:<26}" + "".join(f"{v:8.3f}" for v in values)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA)
    ap.add_argument("--gains", choices=("controller", "source"), default="controller")
    ap.add_argument("--sweep", action="store_true", help="the held-out figures at every λ of the grid")
    args = ap.parse_args(argv)
    if not (args.data / EMPTY[0]).exists():
        print(f"UR10e logs not found in {args.data}: give --data (../shared/data/ur10e)", file=sys.stderr)
        return 2
    start = time.perf_counter()
    robot = gains_bench.ur10e_robot()
    gains = np.array(CONTROLLER_GAINS if args.gains == "controller" else SOURCE_GAINS)
    print(f"load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; gains ({args.gains}) "
          + " / ".join(f"{k:.4g}" for k in gains) + " N m/A")

    # 1. bodies
    f = fit(robot, [torques(args.data / EMPTY[0], BODY_ROWS, robot, gains)])
    maker = rx90sym.nominal_parameters(robot)
    model = f.identified.standard
    print(f"\n1. rows {BODY_ROWS[0]}..{BODY_ROWS[1]}: λ {f.identified.prior['weight_label']} chosen")
    print(f"  {'link':<6}{'identified kg':>14}{'UR kg':>8}{'ratio':>7}")
    for j in range(1, robot.n + 1):
        print(f"  {j:<6}{model[f'M{j}']:14.2f}{maker[f'M{j}']:8.2f}{model[f'M{j}'] / maker[f'M{j}']:7.2f}")
    total, ur = (sum(v[f"M{j}"] for j in range(1, robot.n + 1)) for v in (model, maker))
    print(f"  {'arm':<6}{total:14.2f}{ur:8.2f}{total / ur:7.3f}")

    # 2. held out
    fitted, held = (torques(args.data / EMPTY[0], rows, robot, gains) for rows in (FIT_ROWS, HELD_ROWS))
    weights = (("auto",) + WEIGHT_GRID) if args.sweep else ("auto",)
    print(f"\n2. rows {FIT_ROWS[0]}..{FIT_ROWS[1]} fitted, {HELD_ROWS[0]}..{HELD_ROWS[1]} predicted: RMS [N m]"
          + "".join(f"{'j' + str(j + 1):>8}" for j in range(robot.n)))
    for w in weights:
        g = fit(robot, [fitted], prior_weight=w)
        m_all, m_mov, w_all, w_mov = held_out(g, held)
        label = g.identified.prior["weight_label"] + (" (auto)" if w == "auto" else "")
        if w == "auto":
            print(_row("WLS, all samples", w_all))
            print(_row("WLS, moving", w_mov))
        print(f"  λ {label}")
        print(_row("model, all samples", m_all))
        print(_row("model, moving", m_mov))
        print(_row("model / WLS, all samples", m_all / w_all))
        print(_row("model / WLS, moving", m_mov / w_mov))
    print(f"\nelapsed {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
