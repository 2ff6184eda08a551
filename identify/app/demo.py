"""The end-to-end job on the embedded RX90 (``rx90 demo`` / ``make demo``).

Optimise an excitation trajectory, simulate the twin empty and with the payloads of Tables 4-5,
identify (WLS, essential, consistent) and validate, identify both payloads by the four methods,
identify the real TX40 data, and write one HTML report.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

import numpy as np


def _say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def group_medians(res: Any, truth: dict[str, float]) -> dict[str, float]:
    """Median relative σ [%] of each parameter group (σ over max(|truth|, 0.1·group max), as the
    excitation benchmark judges it)."""
    from excitation.objective import GROUPS, parameter_group

    out = {}
    for group in GROUPS:
        names = [n for n in res.names if parameter_group(n) == group]
        if not names:
            continue
        scale = 0.1 * max(abs(truth[n]) for n in names)
        std = dict(zip(res.names, res.std))
        out[group] = float(np.median([100 * std[n] / max(abs(truth[n]), scale) for n in names]))
    return out


#: Each joint's samples below this speed [rad/s] are left out: the twin has Stribeck friction
#: there, which the model (eq. 5) does not contain.
REST_BELOW = 0.1


def run_demo(out: str | Path = "demo-output", quick: bool = False) -> int:
    """Run the whole mission; returns 0. ``quick`` shortens motions and the optimisation."""
    import rx90sym

    from identify import predict
    from .report.demo_page import demo_page
    from .report.page import write_page

    t_start = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    robot = rx90sym.load_robot("rx90")
    bp = rx90sym.base_parameters(robot)
    chi = robot.parameter_vector(rx90sym.twin.default_parameters(robot))
    truth = dict(zip(bp.names, bp.beta(chi)))
    _say(f"[1/6] model: {robot.name} ({robot.source}; {robot.n} joints), {len(robot.parameter_names)} "
         f"standard, {bp.nb} base parameters")
    traj, other = _excitation(robot, bp, chi, 10.0 if quick else 20.0, out)
    recs = _twin_runs(robot, traj, other, out)
    fits = _robot_fits(robot, bp, recs, truth)
    payloads = _payloads(robot, bp, recs, fits["res"])
    tx = _tx40()
    groups = fits["groups"]
    excitation_text = (f"criterion {traj.criterion}: median relative σ per group, optimised / random "
                       f"feasible trajectory of the same duration (measured on the twin): "
                       + "; ".join(f"{g}: {groups[0][g]:.3g} % / {groups[1][g]:.3g} %" for g in groups[0])
                       + f". cond(W) at 250 Hz = {traj.cond:.2f} (random: {other.cond:.1f}; paper: 58 with "
                       f"18 hand-made motions); cond is not the criterion.")
    res = fits["res"]
    page = demo_page(robot, res, truth, fits["ess"], fits["con"], fits["val"],
                     predict(robot, res, recs["empty"], base=bp), recs["empty"], payloads, tx, excitation_text)
    report = write_page(out / "report.html", page)
    print(f"\nReport: {report.resolve()}")
    _summary(traj, other, fits, payloads)
    print(f"Done in {time.perf_counter() - t_start:.0f} s; files in {out.resolve()}")
    return 0


def _excitation(robot: Any, bp: Any, chi: np.ndarray, duration: float, out: Path) -> tuple[Any, Any]:
    """The optimised trajectory (saved) and a random feasible one of the same duration [s]."""
    import excitation

    _say(f"[2/6] optimising a {duration:g} s excitation trajectory (IPOPT, exact derivatives)...")
    # The demo's motion runs on the simulated twin only: no envelope (excitation.optimise says what
    # that leaves unchecked); rx90 excite plans for a real arm with the envelope on.
    traj = excitation.optimise(robot, duration=duration, harmonics=5, seed=0, starts=2,
                               chi_nominal=chi, base=bp, envelope=None, progress=sys.stderr)
    traj.save(out / "trajectory.csv")
    traj.save_json(out / "trajectory.json")
    return traj, excitation.random_trajectory(robot, duration, 5, seed=7, chi_nominal=chi, base=bp)


def _twin_runs(robot: Any, traj: Any, other: Any, out: Path) -> dict[str, Any]:
    """The twin empty on both motions and with the payloads of Tables 4 and 5 (written as CSV)."""
    import rx90sym

    from identify import write_recording

    _say("[3/6] simulating the twin: empty, validation motion, payloads of Tables 4 and 5...")
    sim = rx90sym.twin.simulate
    recs = {
        "empty": sim(robot, traj, noise="realistic", seed=1),
        "validation": sim(robot, other, noise="realistic", seed=4),
        "tables_4": sim(robot, traj, payload="tables_4", noise="realistic", seed=2),
        "tables_5": sim(robot, traj, payload="tables_5", noise="realistic", seed=3),
    }
    for name, rec in recs.items():
        write_recording(out / f"{name}.csv", rec, robot, convention="controller")
    return recs


def _robot_fits(robot: Any, bp: Any, recs: dict[str, Any], truth: dict[str, float]) -> dict[str, Any]:
    """WLS on the optimised and on the random motion, essential parameters, consistent LS,
    validation, and how the WLS estimates compare with the truth."""
    from identify import Processing, essential_parameters, fit, validate

    _say("[4/6] identifying the robot: WLS, essential parameters, physically consistent LS...")
    # The demo validates with its own filtering (validate(...) below): a fixed processing, not chosen per fit.
    drop = Processing(min_velocity=REST_BELOW, rest="drop", estimate_delay=False, cross_validate=False)
    done = fit(robot, [recs["empty"]], drop, base=bp)
    res = done.result
    # The same identification on the random trajectory (the validation motion): what the
    # criterion (predicted relative sigma) buys, measured per parameter group.
    res_random = fit(robot, [recs["validation"]], drop, base=bp).result
    return {"res": res, "groups": (group_medians(res, truth), group_medians(res_random, truth)),
            "ess": essential_parameters(res),
            "con": done.identified,  # the identified model (no description bodies: the data's alone)
            "val": validate(robot, res, recs["validation"], base=bp),
            "errors": {n: abs(v - truth[n]) / abs(truth[n]) for n, v in zip(res.names, res.values)
                       if abs(truth[n]) > 1e-3},
            "within": [n for n, v, s in zip(res.names, res.values, res.std) if abs(v - truth[n]) <= 3 * s]}


def _payloads(robot: Any, bp: Any, recs: dict[str, Any], res: Any) -> dict[str, list[Any]]:
    """Both payloads by the four methods of section IV."""
    from identify.payloads.methods import payload

    _say("[5/6] identifying the payloads by the four methods of section IV...")
    return {name: [payload(robot, m, empty=[recs["empty"]] if m != 1 else [], loaded=[recs[name]],
                           robot_params=res if m == 1 else None, a_priori=name, base=bp,
                           min_velocity=REST_BELOW)
                   for m in (1, 2, 3, 4)]
            for name in ("tables_4", "tables_5")}


def _tx40() -> tuple[Any, Any]:
    """The real TX40 record: fit on its first two thirds, validate on the rest."""
    import rx90sym

    from identify import Processing, fit, read_motor_recording, split, validate

    _say("[6/6] identifying the real TX40 data (model of the paper + torque offsets)...")
    data = rx90sym.datasets.tx40()  # shipped in the package (Apache-2.0, FIGAROH examples)
    tx = rx90sym.load_robot("tx40", offsets=True)
    raw = read_motor_recording(data.positions, data.torques, tx, period=data.period)
    fit_part, held = split(raw, 2 / 3)
    tx_res = fit(tx, [fit_part], Processing(decimate_to=100.0, min_velocity=None, estimate_delay=False,
                                            cross_validate=False)).result
    return tx_res, validate(tx, tx_res, held, decimate_to=100.0)


def _summary(traj: Any, other: Any, fits: dict[str, Any], payloads: dict[str, list[Any]]) -> None:
    import rx90sym

    groups, res = fits["groups"], fits["res"]
    print(f"Excitation ({traj.criterion}): median relative σ optimised / random, "
          + "; ".join(f"{g} {groups[0][g]:.2g} / {groups[1][g]:.2g} %" for g in groups[0])
          + f" (cond {traj.cond:.1f} / {other.cond:.1f})")
    print(f"Robot (WLS, realistic noise): {len(fits['within'])}/{len(res.names)} base parameters within 3σ of "
          f"the truth; median relative error {100 * np.median(list(fits['errors'].values())):.2f} %")
    print(f"Essential parameters: {len(fits['ess'].names)}; validation relative error per joint [%]: "
          + " ".join(f"{e:.1f}" for e in fits["val"].relative_error_pct))
    print(f"Consistent LS: cost +{fits['con'].cost_increase_pct:.3f} % vs WLS")
    for name, results in payloads.items():
        ap = rx90sym.load_payload(name)
        print(f"Payload {name} (a priori Mc = {ap['Mc']}, MZc = {ap['MZc']}): "
              + "; ".join(f"method {r.method}: Mc = {r['Mc']:.3f}, MZc = {r['MZc']:.3f}" for r in results))
