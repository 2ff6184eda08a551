"""Payload excitation (issue 15): predicted sigma of Mc, MZc, XXc, YYc against duration.

Short motions optimised for the ten payload parameters (10 via points, criterion "sigma" on Wc,
payload of Table 4 for the reference magnitudes and torque limits) against the 20 s robot
trajectory (default criterion). Noise: 1 % of each joint's torque limit, samples counted at
250 Hz (excitation.payload_design). Method 3: the motion run empty and loaded; method 4: the
20 s robot trajectory run empty, the motion run loaded.

    PYTHONPATH=. python benchmarks/compare_payload.py [--durations 5,10,15] [--starts 1] [--twin]

--twin: instead, identify the payload of Table 4 on the twin (realistic noise, seeds 1 and 2) by
methods 3 and 4 from the 20 s robot trajectory and the 10 s payload motion (identify.payloads.methods).
"""
from __future__ import annotations

import argparse
import sys
import time

SHOWN = ("Mc", "MZc", "XXc", "YYc")


def compare(durations=(5.0, 10.0, 15.0), starts: int = 1, via_points: int = 10, stream=sys.stderr) -> list:
    import excitation
    import rx90sym
    from excitation.api import default_noise, optimise_payload
    from excitation.payload_design import payload_sigma

    robot = rx90sym.load_robot("rx90")
    bp = rx90sym.base_parameters(robot)
    chi = robot.parameter_vector(rx90sym.default_parameters(robot))
    noise = default_noise(robot.limits)
    robot_traj = excitation.optimise(robot, 20.0, 5, seed=0, chi_nominal=chi, base=bp, starts=starts,
                                     progress=False, envelope=None)
    rows = [("robot 20 s", 20.0, 0.0, payload_sigma(robot, bp.regressor, robot_traj, noise, robot_traj))]
    for duration in durations:
        t0 = time.perf_counter()
        traj = optimise_payload(robot, duration, via_points, seed=0, chi_nominal=chi, base=bp,
                                starts=starts, progress=False)
        rows.append((f"payload {duration:g} s", duration, time.perf_counter() - t0,
                     payload_sigma(robot, bp.regressor, traj, noise, robot_traj)))
        print(rows[-1][0], f"{rows[-1][2]:.1f} s", file=stream, flush=True)
    return rows


def table(rows: list) -> str:
    head = " ".join(f"{m[-1]}:{n:>5s}" for m in ("method_3", "method_4") for n in SHOWN)
    lines = [f"{'motion':14s} {'s/start':>7s} {head}"]
    for label, _, seconds, sigma in rows:
        cells = " ".join(f"{sigma[m][n]:7.2g}" for m in ("method_3", "method_4") for n in SHOWN)
        lines.append(f"{label:14s} {seconds:7.1f} {cells}")
    return "\n".join(lines)


def twin_check(starts: int = 1) -> None:
    """Payload identified on the twin from the 20 s robot and the 10 s payload motion."""
    import excitation
    import rx90sym
    from excitation.api import optimise_payload
    from identify.payloads.methods import payload

    robot = rx90sym.load_robot("rx90")
    bp = rx90sym.base_parameters(robot)
    chi = robot.parameter_vector(rx90sym.default_parameters(robot))
    trajs = {"robot 20 s": excitation.optimise(robot, 20.0, 5, seed=0, chi_nominal=chi, base=bp,
                                               starts=starts, progress=False, envelope=None),
             "payload 10 s": optimise_payload(robot, 10.0, 10, seed=0, chi_nominal=chi, base=bp,
                                              starts=starts, progress=False)}
    print(f"{'motion':13s} seed method " + " ".join(f"{n + ' ± sigma':>18s}" for n in SHOWN))
    for label, traj in trajs.items():
        for seed in (1, 2):
            empty = rx90sym.twin.simulate(robot, traj, noise="realistic", seed=seed)
            loaded = rx90sym.twin.simulate(robot, traj, payload="tables_4", noise="realistic", seed=seed + 10)
            for method in (3, 4):
                r = payload(robot, method, empty=[empty], loaded=[loaded])
                d = dict(zip(r.names, zip(r.values, r.std)))
                print(f"{label:13s} {seed:4d} {method:6d} "
                      + " ".join(f"{d[n][0]:9.4g} ± {d[n][1]:6.2g}" for n in SHOWN), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--durations", default="5,10,15")
    parser.add_argument("--starts", type=int, default=1)
    parser.add_argument("--twin", action="store_true")
    args = parser.parse_args()
    if args.twin:
        twin_check(args.starts)
        return
    rows = compare(tuple(float(d) for d in args.durations.split(",")), args.starts)
    print("predicted sigma [kg, kg m, kg m^2] (method 3 | method 4)")
    print(table(rows))


if __name__ == "__main__":
    main()
