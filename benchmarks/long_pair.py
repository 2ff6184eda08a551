"""A 20-minute UR10e pair of 24 segments: rx90 gains and rx90 payload --method 4 block by block, their
peak resident memory and their figures against the 50 s pair (issue 38).

Made in a temporary directory (never in the repository; ../shared/data/ur10e has no licence): each
raw log of the shared pair, the 14-harmonic empty run (lines 195..4966) and the loaded run with
2.805 kg (lines 308..5071), the lines benchmarks/ur10e_gains.py reads, its rows repeated COPIES
times with each copy's clock shifted by the log's span + 1 s, converted at 500 Hz by ``rx90 convert``
(the 1 s gaps split it: one segment per copy). The same conversion of one copy is the 50 s pair.
On each pair, each command a process of its own under ``/usr/bin/time -v`` (its peak resident set):

    rx90 gains --robot ur10e --empty E.csv --loaded L.csv --mass 2.805 --mass-std 0.005 --json G.json
    rx90 payload --robot ur10e --method 4 --empty E.csv --loaded L.csv --gains G.json --json P.json

Printed: per pair and command the peak memory [GB] and wall time [s]; the gains and the payload
mass of the long pair beside the 50 s pair's and their relative differences (targets: under 1.5 GB,
gains within 0.5 %, mass within 1 %).

Usage: PYTHONPATH=. python benchmarks/long_pair.py [--data DIR] [--copies 24] [--keep DIR]
"""
from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "ur10e"
EMPTY = ("ur-20_02_19_14harm50sec.csv", (195, 4966))
LOADED = ("ur-20_02_19_14harm50secLoad.csv", (308, 5071))
COLUMNS = "t,q1..q6,qd1..qd6,i1..i6,x:i_target1..x:i_target6,x:tau_target1..x:tau_target6"
MASS, MASS_STD = "2.805", "0.005"
RATE = "500"


def repeated(src: Path, lines: tuple[int, int], copies: int, out: Path) -> Path:
    """Lines first..last of a raw log written ``copies`` times, copy k's clock shifted by k (span + 1 s)."""
    rows = src.read_text().splitlines()[lines[0] - 1:lines[1]]
    t = np.array([float(r.split(",", 1)[0]) for r in rows])
    shift = t[-1] - t[0] + 1.0
    with open(out, "w") as fh:
        for k in range(copies):
            for tk, row in zip(t + k * shift, rows):
                fh.write(f"{float(tk)!r},{row.split(',', 1)[1]}\n")
    return out


def rx90(*args: str) -> tuple[dict, str]:
    """One rx90 command in a process of its own under /usr/bin/time -v: ({peak_gb, wall_s}, stdout)."""
    cmd = ["/usr/bin/time", "-v", sys.executable, "-m", "identify.app.cli", *map(str, args)]
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=os.environ)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd[3:])} exited {proc.returncode}:\n{proc.stderr[-3000:]}")
    kb = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", proc.stderr).group(1))
    return {"peak_gb": kb / 1024**2, "wall_s": wall}, proc.stdout


def pair(folder: Path, data: Path, copies: int) -> dict:
    """Make one pair of ``copies`` copies in ``folder`` and run both commands on it."""
    folder.mkdir(parents=True, exist_ok=True)
    files = {}
    for role, (name, lines) in (("empty", EMPTY), ("loaded", LOADED)):
        raw = repeated(data / name, lines, copies, folder / f"{role}_raw.csv")
        files[role] = folder / f"{role}.csv"
        rx90("convert", raw, "--robot", "ur10e", "--columns", COLUMNS, "--no-header", "--resample", RATE,
             "--out", files[role])
        raw.unlink()
    runs = ("--robot", "ur10e", "--empty", files["empty"], "--loaded", files["loaded"])
    out = {"segments": copies}
    out["gains_run"], _ = rx90("gains", *runs, "--mass", MASS, "--mass-std", MASS_STD, "--json", folder / "G.json")
    out["payload_run"], _ = rx90("payload", *runs, "--method", "4", "--gains", folder / "G.json",
                                 "--json", folder / "P.json")
    out["gains"] = np.array(json.loads((folder / "G.json").read_text())["gains"])
    out["mass"] = {p["name"]: p["value"] for p in json.loads((folder / "P.json").read_text())["payload"]}["Mc"]
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA)
    ap.add_argument("--copies", type=int, default=24, help="copies of each log, one segment each (default 24)")
    ap.add_argument("--keep", type=Path, help="make the pairs here and keep them (default: a temporary directory)")
    args = ap.parse_args(argv)
    if not (args.data / EMPTY[0]).exists():
        print(f"no UR10e data in {args.data}", file=sys.stderr)
        return 2
    print(f"cores {os.cpu_count()}, load average {os.getloadavg()[0]:.2f} at the start")
    with tempfile.TemporaryDirectory() as tmp:
        root = args.keep or Path(tmp)
        short = pair(root / "short", args.data, 1)
        long = pair(root / "long", args.data, args.copies)
    print(f"{'pair':<26}{'command':<24}{'peak GB':>9}{'wall s':>9}")
    for name, p in ((f"50 s, 1 segment", short), (f"{args.copies} x 50 s, {args.copies} segments", long)):
        for cmd in ("gains", "payload"):
            run = p[f"{cmd}_run"]
            label = "rx90 gains" if cmd == "gains" else "rx90 payload --method 4"
            print(f"{name:<26}{label:<24}{run['peak_gb']:9.2f}{run['wall_s']:9.1f}")
    print("gains [N·m/A]   " + "".join(f"{'j' + str(j + 1):>9}" for j in range(6)))
    print("  50 s pair     " + "".join(f"{k:9.4f}" for k in short["gains"]))
    print("  long pair     " + "".join(f"{k:9.4f}" for k in long["gains"]))
    print("  difference %  " + "".join(f"{100 * (a / b - 1):9.3f}" for a, b in zip(long["gains"], short["gains"])))
    print(f"payload mass (method 4, each pair's gains): 50 s {short['mass']:.4f} kg, long {long['mass']:.4f} kg, "
          f"difference {100 * (long['mass'] / short['mass'] - 1):+.3f} %")
    print(f"load average {os.getloadavg()[0]:.2f} at the end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
