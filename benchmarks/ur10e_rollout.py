"""UR10e: the identified model in MuJoCo against the robot's own motion (issue 39, "What it must show").

Data: ../shared/data/ur10e (no licence: read in place, never copied), every log read as a new user
would (``identify.read_log``, the README's column map) on a 500 Hz grid, currents x the README's gains
(10.0, 10.70, 8.46, 9.00, 9.48, 10.12 N m/A, joint side). Fits with the defaults of ``rx90 identify``
(their identified model is what ``rx90 export --mjcf`` writes). Rollouts with
``identify.roll_out_fit`` (what ``rx90 predict --rollout`` runs), 0.25 s and 0.5 s windows.

1. first half -> second half: fit rows 195..2566 of the 14-harmonic run, roll out rows 2567..5375
   (motion, then 4.4 s at rest): per joint the RMS end-position error of the identified model, the
   constant-velocity guess and the nominal description (its bodies and rotor inertias with the fit's
   friction), the share of windows the identified model beats the guess, its ratio to the guess; the
   same started from the recorded q̇ column instead of the filtered derivative.
2. 14-harmonic run -> loaded run: fit rows 195..4966 of the empty run; the payload by method 1
   (the fit itself: its identified model, offsets and processing; ``constrained``) on the loaded run's rows 308..2689; roll out its rows
   2690..5071 with the payload on the exported model's flange (and without it, for contrast).
3. the torque delay: the rollout of 1. with the torques advanced by -20..+20 ms (2 ms steps, a
   sample): per joint RMS end error at 0.25 s, where it is smallest, beside the fit's delay estimate;
   then the same around the delay of a fit that compensates its estimate (``Processing(delay="auto")``).

Usage: PYTHONPATH=. python benchmarks/ur10e_rollout.py [--data DIR]   (~1 min)
"""
from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import rx90sym
from identify import Processing, fit, payload, read_log
from identify.rollout.run import roll_out_fit

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "ur10e"
EMPTY, LOADED = "ur-20_02_19_14harm50sec.csv", "ur-20_02_19_14harm50secLoad.csv"
COLUMNS = "t,q1..q6,qd1..qd6,i1..i6,x:i_target1..x:i_target6,x:tau_target1..x:tau_target6"  # the data README
GAINS = "10.0,10.70,8.46,9.00,9.48,10.12"  # N m/A, joint side (README)
RATE = 500.0  # Hz
FIT_ROWS, HELD_ROWS = (195, 2566), (2567, 5375)
EMPTY_ROWS, LOADED_FIT, LOADED_HELD = (195, 4966), (308, 2689), (2690, 5071)
WINDOWS = (0.25, 0.5)
DELAYS_MS = tuple(range(-20, 21, 2))


def load(name: str, rows: tuple[int, int], data: Path = DATA) -> rx90sym.Recording:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return read_log(data / name, rx90sym.load_robot("ur10e"), COLUMNS, rows=rows, resample=RATE, gains=GAINS)


def mrad(values: np.ndarray) -> str:
    return " / ".join(f"{1e3 * v:.3g}" for v in values)


def table(title: str, out) -> list[str]:
    """Markdown rows: per window, identified / nominal / guess RMS end-position [mrad], the share of windows
    beating the guess and the identified model's ratio to the guess."""
    lines = [f"\n{title}", "", "| window | model | end-position RMS error [mrad], joints 1-6 | beats the guess [%] |",
             "|---|---|---|---|"]
    for w in out.windows:
        for m in (*out.models, "guess"):
            share = "" if m == "guess" else " / ".join(f"{100 * v:.0f}" for v in w.beats_guess(m))
            lines.append(f"| {w.asked_s:g} s | {m} | {mrad(w.rms(m))} | {share} |")
        ratio = w.rms("identified") / w.rms("guess")
        below = "every joint" if np.all(ratio < 1) else "joints " + ", ".join(str(j + 1) for j in np.flatnonzero(ratio < 1))
        lines.append(f"| {w.asked_s:g} s | identified / guess | {' / '.join(f'{r:.2f}' for r in ratio)} | "
                     f"below on {below} |")
        if "nominal" in out.models:
            beats = w.rms("identified") < w.rms("nominal")
            lines.append(f"| {w.asked_s:g} s | identified below nominal | "
                         f"{'every joint' if beats.all() else 'not on joints ' + str(list(np.flatnonzero(~beats) + 1))} | |")
        lines.append(f"| {w.asked_s:g} s | windows | {w.windows} scored, {w.skipped_rest} at rest skipped | |")
    return lines


def delay_curve(f, recording, around: float) -> None:
    """The rollout's RMS end-position error at 0.25 s with the torques advanced by ``around`` + d, d in
    DELAYS_MS, as a markdown table, and where it is smallest."""
    print("| d [ms] | end-position RMS [mrad], joints 1-6 | root of the sum of squares |\n|---|---|---|")
    curve = []
    for d in DELAYS_MS:
        e = roll_out_fit(f, recording, 0.25, nominal=False, delay=around + 1e-3 * d).windows[0].rms("identified")
        curve.append(e)
        print(f"| {d:+d} | {mrad(e)} | {1e3 * np.linalg.norm(e):.3g} |")
    curve = np.array(curve)
    best = [DELAYS_MS[k] for k in np.argmin(curve, axis=0)]
    print(f"smallest per joint at d = {best} ms; of the sum at d = "
          f"{DELAYS_MS[int(np.argmin(np.linalg.norm(curve, axis=1)))]} ms")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA)
    args = ap.parse_args(argv)
    if not (args.data / EMPTY).exists():
        print(f"UR10e logs not found in {args.data}: give --data (../shared/data/ur10e)", file=sys.stderr)
        return 2
    start = time.perf_counter()
    robot = rx90sym.load_robot("ur10e")
    print(f"load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; logs on a {RATE:g} Hz grid, gains {GAINS} N m/A")

    # 1. first half -> second half
    first, second = load(EMPTY, FIT_ROWS, args.data), load(EMPTY, HELD_ROWS, args.data)
    f = fit(robot, [first])
    print(f"fit rows {FIT_ROWS[0]}..{FIT_ROWS[1]}: cut-off {f.cutoff:g} Hz, torque delay compensated {1e3 * f.delay:g} "
          f"ms; {f.delay_estimate.summary()}")
    t0 = time.perf_counter()
    halves = roll_out_fit(f, second, WINDOWS)
    took = time.perf_counter() - t0
    print("\n".join(table(f"1. rows {FIT_ROWS[0]}..{FIT_ROWS[1]} -> {HELD_ROWS[0]}..{HELD_ROWS[1]} of {EMPTY} "
                          f"(start velocity: filtered derivative; rollout {took:.2f} s)", halves)))
    recorded = roll_out_fit(f, second, WINDOWS, velocity="recorded", nominal=False)
    print("\n".join(table("1b. the same, started from the recorded q̇ column", recorded)))

    # 2. 14-harmonic run -> loaded run, the identified payload on the flange
    empty = load(EMPTY, EMPTY_ROWS, args.data)
    loaded_fit, loaded_held = load(LOADED, LOADED_FIT, args.data), load(LOADED, LOADED_HELD, args.data)
    g = fit(robot, [empty])
    p = payload(robot, 1, loaded=[loaded_fit], robot_params=g, constrained=True)
    load_values = p.as_dict()
    print(f"\n2. fit rows {EMPTY_ROWS[0]}..{EMPTY_ROWS[1]} of {EMPTY}; payload (method 1, constrained) on rows "
          f"{LOADED_FIT[0]}..{LOADED_FIT[1]} of {LOADED}: Mc = {load_values['Mc']:.3f} kg (weighed 2.805 kg)")
    with_load = roll_out_fit(g, loaded_held, WINDOWS, payload=load_values)
    print("\n".join(table(f"2. rollout on rows {LOADED_HELD[0]}..{LOADED_HELD[1]} of {LOADED}, the payload on the "
                          f"exported model's flange", with_load)))
    bare = roll_out_fit(g, loaded_held, WINDOWS, nominal=False)
    print("\n".join(table("2b. the same without the payload", bare)))

    # 3. the torque delay
    print(f"\n3. rollout of 1. (0.25 s windows) with the torques advanced by d [ms]; the fit's estimate: "
          f"{f.delay_estimate.summary()}")
    delay_curve(f, second, 0.0)
    auto = fit(robot, [first], Processing(delay="auto"))
    print(f"\n3b. a fit compensating its estimate ({1e3 * auto.delay:.3g} ms), the torques advanced by its delay + d [ms]")
    delay_curve(auto, second, auto.delay)
    print(f"\nelapsed {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
