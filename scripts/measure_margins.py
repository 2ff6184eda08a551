"""Margins of the twin tests over several seed sets (docs/reproducibility.md).

For seed sets k = 0..K-1 the fixtures of tests/conftest.py are rebuilt with motion seeds 10k..10k+3
(noise seeds likewise) and every quantity a test thresholds is printed, so each threshold can be
set with a margin over seeds instead of from one run. Usage (from the repository root):

    PYTHONPATH=$PWD:tests python scripts/measure_margins.py [K]
"""
from __future__ import annotations

import sys

import numpy as np

import identify
import rx90sym
from identify.payloads.methods import payload
from motions import multisine

TABLE_3 = ["ZZ1R", "FV1", "FS1", "XX2R", "XZ2R", "ZZ2R", "MX2R", "FV2", "FS2", "XX3R", "ZZ3R",
           "MY3R", "IA3", "FV3", "FS3", "MX4", "IA4", "FV4", "FS4", "IA5", "FV5", "FS5", "YZ6",
           "IA6", "FV6", "FS6", "FVM6", "FSM6"]


def one_set(robot, bp, truth, k: int) -> dict[str, float]:
    seeds = [10 * k + s for s in range(4)]
    sim = rx90sym.twin.simulate
    empty = [sim(robot, multisine(robot, s), duration=20.0, noise="realistic", seed=s) for s in seeds]
    wls = identify.fit(robot, empty, identify.Processing(min_velocity=0.1, rest="drop", estimate_delay=False), base=bp).result
    tv = np.array([truth[n] for n in wls.names])
    z = (wls.values - tv) / wls.std
    good = wls.rel_std_pct < 5.0
    ess = identify.essential_parameters(wls)
    raw = identify.fit(robot, empty, identify.Processing(min_velocity=None, estimate_delay=False), base=bp).result
    zr = {n: (v - truth[n]) / s for n, v, s in zip(raw.names, raw.values, raw.std)}
    other = sim(robot, multisine(robot, 42 + 10 * k), duration=20.0, noise="realistic", seed=42 + 10 * k)
    val = identify.validate(robot, wls, other, base=bp)
    out = {"good (>= 28)": good.sum(), "max |z| good (<= 3)": np.abs(z[good]).max(),
           "Table 3 in essential (>= 24)": sum(n in ess.names for n in TABLE_3),
           "sigma_rho (0.5..2)": wls.sigma_rho, "validation max % (< 15)": val.relative_error_pct.max(),
           "no rest mask: max |z_FS| (> 3)": max(abs(zr[f"FS{j}"]) for j in range(1, 7))}
    for name in ("tables_4", "tables_5"):
        loaded = [sim(robot, multisine(robot, s), duration=20.0, payload=name, noise="realistic",
                      seed=100 + s) for s in seeds[:2]]
        ap = rx90sym.load_payload(name)
        ests = [payload(robot, m, empty=empty[:2] if m != 1 else [], loaded=loaded,  # as tests/test_payload.py
                        robot_params=wls if m == 1 else None, a_priori=name, base=bp, min_velocity=0.1)
                for m in (1, 2, 3, 4)]
        for key, limit in (("Mc", 0.01), ("MZc", 0.03), ("XXc", 0.10), ("YYc", 0.10)):
            err = max(abs(e[key] - ap[key]) / ap[key] for e in ests)
            out[f"{name} {key} rel err (< {limit:g})"] = err
        worst = 0.0
        for key in ("XXc", "YYc", "MZc", "Mc"):
            i = ests[0].names.index(key)
            for a in ests:
                for b in ests:
                    if a is not b:
                        worst = max(worst, abs(a.values[i] - b.values[i]) / (2 * np.hypot(a.std[i], b.std[i])))
        out[f"{name} method gap / 2 sigma (<= 1)"] = worst
        e3 = ests[2]
        out[f"{name} min rel sigma XYc,YZc,MYc % (> 20)"] = min(e3.rel_std_pct[e3.names.index(n)] for n in ("XYc", "YZc", "MYc"))
        out[f"{name} rel sigma Mc % (< 1)"] = e3.rel_std_pct[e3.names.index("Mc")]
    return out


def main() -> None:
    K = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    robot = rx90sym.load_robot("rx90")
    bp = rx90sym.base_parameters(robot)
    chi = robot.parameter_vector(rx90sym.twin.default_parameters(robot))
    truth = dict(zip(bp.names, bp.beta(chi)))
    rows = [one_set(robot, bp, truth, k) for k in range(K)]
    print(f"{'quantity (test threshold)':48s} " + " ".join(f"{'set ' + str(k):>8s}" for k in range(K)))
    for key in rows[0]:
        print(f"{key:48s} " + " ".join(f"{r[key]:8.4g}" for r in rows))


if __name__ == "__main__":
    main()
