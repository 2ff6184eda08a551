"""Long logs: peak memory and time of ``rx90 convert`` and ``rx90 identify`` against the log's length.

A 21 s excitation of a 7-joint arm (the bundled Franka Panda, its [nominal] parameters as the twin's
truth) is simulated once at 1 kHz (the twin's realistic profile: closed servo loop, encoders, ripple,
torque noise) and written as a controller log; longer logs repeat it (the multisine is periodic over 21 s, so the
copies join without a step) while the clock runs on. Logs are written block by block, so this script
itself stays small in memory. Each command runs in its own process under /usr/bin/time (peak
resident memory, wall time). The current whole-log path (``--block`` above the log's length) is
measured on the two shortest logs as the reference.

    python benchmarks/bench_long_logs.py                 # 21 s, 3.5 min, 10.5 min, 60 min
    python benchmarks/bench_long_logs.py --lengths 21,210 --dask   # quick; + Dask throughput
    python benchmarks/bench_long_logs.py --lengths 21 --lossy 210,630   # + lossy host logs (--resample)
    python benchmarks/bench_long_logs.py --lengths 210,630 --reference 0 --choice-reference 2   # the choice's cost

``rx90 identify`` chooses its processing by blocked cross-validation (the default, block by block on
long logs): the last column gives the seconds of that choice and the candidates scored within its
row cap (from the fit file's ``processing_choice``).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
ROBOT = ["--robot", "panda"]
RATE = 1000.0
BASE_S = 21.0
COLUMNS = "t,q1..q7,tau1..tau7"
WHOLE = "100000000"  # a block longer than any log: the whole-log path


def robot():
    import rx90sym

    return rx90sym.load_robot("panda")


def base_motion(seed: int = 0):
    """The 21 s twin recording (Khalil angles) of the Panda at 1 kHz."""
    import warnings

    import rx90sym
    sys.path.insert(0, str(ROOT / "tests"))
    from motions import multisine

    arm = robot()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return rx90sym.twin.simulate(arm, multisine(arm, seed, duration=BASE_S), duration=BASE_S, noise="realistic",
                                     seed=seed, rate=RATE)


def write_log(path: Path, rec, seconds: float) -> int:
    """A log of ``seconds`` s: the base recording repeated, time running on; written copy by copy."""
    import pyarrow as pa
    from pyarrow import csv

    arm = robot()
    q_ctrl = np.asarray(arm.to_controller(rec.q), dtype=float)
    n = rec.n_samples
    total = int(round(seconds * RATE))
    with open(path, "wb") as fh:
        fh.write((COLUMNS.replace("q1..q7", ",".join(f"q{j}" for j in range(1, 8)))
                  .replace("tau1..tau7", ",".join(f"tau{j}" for j in range(1, 8))) + "\n").encode())
        for start in range(0, total, n):
            m = min(n, total - start)
            cols = {"t": (start + np.arange(m)) / RATE}
            cols.update({f"q{j + 1}": q_ctrl[:m, j] for j in range(7)})
            cols.update({f"tau{j + 1}": rec.tau[:m, j] for j in range(7)})
            csv.write_csv(pa.table(cols), fh, csv.WriteOptions(include_header=False))
    return total


#: The lossy log's columns: a host log of the stream (rx90sym.host_log) holds recorded velocities too.
LOSSY_COLUMNS = "t,q1..q7,qd1..qd7,tau1..tau7"


def write_lossy_log(path: Path, rec, seconds: float) -> int:
    """The log of :func:`write_log` as a host PC logs the stream (rx90sym.host_log, one draw per 21 s copy):
    5 % stale rows, bursts of 5-40 lost packets every 2-4 s, ±0.15 period of jitter, and 0.2 s lost in
    the middle of every copy (a new segment every 21 s). Returns the samples of the clean log."""
    import pyarrow as pa
    from pyarrow import csv

    from rx90sym.host_log import HostFaults, host_log

    arm = robot()
    n = rec.n_samples
    total = int(round(seconds * RATE))
    names = ["t"] + [f"{p}{j}" for p in ("q", "qd", "tau") for j in range(1, 8)]
    with open(path, "wb") as fh:
        fh.write((",".join(names) + "\n").encode())
        for k, start in enumerate(range(0, total, n)):
            part = rec.select(slice(0, min(n, total - start)))
            table, _, _ = host_log(part, HostFaults(long_gaps=(BASE_S / 2,)), seed=k)
            table[:, 0] += start / RATE
            table[:, 1:8] = np.asarray(arm.to_controller(table[:, 1:8]), dtype=float)
            csv.write_csv(pa.table({c: table[:, j] for j, c in enumerate(names)}), fh,
                          csv.WriteOptions(include_header=False))
    return total


def measured(cmd: list[str], env: dict) -> tuple[float, float, str]:
    """(wall s, peak resident GB, stdout) of one command in its own process."""
    with tempfile.NamedTemporaryFile("r", suffix=".time") as tf:
        start = time.perf_counter()
        done = subprocess.run(["/usr/bin/time", "-f", "%M", "-o", tf.name, *cmd], env=env, capture_output=True,
                              text=True)
        wall = time.perf_counter() - start
        if done.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed:\n{done.stderr[-2000:]}")
        kb = float(tf.read().strip().splitlines()[-1])
    return wall, kb / 1024**2, done.stdout


def rx90(*args: str) -> list[str]:
    return [str(Path(sys.executable).parent / "rx90"), *args]


def choice_of(path: Path) -> str:
    """'seconds of the choice (candidates scored / in the grid)' from a fit file, '-' without a choice."""
    import json

    choice = json.loads(path.read_text()).get("processing_choice")
    if not choice:
        return "-"
    scored = sum(c["score_pct"] is not None for c in choice["candidates"])
    return f"{choice['seconds']:.1f} ({scored}/{len(choice['candidates'])})"


def run_length(folder: Path, rec, seconds: float, env: dict, reference: bool, lossy: bool = False,
               choice: bool = True, without_choice: bool = False) -> list[tuple]:
    log, out = folder / f"log_{int(seconds)}.csv", folder / f"rec_{int(seconds)}.csv"
    samples = (write_lossy_log if lossy else write_log)(log, rec, seconds)
    columns = ["--columns", LOSSY_COLUMNS, "--resample", str(RATE)] if lossy else ["--columns", COLUMNS]
    rows = []
    # "default": the command as shipped (a log within one block takes the whole-signal path).
    modes = [("default", None, choice)] + ([("default, --no-cross-validate", None, False)] if without_choice else [])
    for path_name, block, choice in modes + ([("whole (reference)", WHOLE, choice)] if reference else []):
        path_name = f"lossy, {path_name}" if lossy else path_name
        extra = [] if block is None else ["--block", block]
        conv = measured(rx90("convert", str(log), *ROBOT, *columns, "--out", str(out), *extra), env)
        fit = folder / "fit.json"
        ident = measured(rx90("identify", str(out), *ROBOT, "--offsets", "--json", str(fit), *extra,
                              *([] if choice else ["--no-cross-validate"])), env)
        rows.append((seconds, samples, path_name, conv[0], conv[1], ident[0], ident[1], log.stat().st_size / 1e6,
                     choice_of(fit)))
    log.unlink()
    out.unlink()
    return rows


def dask_throughput(folder: Path, rec, env: dict) -> None:
    """The fit's passes over a 3.5 min log on a local Dask cluster of 1 and of 2 workers (same result)."""
    import rx90sym  # noqa: F401
    from dask.distributed import Client, LocalCluster

    from identify.fitting.passes import run_passes
    from identify.observation.processing import Processing

    log = folder / "dask_rec.csv"
    rec_long = _long_recording(rec, 10)
    import identify

    identify.write_recording(log, rec_long, robot(), convention="controller")
    arm = robot()
    results = {}
    for workers in (1, 2):
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as c, \
                Client(c) as client:
            start = time.perf_counter()
            fit = run_passes(arm, [log], Processing(estimate_delay=False), block=20_000, client=client)
            results[workers] = (time.perf_counter() - start, fit.result.values)
    serial_start = time.perf_counter()
    serial = run_passes(arm, [log], Processing(estimate_delay=False), block=20_000)
    serial_s = time.perf_counter() - serial_start
    rel = max(float(np.max(np.abs(v / serial.result.values - 1))) for _, v in results.values())
    print(f"\nDask, 3.5 min log, blocks of 20,000 samples: serial {serial_s:.1f} s; 1 worker "
          f"{results[1][0]:.1f} s; 2 workers {results[2][0]:.1f} s (throughput x{results[1][0] / results[2][0]:.2f} "
          f"against one worker); largest relative difference to serial {rel:.1e}")
    log.unlink()


def _long_recording(rec, copies: int):
    import rx90sym

    n = rec.n_samples
    t = np.arange(n * copies) / RATE
    return rx90sym.recording.Recording(t=t, q=np.tile(rec.q, (copies, 1)), tau=np.tile(rec.tau, (copies, 1)),
                                       source="long", robot=rec.robot)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lengths", default="21,210,630,3600", help="log lengths, s")
    ap.add_argument("--reference", type=int, default=2, help="how many of the shortest also on the whole-log path")
    ap.add_argument("--dask", action="store_true", help="also the Dask throughput (1 vs 2 workers)")
    ap.add_argument("--lossy", default="", help="lengths (s) of lossy host logs too: stale rows, lost packets, "
                                                "a segment per 21 s; e.g. 210,630")
    ap.add_argument("--lossy-reference", type=int, default=1,
                    help="how many of the shortest lossy logs also on the whole-log path")
    ap.add_argument("--folder", help="where the logs go (default: a temporary folder)")
    ap.add_argument("--no-choice", action="store_true",
                    help="identify with --no-cross-validate (the position-spectrum cut-off, no processing choice)")
    ap.add_argument("--choice-reference", type=int, default=0,
                    help="how many of the shortest logs also with --no-cross-validate (the cost of the choice)")
    args = ap.parse_args()
    # One BLAS thread: on a shared 2-core machine OpenBLAS's spinning threads make the small QRs 40x slower.
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
               OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    rec = base_motion()
    lengths = [float(x) for x in args.lengths.split(",")]
    with tempfile.TemporaryDirectory(dir=args.folder) as tmp:
        folder = Path(tmp)
        rows = []
        for k, seconds in enumerate(lengths):
            rows += run_length(folder, rec, seconds, env, k < args.reference, choice=not args.no_choice,
                               without_choice=k < args.choice_reference)
            print(f"  done {seconds:g} s", file=sys.stderr, flush=True)
        for k, seconds in enumerate(float(x) for x in args.lossy.split(",") if x):
            rows += run_length(folder, rec, seconds, env, k < args.lossy_reference, lossy=True,
                               choice=not args.no_choice)
            print(f"  done lossy {seconds:g} s", file=sys.stderr, flush=True)
        print("| log | samples | CSV MB | path | convert s | convert GB | identify s | identify GB | choice s (scored) |")
        print("|---|---|---|---|---|---|---|---|---|")
        for seconds, samples, path_name, cs, cg, is_, ig, mb, ch in rows:
            label = f"{seconds / 60:g} min" if seconds >= 60 else f"{seconds:g} s"
            print(f"| {label} | {samples:,} | {mb:.0f} | {path_name} | {cs:.1f} | {cg:.2f} | {is_:.1f} | {ig:.2f} "
                  f"| {ch} |")
        off = {r[0]: r for r in rows if r[2] == "default, --no-cross-validate"}
        for r in rows:
            if r[2] == "default" and r[0] in off:
                print(f"\n{r[0] / 60:g} min: identify with the choice / without: time x{r[5] / off[r[0]][5]:.2f}, "
                      f"peak memory x{r[6] / off[r[0]][6]:.2f}")
        streamed = {r[0]: r for r in rows if r[2] == "default"}
        if 630.0 in streamed and 3600.0 in streamed:
            a, b = streamed[630.0], streamed[3600.0]
            print(f"\n60 min / 10.5 min time: convert x{b[3] / a[3]:.2f}, identify x{b[5] / a[5]:.2f} "
                  f"(length x{3600 / 630:.2f}); largest peak memory {max(max(r[4], r[6]) for r in streamed.values()):.2f} GB")
        lossy = [r for r in rows if r[2] == "lossy, default"]
        if lossy:
            print("\nlossy logs, peak memory against length: " + "; ".join(
                f"{r[0] / 60:g} min {max(r[4], r[6]):.2f} GB" for r in lossy))
        if args.dask:
            dask_throughput(folder, rec, env)


if __name__ == "__main__":
    main()
