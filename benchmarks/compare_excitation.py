"""Optimised vs random feasible excitation, judged by identification on the twin (issue 7).

Both 20 s Fourier trajectories (5 harmonics) respect the same limits; each is run on the twin
(realistic noise, same seed) and identified by WLS. Prints cond and the median relative
standard deviation (eq. 15) per parameter group.
"""
from __future__ import annotations

import numpy as np

def group_of(name: str) -> str:
    if name in ("FVM6", "FSM6"):
        return "coupling FVM6/FSM6"
    if name.startswith(("FV", "FS")):
        return "friction FV/FS"
    link = int(name.rstrip("R")[-1])
    return "inertial, links 1-3" if link <= 3 else "inertial, wrist 4-6"


def compare(seed: int = 0, duration: float = 20.0, harmonics: int = 5, starts: int = 1,
            criterion: str = "cond") -> dict:
    import excitation
    import identify
    import rx90sym

    robot = rx90sym.load_robot("rx90")
    bp = rx90sym.base_parameters(robot)
    chi = robot.parameter_vector(rx90sym.default_parameters(robot))
    opt = excitation.optimise(robot, duration, harmonics, seed=seed, chi_nominal=chi, base=bp,
                              starts=starts, criterion=criterion, progress=False, envelope=None)
    rnd = excitation.random_trajectory(robot, duration, harmonics, seed=seed + 1, chi_nominal=chi, base=bp)
    out = {}
    for label, traj in (("optimised", opt), ("random", rnd)):
        rec = rx90sym.twin.simulate(robot, traj, noise="realistic", seed=seed)
        res = identify.fit(robot, [rec], identify.Processing(min_velocity=0.1, rest="drop", estimate_delay=False), base=bp).result
        groups: dict[str, list[float]] = {}
        for n, r in zip(res.names, res.rel_std_pct):
            groups.setdefault(group_of(n), []).append(r)
        out[label] = {"cond": traj.cond, "result": res,
                      "median_rel_std": {g: float(np.median(v)) for g, v in groups.items()}}
    return out


def main() -> None:
    out = compare()
    print(f"{'':24s} {'optimised':>10s} {'random':>10s}  ratio")
    print(f"{'cond (250 Hz)':24s} {out['optimised']['cond']:10.2f} {out['random']['cond']:10.2f}  "
          f"{out['optimised']['cond'] / out['random']['cond']:.2f}")
    for g in out["optimised"]["median_rel_std"]:
        a, b = out["optimised"]["median_rel_std"][g], out["random"]["median_rel_std"][g]
        print(f"median σr % {g:13s} {a:10.3f} {b:10.3f}  {a / b:.2f}")


if __name__ == "__main__":
    main()
