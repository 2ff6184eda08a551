"""One set of defaults (issue 31): each command and the library call it makes, both with their
defaults, on the same input files give the same numbers (1e-9 relative).

The inputs are short twin runs of the RX90 (8 s at 250 Hz) written as a user's CSV files; the
commands run in this process (``identify.app.cli.main``). The library side is called as a user
would: on the recordings read with :func:`identify.read_recording` and nothing but the inputs
given. Elsewhere: ``excite`` against ``excitation.optimise`` (test_defaults.py), the whole fit file
of ``rx90 identify`` against ``identify.fit`` (test_fit_file.py, a command in a subprocess).
"""
from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import identify
import rx90sym
from excitation import read_trajectory
from identify.app.cli import main
from monitor_twin import pulses, with_external
from motions import multisine
from command_line import write_trajectory

RTOL = 1e-9
DURATION = 8.0
SENSOR = rx90sym.twin.CurrentSensor((0.5, 0.6, 0.4, 0.3, 0.25, 0.2), "motor", noise=0.02)
PAYLOAD = "tables_4"


def same_numbers(lib: Any, cli: Any, where: str = "") -> None:
    """Every entry of ``lib`` (a JSON-like tree) is in ``cli``: numbers within RTOL relative (NaN
    with NaN), everything else equal. ``cli`` may hold more keys (the command's own report)."""
    if isinstance(lib, dict):
        assert isinstance(cli, dict), where
        missing = set(lib) - set(cli)
        assert not missing, f"{where}: not in the command's output: {sorted(missing)}"
        for key, value in lib.items():
            same_numbers(value, cli[key], f"{where}.{key}")
    elif isinstance(lib, (list, tuple)):
        assert isinstance(cli, (list, tuple)) and len(lib) == len(cli), (where, lib, cli)
        for k, (a, b) in enumerate(zip(lib, cli)):
            same_numbers(a, b, f"{where}[{k}]")
    elif isinstance(lib, (int, float)) and not isinstance(lib, bool) and cli is not None:
        a, b = float(lib), float(cli)
        assert (math.isnan(a) and math.isnan(b)) or abs(a - b) <= RTOL * max(abs(a), abs(b), 1e-300), \
            f"{where}: library {a!r}, command {b!r}"
    else:
        assert lib == cli, f"{where}: library {lib!r}, command {cli!r}"


def cli(*args: Any) -> None:
    code = main([str(a) for a in args])
    assert code == 0, args


def as_json(obj: Any) -> Any:
    """The object as its JSON file holds it (floats as JSON writes them; NaN kept)."""
    return json.loads(json.dumps(obj))


@pytest.fixture(scope="module")
def robot():
    return rx90sym.load_robot("rx90")


@pytest.fixture(scope="module")
def folder(tmp_path_factory, robot):
    """The input files: a trajectory CSV; twin runs (fit, held out, the fit's motion loaded) and
    current recordings (one motion empty and loaded); a held-out run with contact pulses."""
    d = tmp_path_factory.mktemp("same_defaults")
    write_trajectory(d / "traj.csv", robot, 1, duration=6.0)
    motion, other = multisine(robot, 31, DURATION), multisine(robot, 32, DURATION)
    sim = rx90sym.twin.simulate
    runs = {"fit.csv": sim(robot, motion, duration=DURATION, seed=31),
            "held.csv": sim(robot, other, duration=DURATION, seed=32),
            "loaded.csv": sim(robot, motion, duration=DURATION, seed=33, payload=PAYLOAD),
            "cur_empty.csv": sim(robot, motion, duration=DURATION, seed=34, noise="quantised", currents=SENSOR),
            "cur_loaded.csv": sim(robot, motion, duration=DURATION, seed=35, noise="quantised", currents=SENSOR,
                                  payload=PAYLOAD)}
    ext, _ = pulses(robot, runs["held.csv"].t, seed=4)
    runs["pulses.csv"] = with_external(runs["held.csv"], ext)
    for name, rec in runs.items():
        identify.write_recording(d / name, rec, robot)
    return d


def read(folder: Path, name: str, robot) -> Any:
    return identify.read_recording(folder / name, robot)


@pytest.fixture(scope="module")
def wls(folder, robot):
    """``rx90 identify fit.csv --json wls.json`` and ``identify.fit(robot, [rec])``, both with defaults."""
    cli("identify", folder / "fit.csv", "--json", folder / "wls.json")
    return identify.fit(robot, [read(folder, "fit.csv", robot)])


@pytest.fixture(scope="module")
def consistent(folder, robot):
    """``rx90 identify --method consistent`` and ``identify.fit(..., method="consistent")``."""
    cli("identify", folder / "fit.csv", "--method", "consistent", "--json", folder / "consistent.json")
    return identify.fit(robot, [read(folder, "fit.csv", robot)], method="consistent")


def test_simulate(folder, robot):
    """``rx90 simulate traj.csv`` and ``rx90sym.twin.simulate`` on the trajectory it reads."""
    cli("simulate", folder / "traj.csv", "--out", folder / "sim.csv")
    lib = rx90sym.twin.simulate(robot, read_trajectory(folder / "traj.csv", robot))
    back = read(folder, "sim.csv", robot)
    assert back.q.shape == lib.q.shape
    for name in ("t", "q", "tau"):
        a, b = getattr(lib, name), getattr(back, name)
        assert np.abs(a - b).max() <= RTOL * np.abs(a).max(), name


def _fit_numbers(fit_json: dict) -> dict:
    """What a fit is: its parameter values and σ, the processing chosen and the residuals."""
    keys = ("parameters", "residual_rms", "cutoff_hz", "decimate_to_hz", "delay_estimate_s", "model", "standard",
            "bootstrap_std", "bootstrap", "cost", "wls_cost", "prior")
    out = {k: fit_json[k] for k in keys if k in fit_json}
    out["chosen"] = {k: v for k, v in (fit_json.get("processing_choice") or {}).get("chosen", {}).items()
                     if k != "seconds"}
    return out


@pytest.mark.parametrize("method", ["wls", "consistent"])
def test_identify(folder, wls, consistent, method):
    """The fit file's numbers (parameters, σ, segment bootstrap, the processing chosen, the prior) are
    the library fit's."""
    lib = wls if method == "wls" else consistent
    assert lib.bootstrap is not None and lib.bootstrap.seed == 0  # the command's segment bootstrap
    cli_json = json.loads((folder / f"{method}.json").read_text())
    lib_json = as_json(lib.to_json())
    assert lib_json["method"] == cli_json["method"] == method
    same_numbers(_fit_numbers(lib_json), _fit_numbers(cli_json))
    assert cli_json["processing"] == lib_json["processing"] == identify.Processing().to_json()
    if method == "consistent":  # the robot's nominal parameters as the prior, in both
        assert lib.result.prior is not None and lib.result.standard


def test_predict(folder, robot, wls):
    """``rx90 predict`` and ``Fit.predict``: the same held-out errors (raw, filtered, moving, baseline)."""
    cli("predict", folder / "held.csv", "--identification", folder / "wls.json", "--json", folder / "pred.json")
    cli_json = json.loads((folder / "pred.json").read_text())
    for f in (wls, identify.load_fit(folder / "wls.json")):  # the fit in memory, and its file
        same_numbers(as_json(f.predict(read(folder, "held.csv", robot)).to_dict()), cli_json)


def test_export(folder, consistent, tmp_path):
    """``rx90 export --urdf --mjcf`` and ``identify.export_urdf`` / ``export_mjcf``: the same files."""
    cli("export", folder / "consistent.json", "--urdf", tmp_path / "cli.urdf", "--mjcf", tmp_path / "cli.xml")
    # The fit file (what the command reads): the same files. The fit in memory: the same but for the
    # robot file they name (the bundled one; a loaded fit names the copy of the description it embeds).
    for f, named in ((identify.load_fit(folder / "consistent.json"), ()), (consistent, ("source", "source_model"))):
        identify.export_urdf(f, tmp_path / "lib.urdf")
        identify.export_mjcf(f, tmp_path / "lib.xml")
        for lib, cmd in (("lib.urdf", "cli.urdf"), ("lib.xml", "cli.xml")):
            a, b = ((tmp_path / n).read_text() for n in (lib, cmd))
            assert (_model_text(a) if named else a) == (_model_text(b) if named else b), lib
        for lib, cmd in (("lib.actuation.json", "cli.actuation.json"), ("lib.mjcf.actuation.json",
                                                                        "cli.mjcf.actuation.json")):
            a, b = (json.loads((tmp_path / n).read_text()) for n in (lib, cmd))
            for key in ("model_file", *named):  # model_file: the file's own name (lib.*, cli.*)
                a.pop(key, None), b.pop(key, None)
            same_numbers(a, b)


def _model_text(text: str) -> str:
    """An exported model's text without the line naming the robot file it came from."""
    return "\n".join(x for x in text.splitlines() if "Generated by rx90sym from" not in x)


@pytest.mark.parametrize("method", [1, 2, 3, 4])
def test_payload(folder, robot, wls, method):
    """``rx90 payload --method M`` and ``identify.payload``: the same estimates, σ and bootstrap σ."""
    empty = [] if method == 1 else ["--empty", folder / "fit.csv"]
    given = ["--robot-params", folder / "wls.json"] if method == 1 else []
    out = folder / f"payload{method}.json"
    cli("payload", "--method", method, *empty, "--loaded", folder / "loaded.csv", *given, "--json", out)
    cli_json = json.loads(out.read_text())
    lib = identify.payload(robot, method, empty=[] if method == 1 else [read(folder, "fit.csv", robot)],
                           loaded=[read(folder, "loaded.csv", robot)],
                           robot_params=folder / "wls.json" if method == 1 else None)
    same_numbers(as_json(lib.to_dict()), cli_json)


def test_gains(folder, robot):
    """``rx90 gains`` and ``identify.drive_gains``: the same gains, σ and side."""
    mass = rx90sym.load_payload(PAYLOAD)["Mc"]
    out = folder / "gains.json"
    cli("gains", "--empty", folder / "cur_empty.csv", "--loaded", folder / "cur_loaded.csv", "--mass", mass,
        "--json", out)
    lib = identify.drive_gains(robot, [read(folder, "cur_empty.csv", robot)], [read(folder, "cur_loaded.csv", robot)],
                               mass)
    same_numbers(as_json(lib.to_dict()), json.loads(out.read_text()))


def test_monitor(folder, robot, wls):
    """``rx90 monitor`` and ``identify.monitor_log`` (on the fit in memory with the thresholds rx90
    identify --json stores, and on the file): the same events, thresholds and gain."""
    out = folder / "monitor.json"
    cli("monitor", folder / "pulses.csv", "--identification", folder / "wls.json", "--json", out)
    cli_json = json.loads(out.read_text())
    assert cli_json["events"], "the pulses make events"
    from identify.monitor.thresholds import with_contact_thresholds

    fit = with_contact_thresholds(wls, [read(folder, "fit.csv", robot)])[0]  # what rx90 identify --json stores
    for f in (fit, identify.load_fit(folder / "wls.json")):
        lib = as_json(identify.monitor_log(f, folder / "pulses.csv").to_json())
        assert lib.pop("fit_sha256") is None  # the command's: the hash of the file it read
        same_numbers(lib, cli_json)


def _command_defaults(command: str, *required: str) -> dict:
    """The defaults of ``rx90 COMMAND`` as its parser gives them (required options given)."""
    from identify.app.cli import build_parser

    return vars(build_parser().parse_args([command, *required]))


def test_options_the_runs_above_leave_alone_have_the_librarys_defaults():
    """The defaults the command runs above do not exercise (a bound, a tolerance, a rate given to the
    library only when asked): each command's parser default is the library parameter's."""
    import inspect

    from identify.monitor.log import calibrate, monitor_log

    def lib(f, name):
        return inspect.signature(f).parameters[name].default

    sim = _command_defaults("simulate", "t.csv", "--out", "r.csv")
    assert (sim["noise"], sim["seed"]) == (lib(rx90sym.twin.simulate, "noise"), lib(rx90sym.twin.simulate, "seed"))
    gains = _command_defaults("gains", "--empty", "e.csv", "--loaded", "l.csv", "--mass", "1")
    for name in ("method", "mass_std", "flag_pct", "position_tol", "cutoff", "decimate_to"):
        assert gains[name] == lib(identify.drive_gains, name), name
    assert gains["no_offsets"] is not lib(identify.drive_gains, "offsets")
    ident = _command_defaults("identify", "r.csv")
    processing = identify.Processing()
    for name in ("cutoff", "decimate_to", "min_velocity", "rest", "delay", "cross_validate", "friction"):
        assert ident[name] == getattr(processing, name), name
    assert ident["bootstrap_seed"] == lib(identify.fit, "bootstrap_seed")
    mon = _command_defaults("monitor", "r.csv", "--identification", "f.json")
    assert mon["block"] == lib(monitor_log, "block") == lib(calibrate, "block") and mon["gain"] is None
    payload = _command_defaults("payload", "--method", "4", "--loaded", "l.csv")
    assert payload["mass_tol"] is None and payload["position_tol"] is None  # None: the library's, said in --help
    from identify.payloads.defaults import MASS_TOL
    from identify.signal.defaults import POSITION_TOLERANCE

    assert (lib(identify.payload, "mass_tol"), lib(identify.payload, "position_tol")) == (MASS_TOL, POSITION_TOLERANCE)
