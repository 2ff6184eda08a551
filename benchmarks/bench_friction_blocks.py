"""Friction forms block by block: time and agreement of a tanh fit, and of a fit whose friction form is
chosen, read in blocks against the same fit in one block (the whole-signal fit), on an RX90 twin whose
Coulomb friction is FSj·tanh(q̇/0.05) (tests/test_friction_forms.py's friction_twin, 1 % noise).

Rows: the fit in one block (reference), then in blocks; CPU seconds, the ratio to the reference, the
largest relative difference of the estimates (parameters near zero against 1e-6 of the largest), and
whether the velocity scales (and the forms chosen) are the same.

    PYTHONPATH=. python benchmarks/bench_friction_blocks.py [--duration 60] [--block 2000] [--seed 0]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

import numpy as np  # noqa: E402

import identify  # noqa: E402
import rx90sym  # noqa: E402

from test_friction_forms import friction_twin  # noqa: E402


def timed(*args, **kwargs):
    start = time.process_time()
    return identify.fit(*args, **kwargs), time.process_time() - start


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=60.0, help="twin run length [s] at 100 Hz, default 60")
    ap.add_argument("--block", type=int, default=2000, help="block [samples] of the block-wise fits, default 2000")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    robot = rx90sym.load_robot("rx90")
    rec = friction_twin(robot, "tanh", args.seed, args.duration, 100.0)
    n = rec.n_samples
    identify.fit(robot, [rec], identify.Processing(cutoff=10.0, estimate_delay=False), bootstrap_seed=None)  # warm
    cases = [("tanh given", identify.Processing(friction="tanh", cutoff=10.0, estimate_delay=False), n),
             ("form chosen", identify.Processing(), n - 1)]   # n - 1: the block path's own choice, in one block
    print(f"RX90 tanh twin, {args.duration:g} s at 100 Hz ({n} samples), seed {args.seed}; CPU seconds\n")
    head = f"{'fit':<13} {'block':>7} {'blocks':>6} {'CPU [s]':>8} {'ratio':>6} {'max rel diff':>13}  same scales / forms"
    print(head + "\n" + "-" * len(head))
    for label, processing, one in cases:
        ref, t_ref = timed(robot, [rec], processing)
        ref, t_ref = timed(robot, [rec], processing, block=one) if one < n else (ref, t_ref)
        got, t_got = timed(robot, [rec], processing, block=args.block)
        v, r = got.result.values, ref.result.values
        diff = float(np.max(np.abs(v - r) / np.maximum(np.abs(r), 1e-6 * np.max(np.abs(r)))))
        same = (got.model.friction or {}).get("velocity_scale") == (ref.model.friction or {}).get("velocity_scale")
        if ref.choice is not None and "friction" in ref.choice:
            same = same and got.choice["friction"]["chosen"] == ref.choice["friction"]["chosen"]
        for name, f, t, d in ((label, ref, t_ref, "-"), ("", got, t_got, f"{diff:.1e}")):
            blocks = f.passes.blocks if f.passes is not None else 1
            print(f"{name:<13} {f.block or n:>7} {blocks:>6} {t:8.2f} {t / t_ref:6.2f} {d:>13}  "
                  f"{'' if f is ref else same}")


if __name__ == "__main__":
    main()
