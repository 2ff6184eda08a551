"""Time of ``rx90 identify`` with its defaults (the cross-validated processing and friction form)
beside the fit of the same run with a fixed cut-off (``--cutoff``: no choice), on a 50 s, 100 Hz
UR10e twin run (6 joints; tests/motions.py multisine, quantised noise), target 3 s.

Each run is a fresh ``python -m identify.app.cli identify`` (start-up and imports included, as a
user sees it); wall time and CPU time (user + system of the child) are the best of ``--repeat``
runs. CPU time is the figure to compare on a shared machine: wall time grows with the load. The
fixed cut-off is the one the defaults choose on this run (read from the defaults' fit file), so
the two runs differ by the choices only. The commands run with this process's environment: the
``rx90`` command's own BLAS default (one OpenBLAS thread) unless OPENBLAS_NUM_THREADS is set
(e.g. ``OPENBLAS_NUM_THREADS=2``: what a command that leaves OpenBLAS its threads costs).

    PYTHONPATH=. python benchmarks/bench_identify_command.py [--repeat 3] [--duration 50] [--seed 0]
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

import rx90sym  # noqa: E402
from identify.io.recordings import write_recording  # noqa: E402
from rx90sym.twin import simulate  # noqa: E402

from motions import multisine  # noqa: E402

TARGET_S = 3.0


def write_twin_log(path: Path, duration: float = 50.0, seed: int = 0) -> int:
    """The benchmark's recording written to ``path`` (CSV): a UR10e twin run of ``duration`` s at
    100 Hz (tests/motions.py multisine, quantised noise); returns its sample count."""
    robot = rx90sym.load_robot("ur10e")
    rec = simulate(robot, multisine(robot, seed, duration=duration), duration=duration, rate=100.0,
                   noise="quantised", seed=seed)
    write_recording(path, rec, robot)
    return rec.t.size


def run(argv: list[str]) -> tuple[float, float]:
    """(wall, CPU) seconds of one run of ``argv`` (CPU: user + system of the child and its own children)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(argv, capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed:\n{proc.stderr.strip()}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def best(argv: list[str], repeat: int) -> tuple[float, float]:
    """Best wall and best CPU time [s] of ``repeat`` runs, after one untimed run (the compiled
    regressor built and cached, the files in the page cache)."""
    run(argv)
    times = [run(argv) for _ in range(max(1, repeat))]
    return min(w for w, _ in times), min(c for _, c in times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="timed runs per command (best kept), default 3")
    ap.add_argument("--duration", type=float, default=50.0, help="twin run length [s], default 50")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        log, out = Path(tmp) / "run.csv", Path(tmp) / "fit.json"
        samples = write_twin_log(log, args.duration, args.seed)
        identify = [sys.executable, "-m", "identify.app.cli", "identify", str(log), "--robot", "ur10e", "--json", str(out)]
        defaults = best(identify, args.repeat)
        cutoff = json.loads(out.read_text())["cutoff_hz"]
        fixed = best(identify + ["--cutoff", repr(cutoff)], args.repeat)
    print(f"UR10e twin, {args.duration:g} s at 100 Hz ({samples} samples, 6 joints), seed {args.seed}; "
          f"best of {args.repeat} runs each; OPENBLAS_NUM_THREADS {os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}\n")
    head = f"{'rx90 identify':<34} {'wall [s]':>9} {'CPU [s]':>9} {'CPU / fixed':>12} {'CPU / target':>13}"
    print(head + "\n" + "-" * len(head))
    for label, (wall, cpu) in ((f"fixed cut-off (--cutoff {cutoff:.4g})", fixed), ("defaults (cross-validated)", defaults)):
        print(f"{label:<34} {wall:9.3f} {cpu:9.3f} {cpu / fixed[1]:12.2f} {cpu / TARGET_S:13.2f}")
    verdict = "within" if defaults[1] <= TARGET_S else "ABOVE"
    print(f"\ntarget: defaults <= {TARGET_S:g} s: {verdict} (CPU {defaults[1]:.3f} s, wall {defaults[0]:.3f} s)")


if __name__ == "__main__":
    main()
