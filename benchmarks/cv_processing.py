"""Processing chosen by cross-validation against the best cut-off of a grid and a plain 10 Hz LS.

Twin of a 7-joint arm (Panda, 1 kHz, open loop, 2^19-count encoders) at three torque-noise levels;
fit on the first 2/3 of a 20 s run, predict the last 1/3; every figure is the relative RMS error
of the predicted torques against the **noise-free** torques (%). Per run: the cross-validated
choice (identify.selection.cross_validation, rest policy chosen per joint), the best candidate
of its grid, the toolkit's defaults (``identify.fit`` with ``Processing()``: the cross-validation
runs inside the fit), the former defaults (automatic cut-off, zero-coulomb, no cross-validation),
and the plain least squares of benchmarks/plain_ls.py (the reference measured in the same run); the
friction form the defaults chose (identify.friction.choice; the twin's is Coulomb + viscous).

Two scorings of the held-out third: each processing on the samples it keeps (its own filter's edges
dropped, as `rx90 predict` does: a 2 Hz cut-off keeps the central 55 %, 20 Hz 95 %), and every one
on the same samples (common_window: without the lowest cut-off's edges), the fair comparison of
the candidates ("common" column and the second median).

Usage: python benchmarks/cv_processing.py [--seeds 5] [--noise 0.015,0.05,0.15] [--duration 20]
"""
from __future__ import annotations

import argparse
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks"), str(ROOT / "tests")]

import rx90sym  # noqa: E402
from identify import Processing, fit, predict, split  # noqa: E402
from identify.selection.processing_choice import choose_processing  # noqa: E402
from identify.observation.processing import friction_label, rest_label  # noqa: E402
from identify.signal.filtering import EDGE_PERIODS  # noqa: E402
from motions import multisine, panda_truth  # noqa: E402
from plain_ls import PLAIN_CUTOFF, plain_ls, plain_prediction  # noqa: E402
from rx90sym.recording import Recording  # noqa: E402


def relative(pred: np.ndarray, truth: np.ndarray) -> np.ndarray:
    return 100 * np.linalg.norm(pred - truth, axis=0) / np.linalg.norm(truth, axis=0)


def held_out_error(robot, base, fit_part, test_clean, cutoff, decimate_to, rest, window,
                   **options) -> tuple[np.ndarray, np.ndarray, str]:
    """(relative error per joint [%] on the samples the processing keeps (its own filter's edges
    dropped), the same on the samples of ``window`` (t0, t1) [s] only, the fit's friction form)."""
    fit_ = fit(robot, [fit_part], Processing(cutoff=cutoff, decimate_to=decimate_to, rest=rest,
                                            min_velocity=None if rest is None and cutoff else 0.05,
                                            estimate_delay=False, **options), base=base)
    val = predict(robot, fit_.result, test_clean, base=base, cutoff=fit_.cutoff, decimate_to=None,
                  min_velocity=fit_.min_velocity, rest=fit_.rest)
    form = (fit_.model.friction or {}).get("form", "coulomb")
    inside = _inside(val.t, window)
    return (relative(val.predicted, val.measured), relative(val.predicted[inside], val.measured[inside]),
            friction_label(tuple(form) if isinstance(form, list) else form))


def _inside(t: np.ndarray, window: tuple[float, float]) -> np.ndarray:
    inside = (t >= window[0] - 1e-9) & (t <= window[1] + 1e-9)
    if not inside.any():
        raise ValueError(f"no prediction inside {window}")
    return inside


def common_window(test: Recording, lowest_cutoff: float) -> tuple[float, float]:
    """The test samples every processing predicts [s]: without the edges of the lowest cut-off's filter
    (EDGE_PERIODS of its periods) and the plain LS's, so that every candidate is scored on the same
    samples (each alone drops only its own edges: 1.5 s at each end at 2 Hz, 0.15 s at 20 Hz)."""
    t = np.asarray(test.t)
    edge = EDGE_PERIODS / lowest_cutoff + 1.0 / PLAIN_CUTOFF
    return float(t[0] + edge), float(t[-1] - edge)


def one_run(robot, base, truth, seed: int, noise: float, duration: float) -> dict:
    profile = replace(rx90sym.twin.profiles()["quantised"], torque_noise=noise)
    motion = multisine(robot, seed, duration=duration)
    rec = rx90sym.twin.simulate(robot, motion, params=truth, duration=duration, rate=1000.0, noise=profile, seed=seed)
    clean = rx90sym.twin.simulate(robot, motion, params=truth, duration=duration, rate=1000.0,
                                  noise=replace(profile, torque_noise=0.0), seed=seed)
    fit_part, _ = split(rec, 2 / 3)
    _, test_clean = split(clean, 2 / 3)
    choice = choose_processing(robot, [fit_part], base=base, min_velocity=0.05)
    window = common_window(test_clean, min(c.cutoff for c in choice.candidates))
    grid = {(c.cutoff, c.decimate_to, c.rest): held_out_error(robot, base, fit_part, test_clean, c.cutoff,
                                                               c.decimate_to, c.rest, window)[:2]
            for c in choice.candidates if not np.isnan(c.score)}
    chosen, chosen_common = grid[(choice.chosen.cutoff, choice.chosen.decimate_to, choice.chosen.rest)]
    default, default_common, form = held_out_error(robot, base, fit_part, test_clean, None, 50.0, None, window)
    former = held_out_error(robot, base, fit_part, test_clean, None, 50.0, "zero-coulomb", window,
                            cross_validate=False)[0]
    baseline = plain_ls(robot, fit_part)
    pred, kept = plain_prediction(robot, baseline, test_clean)
    plain = relative(pred, np.asarray(test_clean.tau)[kept])
    inside = _inside(np.asarray(test_clean.t)[kept], window)
    plain_common = relative(pred[inside], np.asarray(test_clean.tau)[kept][inside])
    best = min((v[0] for v in grid.values()), key=lambda v: float(np.mean(v)))
    best_common = min((v[1] for v in grid.values()), key=lambda v: float(np.mean(v)))
    # A cut-off drawn at random among those scored with the rest policy chosen (the choice's second stage):
    # the mean of their errors, what a choice blind to the torques gets on average.
    at_random = float(np.mean([np.mean(v[0]) for (c, d, rest), v in grid.items() if rest == choice.chosen.rest]))
    return {"chosen": chosen, "best": best, "default": default, "former": former, "plain": plain,
            "chosen_common": chosen_common, "best_common": best_common, "default_common": default_common,
            "plain_common": plain_common,
            "at_random": at_random, "seconds": choice.seconds, "friction": form,
            "cutoff": choice.chosen.cutoff, "knee": choice.knee, "rest": choice.chosen.rest}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--noise", default="0.015,0.05,0.15")
    ap.add_argument("--duration", type=float, default=20.0)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    robot = rx90sym.load_robot("panda")
    base = rx90sym.base_parameters(robot)
    truth = panda_truth(robot)
    runs = []
    print(f"{'seed':>4} {'noise':>6} {'knee':>6} {'chosen':>7} {'CV err':>7} {'best':>7} {'ratio':>6} {'default':>8} "
          f"{'former':>7} {'plain':>7} {'common':>6} {'CV [s]':>6}   (mean relative error over joints, %, vs noise-free torques)")
    for noise in (float(x) for x in args.noise.split(",")):
        for seed in range(args.seeds):
            r = one_run(robot, base, truth, seed, noise, args.duration)
            runs.append(r)
            m = {k: float(np.mean(r[k])) for k in ("chosen", "best", "default", "former", "plain")}
            print(f"{seed:>4} {noise:>6.3f} {r['knee']:>6.3g} {r['cutoff']:>7.3g} {m['chosen']:>7.3f} {m['best']:>7.3f} "
                  f"{m['chosen'] / m['best']:>6.3f} {m['default']:>8.3f} {m['former']:>7.3f} {m['plain']:>7.3f} "
                  f"{_ratio(r, '_common'):>6.3f} "
                  f"{r['seconds']:>6.1f} {rest_label(r['rest']) if r['rest'] else 'no threshold'}; default's friction "
                  f"{r['friction']}", flush=True)
    print(f"median CV / best-of-grid: {np.median([_ratio(r) for r in runs]):.4f} (each processing on the samples "
          f"it keeps); {np.median([_ratio(r, '_common') for r in runs]):.4f} (every one on the same samples)")
    print(f"median grid mean / best-of-grid: {np.median([r['at_random'] / np.mean(r['best']) for r in runs]):.4f} "
          f"(a cut-off drawn at random, with the rest policy chosen; the best of the grid is the least of its "
          f"noisy errors)")
    chosen = np.median([r["chosen"] for r in runs], axis=0)
    plain = np.median([r["plain"] for r in runs], axis=0)
    print("per joint, median over runs: CV " + " ".join(f"{v:.3f}" for v in chosen))
    print("                          plain " + " ".join(f"{v:.3f}" for v in plain))
    print("                    CV / plain " + " ".join(f"{a / b:.3f}" for a, b in zip(chosen, plain)))
    default = np.median([r["default"] for r in runs], axis=0)
    worst = np.max([r["default"] / r["plain"] for r in runs], axis=0)
    wins = np.sum([r["default"] < r["plain"] for r in runs], axis=0)
    print("                       defaults " + " ".join(f"{v:.3f}" for v in default))
    print("              defaults / plain " + " ".join(f"{a / b:.3f}" for a, b in zip(default, plain)))
    print("     worst run, defaults / plain " + " ".join(f"{v:.3f}" for v in worst))
    print(f"  runs where the defaults beat the plain LS, per joint (of {len(runs)}): " + " ".join(map(str, wins)))
    common = np.median([r["default_common"] / r["plain_common"] for r in runs], axis=0)
    print("  on the same samples, defaults / plain (median) " + " ".join(f"{v:.3f}" for v in common))


def _ratio(run: dict, which: str = "") -> float:
    """Mean error over joints of the chosen processing / that of the grid's best."""
    return float(np.mean(run["chosen" + which]) / np.mean(run["best" + which]))


if __name__ == "__main__":
    main()
