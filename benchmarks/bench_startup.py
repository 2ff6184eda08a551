"""Start-up time of the ``rx90`` command: ``--version`` and ``COMMAND --help`` per command, beside
``python -c pass`` measured in the same run (median of ``--repeat`` runs each; target: under
0.5 s on a 2-core machine).

    PYTHONPATH=. python benchmarks/bench_startup.py [--repeat 5]
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

from identify.app import cli

TARGET_S = 0.5


def seconds(argv: list[str], repeat: int) -> float:
    """Median wall time [s] of ``argv`` run ``repeat`` times (a fresh interpreter each)."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        proc = subprocess.run(argv, capture_output=True, text=True)
        times.append(time.perf_counter() - start)
        if proc.returncode != 0:
            raise SystemExit(f"{' '.join(argv)} failed: {proc.stderr.strip()}")
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="runs per command (median), default 5")
    args = ap.parse_args()
    rx90 = [sys.executable, "-m", "identify.app.cli"]
    reference = seconds([sys.executable, "-c", "pass"], args.repeat)
    commands = sorted(cli.build_parser()._subparsers._group_actions[0].choices)
    rows = [("--version", seconds(rx90 + ["--version"], args.repeat))]
    rows += [(f"{c} --help", seconds(rx90 + [c, "--help"], args.repeat)) for c in commands]
    print(f"python -c pass: {reference:.3f} s (median of {args.repeat})")
    print(f"{'rx90 ...':<20} {'time [s]':>9} {'minus python':>13} {'ratio':>7}")
    for label, t in rows:
        print(f"{label:<20} {t:9.3f} {t - reference:13.3f} {t / reference:7.1f}")
    worst = max(t for _, t in rows)
    print(f"slowest: {worst:.3f} s ({'within' if worst < TARGET_S else 'ABOVE'} the {TARGET_S:g} s target)")


if __name__ == "__main__":
    main()
