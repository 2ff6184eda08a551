"""Multi-start through Dask (issue 15): starts per minute with 1 and 2 local workers, and the
identical-results check against the serial run.

RX90, 10 s Fourier trajectory with 3 harmonics, default criterion, seed 0, ``--starts`` starts
(default 4). Each configuration runs the same starts; the cluster start-up is timed apart.

    PYTHONPATH=. python benchmarks/bench_dask.py [--starts 4]
"""
from __future__ import annotations

import argparse
import time

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=int, default=4)
    args = parser.parse_args()

    import excitation
    import rx90sym

    robot = rx90sym.load_robot("rx90")
    bp = rx90sym.base_parameters(robot)
    chi = robot.parameter_vector(rx90sym.default_parameters(robot))

    def run(client):
        t0 = time.perf_counter()
        traj = excitation.optimise(robot, 10.0, 3, seed=0, starts=args.starts, chi_nominal=chi, base=bp,
                                   client=client, progress=False, envelope=None)
        return traj, time.perf_counter() - t0

    serial, t_serial = run(None)
    rows = [("serial (this process)", t_serial, 0.0, serial)]
    for workers in (1, 2):
        t0 = time.perf_counter()
        with excitation.dask_client(workers=workers) as client:
            client.wait_for_workers(workers)
            t_up = time.perf_counter() - t0
            traj, elapsed = run(client)
        rows.append((f"Dask LocalCluster, {workers} worker(s)", elapsed, t_up, traj))
    print(f"{'configuration':32s} {'time s':>7s} {'starts/min':>10s} {'start-up s':>10s}  identical to serial")
    for label, elapsed, t_up, traj in rows:
        same = np.array_equal(traj.coefficients, serial.coefficients) and traj.cond == serial.cond
        print(f"{label:32s} {elapsed:7.1f} {60.0 * args.starts / elapsed:10.2f} {t_up:10.1f}  {same}")
    print(f"ratio 2 workers / 1 worker (starts per minute): {rows[1][1] / rows[2][1]:.2f}")


if __name__ == "__main__":
    main()
