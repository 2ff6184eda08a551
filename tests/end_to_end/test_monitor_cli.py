"""``rx90 monitor`` and the thresholds ``rx90 identify`` stores (identify.monitor)."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import rx90sym
from identify import load_fit
from identify.app import cli
from identify.io.recordings import write_recording
from identify.monitor.log import calibrate, monitor_log
from monitor_twin import pulses, twin_run, with_external
from rx90sym.recording import Recording


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A twin fit by ``rx90 identify`` (fixed processing) with its stored thresholds, a held-out run, and
    a run with pulses, as files."""
    d = tmp_path_factory.mktemp("monitor")
    robot = rx90sym.load_robot("rx90")
    fitted, held, probe = (twin_run("rx90", s, "realistic", 12.0) for s in (100, 101, 102))
    ext, plist = pulses(robot, probe.t, seed=4)
    for name, rec in (("fit.csv", fitted), ("held.csv", held), ("pulses.csv", with_external(probe, ext))):
        write_recording(d / name, rec, robot)
    code = cli.main(["identify", str(d / "fit.csv"), "--robot", "rx90", "--cutoff", "10", "--friction", "coulomb",
                     "--rest", "zero-coulomb", "--validate", str(d / "held.csv"), "--json", str(d / "fit.json")])
    assert code == 0
    return d, plist


def test_identify_stores_thresholds_from_the_held_out_run(files):
    """contact_thresholds_nm of the file are calibrate() on the held-out recording (recomputed here)."""
    d, _ = files
    f = load_fit(d / "fit.json")
    from identify.io.recordings import read_recording

    held = read_recording(d / "held.csv", f.robot)
    assert f.contact_thresholds is not None and np.all(f.contact_thresholds > 0)
    assert np.allclose(f.contact_thresholds, calibrate(f, [held]), rtol=1e-9)
    old = json.loads((d / "fit.json").read_text())
    old.pop("contact_thresholds_nm")
    (d / "old.json").write_text(json.dumps(old))
    assert load_fit(d / "old.json").contact_thresholds is None


def test_monitor_command_writes_events_residual_and_report(files, capsys):
    d, plist = files
    out = [str(d / x) for x in ("ev.json", "r.csv", "r.html")]
    assert cli.main(["monitor", str(d / "pulses.csv"), "--identification", str(d / "fit.json"), "--json", out[0],
                     "--out", out[1], "--report", out[2]]) == 0
    printed = capsys.readouterr().out
    record = json.loads(Path(out[0]).read_text())
    assert {"events", "thresholds_nm", "gain", "fit_sha256"} <= set(record)
    import hashlib

    assert record["fit_sha256"] == hashlib.sha256((d / "fit.json").read_bytes()).hexdigest()
    assert record["thresholds_nm"] == pytest.approx(load_fit(d / "fit.json").contact_thresholds.tolist())
    starts = [e["start_s"] for e in record["events"]]
    for s, e, j, A in plist:  # every pulse: an event on its joint starting within 50 ms
        assert any(abs(x["start_s"] - s) < 0.05 and j + 1 in x["joints"] for x in record["events"]), (s, j, A, starts)
    assert f"{len(record['events'])} contact event(s)" in printed
    table = np.loadtxt(out[1], delimiter=",", skiprows=1)
    assert table.shape == (twin_run("rx90", 102, "realistic", 12.0).n_samples, 1 + 6 + 6 + 1) and table[0, 0] == 0.0
    assert "Contact monitor" in Path(out[2]).read_text()


def test_old_fit_file_needs_calibrate(files, capsys):
    d, _ = files
    args = ["monitor", str(d / "pulses.csv"), "--identification", str(d / "old.json")]
    assert cli.main(args) == 2
    assert "--calibrate" in capsys.readouterr().err
    assert cli.main(args + ["--calibrate", str(d / "held.csv"), "--json", str(d / "c.json")]) == 0
    new = json.loads((d / "c.json").read_text())["thresholds_nm"]
    assert new == pytest.approx(load_fit(d / "fit.json").contact_thresholds.tolist(), rel=1e-9)


def test_bad_input_exits_2_and_writes_nothing(files, capsys, tmp_path):
    d, _ = files
    robot = rx90sym.load_robot("rx90")
    rec = twin_run("rx90", 102, "realistic", 12.0)
    tx40 = rx90sym.load_robot("tx40")
    write_recording(tmp_path / "tx40.csv", Recording(t=rec.t, q=rec.q, tau=rec.tau, source="x", robot="tx40"), tx40)
    write_recording(tmp_path / "short.csv", Recording(t=rec.t[:2], q=rec.q[:2], tau=rec.tau[:2], source="s",
                                                      robot="rx90"), robot)
    fit = json.loads((d / "fit.json").read_text())
    for par in fit["parameters"]:
        if par["name"].startswith(("FS", "FV")):
            par["value"] = 0.0
    (tmp_path / "nofriction.json").write_text(json.dumps(fit))
    cases = [(tmp_path / "tx40.csv", d / "fit.json", "tx40"), (tmp_path / "short.csv", d / "fit.json", "short.csv"),
             (d / "pulses.csv", tmp_path / "nofriction.json", "no friction terms")]
    for recording, ident, words in cases:
        out = tmp_path / "ev.json"
        code = cli.main(["monitor", str(recording), "--identification", str(ident), "--json", str(out),
                         "--out", str(tmp_path / "r.csv")])
        err = capsys.readouterr().err
        assert code == 2 and words in err, (recording, err)
        assert not out.exists() and not (tmp_path / "r.csv").exists() and not list(tmp_path.glob("*.part"))
    # In memory (no reader's check): without velocities, fewer than 3 samples cannot be differentiated.
    from identify.monitor.log import MonitorInputError

    with pytest.raises(MonitorInputError, match="3 are needed"):
        monitor_log(load_fit(d / "fit.json"), Recording(t=rec.t[:2], q=rec.q[:2], tau=rec.tau[:2], source="s",
                                                        robot="rx90"), 1.0)


def test_command_module_imports_nothing_heavy():
    path = Path(cli.__file__).parent / "commands" / "monitor.py"
    code = (f"import importlib.util, sys\nspec = importlib.util.spec_from_file_location('m', {str(path)!r})\n"
            "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m)\n"
            "print([x for x in ('numpy', 'scipy', 'casadi', 'rx90sym', 'identify') if x in sys.modules])")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"


def test_a_held_out_run_at_rest_stores_no_zero_threshold(files, monkeypatch):
    """A validation recording where the arm holds still (the UR10e p4 run) leaves the residual within the
    friction slack: a threshold of 0 N·m would flag every sample; the fit keeps none and says why."""
    import identify.monitor.thresholds as thresholds

    d, _ = files
    f = load_fit(d / "fit.json")
    still = np.r_[0.0, np.ones(f.robot.n - 1)]
    monkeypatch.setattr(thresholds, "calibrate", lambda fit, recs, *a, **k: still)
    kept, why = thresholds.with_contact_thresholds(f, [d / "fit.csv"], d / "held.csv")
    assert kept is f and "joint(s) 1" in why and "held.csv" in why, why
    monkeypatch.setattr(thresholds, "calibrate", lambda fit, recs, *a, **k: still + 1.0)
    kept, why = thresholds.with_contact_thresholds(f, [d / "fit.csv"], d / "held.csv")
    assert why == "" and np.allclose(kept.contact_thresholds, still + 1.0)
