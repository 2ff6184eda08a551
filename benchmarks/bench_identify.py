"""Benchmark of the identification solvers at the paper's size (§III-A: r ≈ 63,000 equations,
c = 54 base parameters, 6 joint blocks).

Each timed item is one function ``(problem, repeat) -> Row``; ``BENCHMARKS`` lists them and
:func:`print_table` prints item, time, target, ratio to target, and a reference measured in the
same run with the ratio to it. To add an item, write such a function (use :func:`time_it`) and
append it to ``BENCHMARKS``.

BLAS runs on one thread unless OPENBLAS_NUM_THREADS / OMP_NUM_THREADS are set: on a shared
2-core machine multi-threaded BLAS makes timings erratic.

Usage: python benchmarks/bench_identify.py [--repeat 5] [--rows 63000] [--seed 0]
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before numpy loads BLAS

import argparse  # noqa: E402
import sys  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Callable, Sequence  # noqa: E402

import numpy as np  # noqa: E402

from timing import time_it  # noqa: E402,F401 (re-exported for the other scripts)

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout

from identify.estimation.essential import essential_parameters  # noqa: E402
from identify.estimation.least_squares import weighted_least_squares  # noqa: E402

N_JOINTS = 6
N_PARAMETERS = 54
N_ESSENTIAL = 28  # Table 3: 28 essential parameters out of 54
NOISE_STD = np.array([2.0, 2.0, 1.0, 0.3, 0.2, 0.1])  # N·m per joint


@dataclass(frozen=True)
class Problem:
    """A joint-grouped identification system: W (r, c), Y (r,), joint (r,), names (c,)."""

    W: np.ndarray
    Y: np.ndarray
    joint: np.ndarray
    names: tuple[str, ...]


@dataclass(frozen=True)
class Row:
    """One line of the table; times in seconds."""

    item: str
    seconds: float
    target: float | None = None
    reference: str | None = None
    reference_seconds: float | None = None


def _fmt(v: float | None, spec: str) -> str:
    return "-" if v is None else format(v, spec)


def print_table(rows: Sequence[Row]) -> None:
    """Print item | time | target | time/target | reference | ref. time | time/ref."""
    width = max(len("item"), *(len(r.item) for r in rows))
    ref_width = max(len("reference"), *(len(r.reference or "-") for r in rows))
    head = (f"{'item':<{width}}  {'time (s)':>9}  {'target (s)':>10}  {'/target':>7}  "
            f"{'reference':<{ref_width}}  {'ref (s)':>8}  {'/ref':>6}")
    print(head)
    print("-" * len(head))
    for r in rows:
        to_target = r.seconds / r.target if r.target else None
        to_ref = r.seconds / r.reference_seconds if r.reference_seconds else None
        print(f"{r.item:<{width}}  {r.seconds:9.4f}  {_fmt(r.target, '10.3g')}  {_fmt(to_target, '7.3g')}  "
              f"{r.reference or '-':<{ref_width}}  {_fmt(r.reference_seconds, '8.4f')}  {_fmt(to_ref, '6.3g')}")


def make_problem(seed: int = 0, rows: int = 63_000) -> Problem:
    """Random well-conditioned W (column scales 0.5–2), 6 equal joint blocks, different noise per
    joint, 28 non-zero and 26 zero true parameters (the shape of Table 3)."""
    rng = np.random.default_rng(seed)
    W = rng.standard_normal((rows, N_PARAMETERS)) * rng.uniform(0.5, 2.0, N_PARAMETERS)
    joint = np.minimum(np.arange(rows) * N_JOINTS // rows, N_JOINTS - 1)
    beta = rng.uniform(1.0, 10.0, N_PARAMETERS) * rng.choice([-1.0, 1.0], N_PARAMETERS)
    beta[rng.choice(N_PARAMETERS, N_PARAMETERS - N_ESSENTIAL, replace=False)] = 0.0
    Y = W @ beta + rng.standard_normal(rows) * NOISE_STD[joint]
    return Problem(W, Y, joint, tuple(f"P{j + 1}" for j in range(N_PARAMETERS)))


def bench_wls(problem: Problem, repeat: int) -> Row:
    """WLS with all statistics (weights, σρ, covariance, σ %, cond) vs one bare numpy lstsq."""
    p = problem
    seconds = time_it(lambda: weighted_least_squares(p.W, p.Y, p.joint, p.names), repeat)
    ref = time_it(lambda: np.linalg.lstsq(p.W, p.Y, rcond=None), repeat)
    return Row("WLS + statistics (eqs. 10-15)", seconds, 0.1, "numpy.linalg.lstsq(W, Y)", ref)


def bench_essential(problem: Problem, repeat: int) -> Row:
    """Essential-parameter elimination on the compressed system vs the same elimination
    re-solving the raw weighted W with numpy lstsq at every trial (timed once)."""
    p = problem
    wls = weighted_least_squares(p.W, p.Y, p.joint, p.names)
    seconds = time_it(lambda: essential_parameters(wls), repeat)
    trials = [step.removed for step in essential_parameters(wls).history]
    w = wls.weights[p.joint]
    Ww, Yw = p.W * w[:, None], p.Y * w

    def naive() -> None:
        keep = list(range(len(p.names)))
        for name in trials:
            keep.remove(p.names.index(name))
            np.linalg.lstsq(Ww[:, keep], Yw, rcond=None)

    ref = time_it(naive, 1, warmup=False)  # slow: once
    label = f"essential parameters ({len(trials)} trials)"
    return Row(label, seconds, 1.0, "same trials, lstsq on raw W", ref)


BENCHMARKS: list[Callable[[Problem, int], Row]] = [bench_wls, bench_essential]


def main(argv: Sequence[str] | None = None) -> list[Row]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="timed calls per item (best is kept)")
    parser.add_argument("--rows", type=int, default=63_000, help="equations r")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    problem = make_problem(args.seed, args.rows)
    print(f"r = {problem.W.shape[0]} equations, c = {problem.W.shape[1]} parameters, "
          f"{N_JOINTS} joint blocks; BLAS threads: {os.environ['OPENBLAS_NUM_THREADS']}; "
          f"best of {args.repeat}\n")
    rows = [bench(problem, args.repeat) for bench in BENCHMARKS]
    print_table(rows)
    return rows


if __name__ == "__main__":
    main()
