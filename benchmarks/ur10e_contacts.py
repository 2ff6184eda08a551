"""The contact monitor on the real UR10e (issue 30): fit of the 14-harmonic empty run with drive gains,
then the push log and the moving runs.

Data: ../shared/data/ur10e (no licence: read in place, never copied). Fit: the empty run, rows 195-4966
on a 100 Hz grid (benchmarks/ur10e_gains.py), torque offsets on, drive gains = the controller's own
ratio of target torque to target current (joint side), rx90 identify's defaults with a fixed cut-off
(10 Hz) and Coulomb friction. Thresholds: as ``rx90 identify`` stores them without a held-out
file, i.e. on the held-out blocks of the fitted run (identify.monitor.thresholds).

Pushes (the source does not label them; docs/contact-monitor.md): in the push log the arm holds a
pose, so the currents of joints 2 and 3 stay at their holding values except while a person pushes.
A push is a run of samples where |i_j − median(i_j)| > PUSH_CURRENT_A on joint 2 or 3, runs closer
than PUSH_GAP_S merged, runs shorter than PUSH_MIN_S dropped.

Usage: python benchmarks/ur10e_contacts.py [--data DIR]
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import ur10e_gains as g  # noqa: E402

from identify import Processing, fit  # noqa: E402
from identify.io.gains import DriveGains, apply_gains  # noqa: E402
from identify import read_log  # noqa: E402
from identify.io.recordings import RecordingWarning  # noqa: E402
from identify.monitor.log import monitor_log  # noqa: E402
from identify.monitor.thresholds import with_contact_thresholds  # noqa: E402

DATA = g.DATA
PUSH = "collision/ur-20_01_22-push_pose_1.csv"
PUSH_CURRENT_A = 1.0      # A above the holding current on joint 2 or 3
PUSH_GAP_S = 0.3          # runs closer than this are one push
PUSH_MIN_S = 0.1          # shorter runs are not pushes


def robot():
    return g.ur10e_robot().with_options(offsets=True)


def read(path: Path, rows: tuple[int, int] | None = None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RecordingWarning)
        return read_log(path, robot(), g.COLUMNS, rows=rows, resample=g.RATE)


def ur10e_fit(data: Path = DATA, run: tuple[str, tuple[int, int]] = g.EMPTY):
    """(fit with the controller's gains, the fitted run with currents, gains)."""
    empty = read(data / run[0], run[1])
    gains = DriveGains(g.controller_constants(empty), side="joint", source="controller constants")
    F = fit(robot(), [apply_gains(empty, gains, robot())],
            Processing(cutoff=10.0, friction="coulomb", rest="zero-coulomb"), gains=gains)
    F, why = with_contact_thresholds(F, [empty])
    if why:
        raise RuntimeError(f"UR10e fit: no contact thresholds ({why})")
    return F, empty, gains


def label_pushes(rec) -> list[tuple[float, float]]:
    """(start, end) [s from the first sample] of each push, from the currents of joints 2 and 3."""
    i = np.asarray(rec.current, dtype=float)[:, 1:3]
    t = rec.t - rec.t[0]
    on = (np.abs(i - np.median(i, axis=0)) > PUSH_CURRENT_A).any(axis=1)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], on.astype(int), [0]])))
    runs = [[t[a], t[b - 1]] for a, b in zip(edges[::2], edges[1::2])]
    merged: list[list[float]] = []
    for s, e in runs:
        if merged and s - merged[-1][1] < PUSH_GAP_S:
            merged[-1][1] = e
        else:
            merged.append([s, e])
    return [(s, e) for s, e in merged if e - s >= PUSH_MIN_S]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA)
    args = ap.parse_args()
    start = time.perf_counter()
    F, empty, gains = ur10e_fit(args.data)
    print(f"fit in {time.perf_counter() - start:.1f} s; gains {np.round(gains.gains, 2)} N·m/A")
    print("thresholds [N·m]:", np.round(F.contact_thresholds, 2))
    push = read(args.data / PUSH)
    pushes = label_pushes(push)
    res = monitor_log(F, push, keep=True)
    print(f"push log: {len(pushes)} pushes labelled from the currents:",
          ", ".join(f"{s:.2f}-{e:.2f}" for s, e in pushes))
    print(res.table())
    print("detectable moving [N·m]:", np.round(res.detectable_moving_nm, 1))
    print("detectable at rest [N·m]:", np.round(res.detectable_rest_nm, 1))
    for s, e in pushes:
        hit = [x for x in res.events if x.start_s <= e and x.end_s >= s]
        print(f"push {s:6.2f}-{e:6.2f} s: " + (f"event {hit[0].start_s:.2f}-{hit[0].end_s:.2f} s joints {hit[0].joints}"
                                              if hit else "MISSED"))
    runs = [(F, g.EMPTY, "empty fit"), (F, g.LOADED, "empty fit: the 2.805 kg payload is an external load to it"),
            (F, ("ur-20_01_17-p4.csv", None), "empty fit; the arm at rest throughout")]
    F_loaded = ur10e_fit(args.data, g.LOADED)[0]
    runs.append((F_loaded, g.LOADED, "fit of the loaded run itself (the payload in the model)"))
    for model, (name, rows), what in runs:
        r = monitor_log(model, read(args.data / name, rows))
        print(f"{name} ({what}): {len(r.events)} event(s)" + "".join(
            f"\n  {x.start_s:.2f}-{x.end_s:.2f} s joints {x.joints} peak {np.round(x.peak_nm, 1)}" for x in r.events))


if __name__ == "__main__":
    main()
