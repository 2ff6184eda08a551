"""``identify.fit`` from a plain Python process against ``rx90 identify`` on the same recording
(the 50 s, 100 Hz UR10e twin of benchmarks/bench_identify_command.py), target: library / command
≤ 1.3 in every setting.

Whole processes, as a user starts them: ``python SCRIPT`` calling ``identify.fit(robot, [log])``
with the defaults, and ``python -m identify.app.cli identify LOG --robot ur10e`` (start-up and
imports included in both). Three settings:

- plain: no thread variable in the environment (rx90sym.threads.BLAS_THREAD_VARIABLES:
  OPENBLAS_NUM_THREADS, OMP_NUM_THREADS, MKL_NUM_THREADS, ... removed), as a notebook or a script starts;
- OPENBLAS_NUM_THREADS=16 for both (an explicit choice, which both honour);
- busy: as plain, beside ``--busy`` processes each spinning BLAS (one thread, a 300 x 300 matrix
  product in a loop) pinned to one of the last cores.

Wall time, median of ``--repeat`` runs each (library and command alternate, after one untimed run
each: the compiled regressor cached, the file in the page cache), the target's ratio; CPU time
(user + system of the child) and its ratio beside it (on a shared machine the wall times move with
the load, the CPU times much less).

    PYTHONPATH=. python benchmarks/bench_library_vs_command.py [--repeat 3] [--busy 1] [--duration 50]
"""
from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(Path(__file__).resolve().parent)]

from bench_identify_command import write_twin_log  # noqa: E402
from rx90sym.threads import BLAS_THREAD_VARIABLES  # noqa: E402

TARGET = 1.3

LIBRARY = """
import sys
import identify, rx90sym
fit = identify.fit(rx90sym.load_robot("ur10e"), [sys.argv[1]])
print(fit.result.values[:3])
"""

BUSY = """
import os, numpy as np
os.sched_setaffinity(0, {{{core}}})
a = np.random.default_rng(0).random((300, 300))
while True:
    a = a @ a
    a /= np.abs(a).max()
"""


def plain_environment(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES}
    return {**env, "PYTHONPATH": str(ROOT), **extra}


def run(argv: list[str], env: dict[str, str]) -> tuple[float, float]:
    """(wall, CPU) seconds of one run of ``argv`` (CPU: user + system of the child)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(argv, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed:\n{proc.stderr.strip()}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def busy_processes(count: int) -> list[subprocess.Popen]:
    """``count`` processes spinning one-thread BLAS, each pinned to one of the last cores."""
    cores = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else list(range(os.cpu_count() or 1))
    env = {**plain_environment(), "OPENBLAS_NUM_THREADS": "1"}
    return [subprocess.Popen([sys.executable, "-c", BUSY.format(core=core)], env=env)
            for core in cores[-count:]]


def setting(library: list[str], command: list[str], env: dict[str, str], repeat: int) -> dict[str, tuple[float, float]]:
    """Median wall and median CPU [s] of the library and the command, run alternately."""
    run(library, env), run(command, env)
    times: dict[str, list[tuple[float, float]]] = {"library": [], "command": []}
    for _ in range(max(1, repeat)):
        times["library"].append(run(library, env))
        times["command"].append(run(command, env))
    return {k: (statistics.median(w for w, _ in v), statistics.median(c for _, c in v)) for k, v in times.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="timed runs per process and setting (median), default 3")
    ap.add_argument("--busy", type=int, default=1, help="busy processes in the busy setting, default 1")
    ap.add_argument("--duration", type=float, default=50.0, help="twin run length [s], default 50")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        log, script = Path(tmp) / "run.csv", Path(tmp) / "fit_library.py"
        samples = write_twin_log(log, args.duration, args.seed)
        script.write_text(LIBRARY)
        library = [sys.executable, str(script), str(log)]
        command = [sys.executable, "-m", "identify.app.cli", "identify", str(log), "--robot", "ur10e"]
        rows = [("plain (no thread variable)", setting(library, command, plain_environment(), args.repeat)),
                ("OPENBLAS_NUM_THREADS=16", setting(library, command, plain_environment(OPENBLAS_NUM_THREADS="16"),
                                                    args.repeat))]
        busy = busy_processes(args.busy)
        try:
            time.sleep(1.0)
            rows.append((f"beside {args.busy} busy BLAS process{'es' if args.busy > 1 else ''}",
                         setting(library, command, plain_environment(), args.repeat)))
        finally:
            for p in busy:
                p.kill()
                p.wait()
    print(f"UR10e twin, {args.duration:g} s at 100 Hz ({samples} samples, 6 joints), seed {args.seed}; "
          f"{cores} cores (os.cpu_count() {os.cpu_count()}); median of {args.repeat} runs each; "
          f"load average at the start {load:.2f}\n")
    head = (f"{'setting':<30} {'library [s]':>12} {'command [s]':>12} {'library/command':>16} "
            f"{'lib CPU [s]':>12} {'cmd CPU [s]':>12} {'CPU ratio':>10}")
    print(head + "\n" + "-" * len(head))
    worst = 0.0
    for label, t in rows:
        ratio = t["library"][0] / t["command"][0]
        worst = max(worst, ratio)
        print(f"{label:<30} {t['library'][0]:12.2f} {t['command'][0]:12.2f} {ratio:16.2f} {t['library'][1]:12.2f} "
              f"{t['command'][1]:12.2f} {t['library'][1] / t['command'][1]:10.2f}")
    print(f"\ntarget: library/command <= {TARGET:g} in every setting: {'within' if worst <= TARGET else 'ABOVE'} "
          f"(worst {worst:.2f})")


if __name__ == "__main__":
    main()
