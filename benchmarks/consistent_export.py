"""Is every consistent fit exportable? Margins and solve times of the consistent fit on twins.

For each robot (the four bundled robot files and three URDF twins generated from them with their
nominal bodies) and each seed: a 4 s, 100 Hz multisine, torques from the robot's inverse dynamics
with its nominal parameters plus 1 % seeded Gaussian noise; the WLS fit (cut-off 10 Hz, no
cross-validation), then the consistent fit with the nominal parameters as prior (what
``rx90 identify --method consistent`` does; the prior's covariance is eq. 13's, not the
bootstrap's). Printed per robot over the seeds: the smallest pseudo-inertia eigenvalue of any link
(computed here with numpy, not with the toolkit's check), the smallest IA/FV/FS, the consistent
solve's time (both stages, the margin retries included; the WLS fit is not timed), how many fits
the margin retry re-solved, and how many URDF / MJCF exports were refused.

Uses only interfaces that predate the margin, so the same script measures a checkout before it:
``PYTHONPATH=OLD python benchmarks/consistent_export.py`` and ``PYTHONPATH=NEW ...``.

Usage: PYTHONPATH=CHECKOUT python benchmarks/consistent_export.py [--seeds 5] [--robots rx90 tx40 ...]
"""
from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before numpy loads BLAS

import argparse  # noqa: E402
import tempfile  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import rx90sym  # noqa: E402
from identify import Processing, fit  # noqa: E402
from identify.estimation.consistency.prior import PhysicalPrior  # noqa: E402
from identify.fitting.consistent_fit import consistent_fit  # noqa: E402
from identify.io.recordings import recording_from_arrays  # noqa: E402
from rx90sym.mjcf_export import mjcf_export  # noqa: E402
from rx90sym.urdf_export import urdf_export  # noqa: E402

ROBOTS = ("rx90", "tx40", "ur10e", "panda", "rx90-urdf", "ur10e-urdf", "panda-urdf")


def load(case: str, folder: Path) -> rx90sym.Robot:
    """A bundled robot, or ``NAME-urdf``: NAME's model and nominal bodies written as a URDF."""
    if not case.endswith("-urdf"):
        return rx90sym.load_robot(case)
    source = rx90sym.load_robot(case.removesuffix("-urdf"))
    path = folder / f"{case}.urdf"
    rx90sym.write_urdf(source, rx90sym.nominal_parameters(source), path)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*no acceleration limits.*")
        return rx90sym.load_robot(path, tip="flange")


def motion(robot: rx90sym.Robot, seed: int, duration: float = 4.0, rate: float = 100.0):
    """Sums of three sines per joint, rest to rest at t = 0, within 60 % of the limits."""
    rng = np.random.default_rng(seed)
    lim = robot.limits
    lo, hi = np.maximum(lim.q_min, -np.pi), np.minimum(lim.q_max, np.pi)
    w = rng.choice(np.arange(1, 9), size=(3, robot.n)) / duration * 2 * np.pi
    phase = rng.uniform(0, 2 * np.pi, (3, robot.n))
    amp = 0.6 * (hi - lo) / 2 * rng.dirichlet(np.ones(3), robot.n).T
    amp *= np.minimum(1.0, np.minimum(0.6 * lim.qd_max / np.sum(amp * w, 0), 0.6 * lim.qdd_max / np.sum(amp * w**2, 0)))
    t = np.arange(0.0, duration, 1.0 / rate)[:, None, None]
    q = (lo + hi) / 2 + np.sum(amp * (np.sin(w * t + phase) - np.sin(phase)), 1)
    qd = np.sum(amp * w * np.cos(w * t + phase), 1)
    qdd = -np.sum(amp * w**2 * np.sin(w * t + phase), 1)
    return t.ravel(), q, qd, qdd


def min_pseudo_inertia_eigenvalue(values: dict, n: int) -> float:
    lam = []
    for j in range(1, n + 1):
        v = {k: values[f"{k}{j}"] for k in ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")}
        I = np.array([[v["XX"], v["XY"], v["XZ"]], [v["XY"], v["YY"], v["YZ"]], [v["XZ"], v["YZ"], v["ZZ"]]])
        J = np.zeros((4, 4))
        J[:3, :3] = 0.5 * np.trace(I) * np.eye(3) - I
        J[:3, 3] = J[3, :3] = (v["MX"], v["MY"], v["MZ"])
        J[3, 3] = v["M"]
        lam.append(np.linalg.eigvalsh(J)[0])
    return float(min(lam))


def one(case: str, seed: int, folder: Path) -> dict:
    robot = load(case, folder)
    nominal = rx90sym.nominal_parameters(robot)
    chi = robot.parameter_vector(nominal)
    t, q, qd, qdd = motion(robot, seed)
    tau = np.array(robot.inverse_dynamics.map(len(t))(q.T, qd.T, qdd.T, np.tile(chi[:, None], (1, len(t))))).T
    tau += np.random.default_rng(seed).normal(size=tau.shape) * 0.01 * tau.std(axis=0)
    rec = recording_from_arrays(t, q, tau, robot)
    wls = fit(robot, [rec], Processing(cutoff=10.0), "wls")
    try:
        res = consistent_fit(robot, wls.result, wls.base, physical_prior=PhysicalPrior(nominal, "nominal"))
    except Exception as exc:  # noqa: BLE001 - a failed fit is a row of the table
        return {"failed": f"{type(exc).__name__}: {exc}"}
    standard = dict(res.standard)
    refused = {}
    for kind, writer in (("urdf", urdf_export), ("mjcf", mjcf_export)):
        try:
            writer(robot, standard, folder / f"out.{kind}")
        except ValueError as exc:
            refused[kind] = str(exc)
    return {"eig": min_pseudo_inertia_eigenvalue(standard, robot.n),
            "terms": min(v for k, v in standard.items() if k.startswith(("IA", "FV", "FS"))),
            "time": res.solution.solve_time, "retried": bool(res.solution.retried), "refused": refused}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS), choices=ROBOTS)
    args = parser.parse_args(argv)
    print(f"consistent fit with the nominal prior, {args.seeds} seeds, 4 s at 100 Hz, 1 % noise "
          f"(code: {Path(rx90sym.__file__).resolve().parents[1]})")
    print(f"{'robot':<12}{'min eig':>11}{'median eig':>12}{'min IA/FV/FS':>14}{'solve s':>9}{'retried':>9}"
          f"{'URDF refused':>14}{'MJCF refused':>14}  failed")
    times, eigs = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for case in args.robots:
            rows = [one(case, seed, Path(tmp)) for seed in range(args.seeds)]
            ok = [r for r in rows if "failed" not in r]
            failed = [r["failed"][:60] for r in rows if "failed" in r]
            if not ok:
                print(f"{case:<12}{'':>83}  {len(failed)}: {failed[0]}")
                continue
            eig = [r["eig"] for r in ok]
            times += [r["time"] for r in ok]
            eigs += eig
            print(f"{case:<12}{min(eig):11.2e}{np.median(eig):12.2e}{min(r['terms'] for r in ok):14.2e}"
                  f"{np.median([r['time'] for r in ok]):9.3f}{sum(r['retried'] for r in ok):9d}"
                  f"{sum('urdf' in r['refused'] for r in ok):14d}{sum('mjcf' in r['refused'] for r in ok):14d}"
                  f"  {len(failed)}" + (f" ({failed[0]})" if failed else ""), flush=True)
    if times:
        print(f"all: min eigenvalue {min(eigs):.2e}, median solve {np.median(times):.3f} s, "
              f"total solve {np.sum(times):.2f} s over {len(times)} fits")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
