"""What the safety envelope costs (issue 19): time per start and predicted precision.

A 6-joint arm (the UR5 URDF of the tests, its inertials as nominal parameters, acceleration
limits 2x the velocity limits), a 20 s, 5-harmonic trajectory, criterion "sigma", one start
with the same seed for every configuration, adding the envelope's parts one at a time:

  none        the robot's own limits, no Cartesian constraint (the former default)
  limits      + experiment limits (90 % of the ranges, 0.7 x velocities, 0.5 x accelerations)
  height      + no moving point below the mounting plane + 0.05 m
  speed       + Cartesian speed <= 1 m/s at the tool point and every capsule end
  full        + self-collision of the URDF's capsules (the default of rx90 excite)
  vm          full, evaluated as before the compiled kernels: one CasADi graph in its virtual
              machine (OptimiserOptions(compiled=False)) and IPOPT's Sherman-Morrison L-BFGS
              (the reference of the speed-up full / vm, measured in the same run)

Columns: wall-clock and CPU time of the start [s] (CPU time suffers less from other processes on
a loaded machine), IPOPT iterations, wall time per iteration [ms], cond(W), the criterion, and the predicted
relative sigma of each parameter group (median over the group, %, eq. 15 with the default noise
of 1 % of each torque limit; groups and reference magnitudes as docs/excitation.md), and "ok"
when the result holds every limit on the optimiser's own 1 kHz check (no margins). The ratio
full / none of the time per start is the figure the issue's target (<= 2x) refers to; full / vm
is the speed-up of the compiled evaluation (issue 32: a start <= 10 s, the same precision).

    python benchmarks/bench_envelope.py [--seed 0 [1 ...]] [--only none full vm] [--duration 20] [--json out.json]

--variant NAME:KEY=VALUE[,KEY=VALUE...] adds a configuration NAME: ``full`` with these extra
IPOPT options (e.g. ``--variant adaptive:mu_strategy=adaptive``), run in the same loop and
seeds, with its own ratio against ``none``. --start-room F adds ``room``: ``full`` whose random
starts are pulled towards the centre pose until they hold F x the optimiser's height, clearance
and speed margins (F = 1: the code's starts), the experiment of docs/excitation.md.

With --every-robot: ``rx90 excite`` with its defaults (one start) on every bundled robot and the
UR5 URDF: time, cond, the largest torque usage, the smallest clearance and height margin, the
fastest point, and any warning that a check is off (there should be none).

    python benchmarks/bench_envelope.py --every-robot [--duration 20]
"""
from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import time
import warnings
from pathlib import Path

import numpy as np

UR5 = Path(__file__).resolve().parents[1] / "tests" / "data" / "urdf" / "ur5.urdf"


MODELS = ("none", "limits", "height", "speed", "full")
#: ``vm``: the IPOPT settings and evaluation before the compiled kernels (see the docstring)
VM_IPOPT = (("limited_memory_aug_solver", "sherman-morrison"),)


def models(robot, chi, base):
    """(name, ExcitationModel) of each configuration, cumulative."""
    import excitation
    from excitation.model import model_from_robot

    full, _ = excitation.safe_model(robot, chi, base, excitation.Envelope())
    plain = model_from_robot(robot, chi, base)
    limits = dataclasses.replace(plain, limits=full.limits, centre=full.centre)
    height = dataclasses.replace(limits, heights=full.heights, z_min=full.z_min, point_names=full.point_names)
    speed = dataclasses.replace(height, speeds=full.speeds, speed_max=full.speed_max)
    return [("none", plain), ("limits", limits), ("height", height), ("speed", speed), ("full", full)]


def group_sigma(traj, model, objective) -> dict[str, float]:
    """Median predicted relative sigma [%] per parameter group (eq. 15)."""
    from excitation.criterion import regressor_samples
    from excitation.objective import GROUPS, numeric_information, parameter_group

    t, q, qd, qdd = traj.sample(250.0)
    g = numeric_information(regressor_samples(model.regressor, q, qd, qdd), objective, traj.duration)
    rel = np.sqrt(objective.predicted_variance(g)) / objective.reference
    groups = np.array([parameter_group(n) for n in model.names])
    return {name: float(100 * np.median(rel[groups == name])) for name in GROUPS if np.any(groups == name)}


def every_robot(duration: float) -> None:
    """The default excitation of every bundled robot and the UR5 URDF, through the command line."""
    import subprocess
    import sys
    import tempfile

    rx90 = str(Path(sys.executable).with_name("rx90"))
    print(f"{'robot':10s} {'s':>6s} {'cond':>7s} {'torque':>7s} {'clear m':>8s} {'above m':>8s} {'v m/s':>6s}  warnings")
    for name in ("rx90", "tx40", "ur10e", "panda", str(UR5)):
        extra = ["--tip", "tool0"] if name.endswith(".urdf") else []
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            proc = subprocess.run([rx90, "excite", "--robot", name, *extra, "--duration", f"{duration:g}", "--starts",
                                   "1", "--out", f"{tmp}/t.csv", "--json", f"{tmp}/t.json"],
                                  capture_output=True, text=True)
            elapsed = time.perf_counter() - t0
            label = Path(name).name
            if proc.returncode != 0:
                print(f"{label:10s} failed: {proc.stderr.strip().splitlines()[-1]}")
                continue
            usage = json.loads(Path(f"{tmp}/t.json").read_text())["limits_usage"]
            warns = [w for w in proc.stderr.splitlines() if "warning" in w and "acceleration" not in w]
            torque = max(v for v in usage["torque"] if v is not None) if isinstance(usage["torque"], list) else "off"
            print(f"{label:10s} {elapsed:6.1f} {json.loads(Path(f'{tmp}/t.json').read_text())['cond']:7.1f} "
                  f"{torque:7.3f} {usage['min_clearance_m']:8.4f} {usage['min_height_m'] - usage['z_min_m']:8.4f} "
                  f"{usage['max_point_speed_m_s']:6.3f}  {'; '.join(warns) or 'none'}", flush=True)


def parse_variant(text: str) -> tuple[str, tuple[tuple[str, object], ...]]:
    """NAME:KEY=VALUE,... -> (NAME, IPOPT options); numbers become float or int."""
    name, _, rest = text.partition(":")
    pairs = []
    for item in filter(None, rest.split(",")):
        key, _, value = item.partition("=")
        for kind in (int, float, str):
            try:
                pairs.append((key.strip(), kind(value.strip())))
                break
            except ValueError:
                continue
    return name, tuple(pairs)


@contextlib.contextmanager
def start_room(factor: float):
    """Within it, random starts hold ``factor`` x the optimiser's height, clearance and speed
    margins (a patch of excitation.envelope.shrink_to_envelope, for this experiment only)."""
    from excitation import envelope

    original = envelope.shrink_to_envelope

    def shrink(model, form, z, z_centre, times, margins, tries=12):
        wide = dataclasses.replace(margins, height=factor * margins.height, velocity=factor * margins.velocity,
                                   clearance=factor * margins.clearance)
        return original(model, form, z, z_centre, times, wide, tries)

    envelope.shrink_to_envelope = shrink if factor != 1.0 else original
    try:
        yield
    finally:
        envelope.shrink_to_envelope = original


def run_configs(robot, chi, base, args: argparse.Namespace, seed: int) -> list[dict]:
    """One start of each configuration with ``seed``: times, iterations, cond, criterion, sigmas."""
    import excitation
    from excitation.options import OptimiserOptions

    rows = []
    configs = [(name, model, ()) for name, model in models(robot, chi, base)]
    full = next(model for name, model, _ in configs if name == "full")
    configs.append(("vm", full, VM_IPOPT))
    configs += [(name, full, extra) for name, extra in map(parse_variant, args.variant)]
    configs += [("room", full, ())] if args.start_room else []
    for name, model, extra in configs:
        if args.only and name not in args.only and (extra == () or name == "vm") and name != "room":
            continue
        objective = excitation.make_objective(model, "sigma", nominal_base=base.beta(chi))
        options = OptimiserOptions(criterion=objective, ipopt=extra, compiled=name != "vm")
        t0, c0 = time.perf_counter(), time.process_time()
        with start_room(args.start_room if name == "room" else 1.0):
            traj = excitation.optimise_model(model, excitation.FourierSeries(args.duration, args.harmonics),
                                             seed=seed, starts=1, options=options, progress=args.progress)
        elapsed, cpu = time.perf_counter() - t0, time.process_time() - c0
        rows.append({"config": name, "seed": seed, "time_s": elapsed, "cpu_s": cpu,
                     "iterations": traj.info.iterations, "cond": traj.cond, "feasible": traj.usage.feasible,
                     "criterion": traj.info.criterion_value, "sigma_percent": group_sigma(traj, model, objective)})
        print(f"{name}: {elapsed:.1f} s", flush=True)
    return rows


def print_table(rows: list[dict], args: argparse.Namespace, seed: int) -> dict[str, float] | None:
    """The table of one seed; returns the full / none ratios (wall, CPU) when both ran."""
    groups = list(rows[0]["sigma_percent"])
    print(f"\nUR5 URDF, {args.duration:g} s, {args.harmonics} harmonics, seed {seed}, one start each")
    print(f"{'config':8s} {'s/start':>8s} {'cpu s':>6s} {'iter':>5s} {'ms/it':>6s} {'cond':>8s} {'crit':>7s} "
          + " ".join(f"{g[:22]:>22s}" for g in groups) + "  1 kHz")
    for r in rows:
        print(f"{r['config']:8s} {r['time_s']:8.1f} {r['cpu_s']:6.1f} {r['iterations']:5d} "
              f"{1e3 * r['time_s'] / max(r['iterations'], 1):6.0f} {r['cond']:8.1f} {r['criterion']:7.3f} "
              + " ".join(f"{r['sigma_percent'][g]:22.3g}" for g in groups) + f"  {'ok' if r['feasible'] else 'VIOLATED'}")
    by = {r["config"]: r for r in rows}
    if "full" in by and "vm" in by:
        print(f"speed-up vm / full (time per start): {by['vm']['time_s'] / by['full']['time_s']:.2f}; CPU time "
              f"{by['vm']['cpu_s'] / by['full']['cpu_s']:.2f}")
    if "none" not in by:
        return None
    none, out = by["none"], {}
    for name in [r["config"] for r in rows if r["config"] not in MODELS[:-1] + ("vm",)]:
        full = by[name]
        per_it = (full["time_s"] / max(full["iterations"], 1)) / (none["time_s"] / max(none["iterations"], 1))
        print(f"ratio {name} / none (time per start): {full['time_s'] / none['time_s']:.2f} (target <= 2); "
              f"CPU time {full['cpu_s'] / none['cpu_s']:.2f}; time per IPOPT iteration {per_it:.2f}")
        out[name] = {"wall": full["time_s"] / none["time_s"], "cpu": full["cpu_s"] / none["cpu_s"]}
    return out or None


def summarise(rows: list[dict], ratios: list[dict], seeds: list[int]) -> None:
    """Per configuration over the seeds: ratios against none, iterations, median sigma per group."""
    print(f"\nover seeds {', '.join(map(str, seeds))}:")
    for name in ratios[0]:
        wall, cpu = (np.array([r[name][k] for r in ratios]) for k in ("wall", "cpu"))
        mine = [r for r in rows if r["config"] == name]
        sig = {g: float(np.median([r["sigma_percent"][g] for r in mine])) for g in mine[0]["sigma_percent"]}
        print(f"  {name}: ratio / none per start {', '.join(f'{v:.2f}' for v in wall)} (mean {wall.mean():.2f}); "
              f"CPU mean {cpu.mean():.2f}; iterations {', '.join(str(r['iterations']) for r in mine)}; "
              f"median sigma % " + ", ".join(f"{g} {v:.3g}" for g, v in sig.items()))
    none = [r for r in rows if r["config"] == "none"]
    print(f"  none: iterations {', '.join(str(r['iterations']) for r in none)}")


def per_start(rows: list[dict], seeds: list[int]) -> None:
    """Per configuration over the seeds: time per start (wall, CPU; median), iterations, median
    relative sigma per group (median over the seeds), and whether every start held the 1 kHz check."""
    print(f"\nper start over seeds {', '.join(map(str, seeds))} (median):")
    names = list(dict.fromkeys(r["config"] for r in rows))
    by = {name: [r for r in rows if r["config"] == name] for name in names}
    for name in names:
        mine = by[name]
        wall, cpu = (np.array([r[k] for r in mine]) for k in ("time_s", "cpu_s"))
        sig = {g: float(np.median([r["sigma_percent"][g] for r in mine])) for g in mine[0]["sigma_percent"]}
        print(f"  {name:6s} s/start {', '.join(f'{v:.1f}' for v in wall)} (median {np.median(wall):.1f}); "
              f"CPU {', '.join(f'{v:.1f}' for v in cpu)} (median {np.median(cpu):.1f}); "
              f"iterations {', '.join(str(r['iterations']) for r in mine)}; 1 kHz check "
              f"{'all ok' if all(r['feasible'] for r in mine) else 'VIOLATED'}; median sigma % "
              + ", ".join(f"{g} {v:.3g}" for g, v in sig.items()))
    if "full" in by and "vm" in by:
        ref = {g: np.median([r["sigma_percent"][g] for r in by["vm"]]) for g in by["vm"][0]["sigma_percent"]}
        new = {g: np.median([r["sigma_percent"][g] for r in by["full"]]) for g in ref}
        print("  full / vm: median time per start "
              f"{np.median([r['time_s'] for r in by['full']]) / np.median([r['time_s'] for r in by['vm']]):.2f}, "
              f"CPU {np.median([r['cpu_s'] for r in by['full']]) / np.median([r['cpu_s'] for r in by['vm']]):.2f}; "
              "median sigma " + ", ".join(f"{g} {new[g] / ref[g]:.3f}" for g in ref))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, nargs="+", default=[0], help="one start per seed and configuration")
    parser.add_argument("--duration", type=float, default=20.0)
    parser.add_argument("--harmonics", type=int, default=5)
    parser.add_argument("--only", nargs="*", default=None, help="run only these configurations")
    parser.add_argument("--variant", nargs="*", default=[], metavar="NAME:KEY=VALUE,...",
                        help="also run full with these extra IPOPT options")
    parser.add_argument("--start-room", type=float, default=None, metavar="F",
                        help="also run full with starts holding F x the optimiser's margins")
    parser.add_argument("--progress", action="store_true", help="a line per start on stderr")
    parser.add_argument("--json", help="also write the figures to this JSON file")
    parser.add_argument("--every-robot", action="store_true", help="default rx90 excite on every robot")
    args = parser.parse_args()
    if args.every_robot:
        every_robot(args.duration)
        return

    import rx90sym

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the URDF's missing acceleration limits: given below
        robot = rx90sym.load_robot(UR5, tip="tool0", acceleration=2.0 * 3.15)
    chi = robot.parameter_vector(rx90sym.nominal_parameters(robot))
    base = rx90sym.base_parameters(robot)
    rows, ratios = [], []
    for seed in args.seed:
        seed_rows = run_configs(robot, chi, base, args, seed)
        rows += seed_rows
        ratio = print_table(seed_rows, args, seed)
        if ratio is not None:
            ratios.append(ratio)
    if len(ratios) > 1:
        summarise(rows, ratios, args.seed)
    if len(args.seed) > 1:
        per_start(rows, args.seed)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
