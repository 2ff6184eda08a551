"""One processing record, one fit object and its file: the library and the command give the same
numbers, the file reads back with its robot and processing, and a foreign file is refused."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import identify
import rx90sym
from motions import multisine

RX90 = str(Path(sys.executable).parent / "rx90")
TIMING = ()  # keys that may differ between two identical runs (besides the choice's seconds)


def cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    proc = subprocess.run([RX90, *args], capture_output=True, text=True, cwd=cwd, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return proc


@pytest.fixture(scope="module")
def runs(tmp_path_factory, rx90):
    """Two twin recordings written as a user's CSV files (fit, held out)."""
    d = tmp_path_factory.mktemp("fitfile")
    for name, seed in (("fit.csv", 31), ("held.csv", 32)):
        rec = rx90sym.twin.simulate(rx90, multisine(rx90, seed), duration=8.0, noise="realistic", seed=seed)
        identify.write_recording(d / name, rec, rx90, convention="controller")
    return d


@pytest.fixture(scope="module")
def cli_fit(runs):
    """``rx90 identify fit.csv --json`` with every default (its file and its printed text)."""
    proc = cli("identify", "fit.csv", "--json", "cli.json", cwd=runs)
    return json.loads((runs / "cli.json").read_text()), proc.stdout


@pytest.fixture(scope="module")
def lib_fit(runs, rx90):
    """``identify.fit`` with every default on the same file (its segment bootstrap too), with its contact
    thresholds (identify.monitor.thresholds) as the command's --json stores them."""
    from identify.monitor.thresholds import with_contact_thresholds

    rec = identify.read_recording(runs / "fit.csv", rx90)
    return with_contact_thresholds(identify.fit(rx90, [rec]), [rec])[0]


def _without(d: dict, keys) -> dict:
    """``d`` without ``keys`` nor the timing fields of the cross-validated choice (its seconds)."""
    out = {k: v for k, v in d.items() if k not in keys}
    if out.get("processing_choice"):
        choice = {k: v for k, v in out["processing_choice"].items() if k != "seconds"}
        choice["candidates"] = [{k: v for k, v in c.items() if k != "seconds"} for c in choice["candidates"]]
        choice["chosen"] = {k: v for k, v in choice["chosen"].items() if k != "seconds"}
        if choice.get("offset_candidate"):  # the chosen processing scored with torque offsets
            choice["offset_candidate"] = {k: v for k, v in choice["offset_candidate"].items() if k != "seconds"}
        if "friction" in choice:  # the friction form's choice (identify.friction.choice)
            forms = {k: v for k, v in choice["friction"].items() if k != "seconds"}
            forms["candidates"] = [{k: v for k, v in c.items() if k != "seconds"} for c in forms["candidates"]]
            if forms.get("combined"):  # the per-joint forms scored together
                forms["combined"] = {k: v for k, v in forms["combined"].items() if k != "seconds"}
            choice["friction"] = forms
        out["processing_choice"] = choice
    return out


@pytest.mark.slow
def test_library_defaults_and_command_defaults_give_the_same_file(cli_fit, lib_fit, runs):
    cli, _ = cli_fit
    lib = json.loads(lib_fit.save(runs / "lib.json").read_text())
    assert _without(lib, TIMING) == _without(cli, TIMING)
    # The defaults are the command's: rest threshold and policy, decimation, delay 0 compensated
    # while the estimate is reported.
    assert cli["processing"] == identify.Processing().to_json()
    assert cli["model"]["min_velocity"] == identify.DEFAULT_MIN_VELOCITY
    # No cut-off given: cut-off, decimation and per-joint rest policy chosen by cross-validation.
    chosen = cli["processing_choice"]["chosen"]
    assert cli["model"]["cutoff_hz"] == chosen["cutoff_hz"] and cli["model"]["rest"] == chosen["rest"]
    assert cli["delay_estimate_s"] is not None and cli["model"]["delay_s"] == 0.0
    assert cli["schema_version"] == identify.fitting.fit_file.SCHEMA_VERSION


def test_former_keys_of_the_identification_json_are_kept(cli_fit):
    cli, _ = cli_fit
    former = {"robot", "method", "parameters", "sigma_rho", "cond", "cond_unweighted", "residual_rms",
              "weights", "rows", "history", "spring", "bootstrap_std", "bootstrap", "cutoff_hz",
              "decimate_to_hz", "delay_estimate_s", "model", "essential", "validation"}
    assert former <= set(cli)


@pytest.mark.slow
def test_load_fit_predicts_as_the_predict_command(cli_fit, runs, rx90):
    cli("predict", "held.csv", "--identification", "cli.json", "--json", "pred.json", cwd=runs)
    replay = json.loads((runs / "pred.json").read_text())
    loaded = identify.load_fit(runs / "cli.json")
    assert loaded.robot.name == "rx90" and loaded.processing == identify.Processing()
    val = loaded.predict(identify.read_recording(runs / "held.csv", loaded.robot))
    assert _without(val.to_dict(), ()) == _without(replay, ("identification", "robot_warning"))


def test_saved_fit_reads_back_and_predicts_the_same(lib_fit, runs, rx90, tmp_path):
    path = lib_fit.with_essential().save(tmp_path / "fit.json")
    back = identify.load_fit(path)
    assert back.to_json() == json.loads(path.read_text())
    held = identify.read_recording(runs / "held.csv", rx90)
    a, b = lib_fit.predict(held), back.predict(held)
    np.testing.assert_array_equal(a.predicted, b.predicted)
    # The held-out error is the model's, not a copy of the fit: it differs from the fit's residual.
    assert not np.allclose(a.rms_error, lib_fit.result.residual_rms, rtol=1e-3)


@pytest.mark.parametrize("change, words", [
    (lambda d: d.pop("schema_version"), "without 'schema_version'"),
    (lambda d: d.update(schema_version=99), "schema_version 99 is not supported"),
    (lambda d: d["processing"].update(cut_off=3.0), "unknown processing field(s) cut_off"),
])
def test_old_or_foreign_fit_files_are_refused_by_name(lib_fit, tmp_path, change, words):
    data = lib_fit.to_json()
    change(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ValueError) as err:
        identify.load_fit(path)
    assert str(path) in str(err.value) and words in str(err.value)


def test_processing_record_checks_and_round_trips():
    p = identify.Processing(cutoff=4.0, decimate_to=0, min_velocity=0, rest="drop", delay="auto")
    assert p.decimate_to is None and p.min_velocity is None
    assert identify.Processing.from_json(json.loads(json.dumps(p.to_json()))) == p
    for bad in ({"rest": "keep"}, {"delay": "later"}, {"cutoff": -1.0}, {"decimate_to": float("nan")}):
        with pytest.raises(ValueError, match="processing: "):
            identify.Processing(**bad)


def test_the_deprecated_entry_points_are_gone():
    """identify.identify and identify.fit_recordings were removed (the project has no outside users)."""
    for name in ("identify", "fit_recordings"):
        assert not hasattr(identify, name)


def test_a_bootstrap_sigma_the_draws_could_not_estimate_is_null_in_the_file_and_nan_again():
    """A spring coefficient's bootstrap σ can be NaN (rank-deficient draws): the file stays JSON."""
    import json as _json

    from identify.fitting.fit_result import Bootstrap
    b = Bootstrap(np.array([0.5, np.nan, 2.0]), 0.5, 200, 0)
    text = _json.dumps(b.to_json(), allow_nan=False)      # raised "Out of range float values" before
    back = Bootstrap.from_json(_json.loads(text))
    assert back.std[0] == 0.5 and np.isnan(back.std[1]) and back.std[2] == 2.0


def test_a_fit_file_or_gains_file_that_is_not_json_is_named_with_its_line_and_column(tmp_path):
    """One JSON reader (rx90sym.files.read_json) for fit, gains and parameter files: the file, the
    line and the column of the fault in the message."""
    import rx90sym
    from identify.io.gains import read_gains
    bad = tmp_path / "broken.json"
    bad.write_text('{"parameters": [\n  1, 2,\n]}\n')
    for read in (identify.load_fit, lambda p: read_gains(p, rx90sym.load_robot("rx90"))):
        with pytest.raises(ValueError, match=r"broken\.json: not valid JSON \(line 3, column 1"):
            read(bad)
