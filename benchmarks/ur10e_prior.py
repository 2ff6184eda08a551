"""UR10e: believable bodies from the published prior (issue 18, item 2).

Data: ../shared/data/ur10e (no licence: read in place, never copied), read by the loader of
benchmarks/ur10e_gains.py (uniform 100 Hz grid); currents -> torques with the gains published
with the data (README: 10.0, 10.70, 8.46, 9.00, 9.48, 10.12 N m/A), as benchmarks/ur10e_heldout.py.

Fit on rows 195..2566 of the 14-harmonic empty run (~24 s) with the defaults of ``rx90 identify``;
predict rows 2567..5375 (motion, then 4.4 s at rest). Three fits of the same system:

- WLS (the reference);
- consistent, no prior (stage 1 alone: the physical chi of least residual; its split of what the
  data cannot see is arbitrary);
- consistent with the UR10e's [nominal] table as the prior (identify.estimation.consistency.prior).

Printed: per link mass, CoG and principal inertias at the CoG beside the prior (UR's published
mass and CoG, derived inertias) for both consistent fits; whole-arm mass; whether each CoG lies in
its link's bounding ellipsoid; held-out RMS per joint (all samples, while moving) and its ratio to
WLS's.

Usage: PYTHONPATH=. python benchmarks/ur10e_prior.py [--data DIR]   (~1 min)
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import rx90sym
from identify import fit
from identify.estimation.consistency.prior import PhysicalPrior
from identify.estimation.consistency.prior_fit import unseen_distance
from rx90sym.rigid_body import RigidBody
from ur10e_heldout import SOURCE_GAINS, data_folder, gains_bench, torques   # this folder (the script's own)

DATA = gains_bench.DATA
EMPTY = gains_bench.EMPTY
FIT_ROWS, VAL_ROWS = (195, 2566), (2567, 5375)
FIELDS = ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")


def body(values: dict, j: int) -> RigidBody:
    return RigidBody.from_vector(np.array([values[f"{p}{j}"] for p in FIELDS]))


def figures(data: Path = DATA) -> dict:
    robot = gains_bench.ur10e_robot()
    fit_rec, val_rec = (torques(data / EMPTY[0], rows, robot) for rows in (FIT_ROWS, VAL_ROWS))
    wls = fit(robot, [fit_rec])   # the defaults of rx90 identify
    prior = PhysicalPrior(rx90sym.nominal_parameters(robot), "UR10e [nominal] (rx90sym/robots/ur10e.toml)")
    common = dict(method="consistent", base=wls.base, observation=wls.observation)
    start = time.perf_counter()
    fits = {"WLS": wls, "consistent, no prior": fit(robot, [fit_rec], **common),
            "consistent, prior": fit(robot, [fit_rec], physical_prior=prior, **common)}
    out = {"robot": robot, "prior": prior, "gains": SOURCE_GAINS, "time_s": time.perf_counter() - start, "fits": {}}
    for name, f in fits.items():
        standard = getattr(f.result, "standard", None)
        out["fits"][name] = {"validation": f.predict(val_rec), "cost": wls.result.system.rss(f.result.values),
                             "chi": None if standard is None else robot.parameter_vector(standard)}
    K = wls.base.K
    out["unseen"] = {name: unseen_distance(K, robot.parameter_names, prior, out["fits"][name]["chi"])
                     for name in ("consistent, no prior", "consistent, prior")}
    return out


def moving_rms(val) -> np.ndarray:
    err = val.measured - val.predicted
    return np.array([np.sqrt(np.mean(err[val.moving[:, j], j] ** 2)) for j in range(err.shape[1])])


def body_rows(values: dict, prior: PhysicalPrior, n: int) -> list[str]:
    lines = [f"  {'link':<5}{'mass kg':>9}{'prior':>8}{'ratio':>7}   {'CoG m (frame j)':<27}{'prior CoG':<27}"
             f"{'in ellipsoid':<13}principal inertias at CoG kg m^2 (prior)"]
    for j in range(1, n + 1):
        b, p = body(values, j), prior.body(str(j))
        c, I = b.com_inertia()
        cp_, Ip = p.com_inertia()
        inside = prior.ellipsoid(str(j)).contains(c)
        lines.append(f"  {j:<5}{b.m:9.3f}{p.m:8.3f}{b.m / p.m:7.2f}   {_v(c):<27}{_v(cp_):<27}{str(inside):<13}"
                     f"{_v(np.linalg.eigvalsh(I), '.3g')} ({_v(np.linalg.eigvalsh(Ip), '.3g')})")
    return lines


def _v(x, fmt: str = "+.3f") -> str:
    return "[" + " ".join(f"{v:{fmt}}" for v in x) + "]"


def main(argv: list[str] | None = None) -> int:
    data = data_folder(argv, __doc__)
    if data is None:
        return 2
    start = time.perf_counter()
    f = figures(data)
    robot, prior = f["robot"], f["prior"]
    print(f"Fit rows {FIT_ROWS[0]}..{FIT_ROWS[1]}, predict rows {VAL_ROWS[0]}..{VAL_ROWS[1]} of {EMPTY[0]}; "
          f"gains (README) " + " ".join(f"{k:.4g}" for k in f["gains"]))
    print(f"prior: {prior.source}; the two consistent fits {f['time_s']:.1f} s")
    maker = sum(prior.values[f"M{j}"] for j in range(1, 7))
    for name in ("consistent, no prior", "consistent, prior"):
        values = dict(zip(robot.parameter_names, f["fits"][name]["chi"]))
        total = sum(values[f"M{j}"] for j in range(1, 7))
        print(f"\n{name}: whole arm {total:.2f} kg (UR: {maker:.3f} kg, {100 * (total / maker - 1):+.1f} %); "
              f"unseen directions {100 * f['unseen'][name]:.1f} % from the prior's")
        print("\n".join(body_rows(values, prior, robot.n)))
    ref = f["fits"]["WLS"]
    print("\nheld-out RMS per joint [N m] and ratio to WLS")
    for name, fit in f["fits"].items():
        val = fit["validation"]
        rms_all, rms_mov = val.rms_error, moving_rms(val)
        print(f"  {name:<22} all    " + " ".join(f"{v:7.3f}" for v in rms_all)
              + "   ratio max " + f"{np.max(rms_all / ref['validation'].rms_error):.4f}")
        print(f"  {'':<22} moving " + " ".join(f"{v:7.3f}" for v in rms_mov)
              + "   ratio max " + f"{np.max(rms_mov / moving_rms(ref['validation'])):.4f}")
        print(f"  {'':<22} weighted RSS of the fit {fit['cost']:.6g}")
    print(f"elapsed {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
