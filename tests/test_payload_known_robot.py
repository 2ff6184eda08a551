"""Payload method 1 with the robot's fit made with the defaults of rx90 identify (issue 38 item 1): its
identified model (with its torque offsets) and its processing are those of eq. 22's known part, in the library (a Fit, its file, its result) and in ``rx90 payload --method 1
--robot-params FIT.json``, with the same numbers; a fit of another robot, or one processed otherwise
than ``--filtering-from``, is refused (exit 2, nothing written).

Truth: the RX90 twin carrying the payload of Table 4, its joint torques with constant offsets on
joints 2 and 3 (as a real drive's): without the offsets the known part is wrong by them.
"""
from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

import identify
import rx90sym
from identify.app.cli import main

from motions import multisine

OFFSETS = np.array([0.0, 3.0, -2.0, 0.0, 0.0, 0.0])  # N·m
DURATION = 10.0


def _with_offsets(rec):
    return replace(rec, tau=rec.tau + OFFSETS)


@pytest.fixture(scope="module")
def folder(rx90, tmp_path_factory):
    """An empty run and a loaded run of another motion (loaded.csv)."""
    d = tmp_path_factory.mktemp("known_robot")
    sim = rx90sym.twin.simulate
    empty = _with_offsets(sim(rx90, multisine(rx90, 7, duration=DURATION), duration=DURATION, seed=7,
                              noise="quantised"))
    loaded = _with_offsets(sim(rx90, multisine(rx90, 8, duration=DURATION), duration=DURATION, seed=8,
                               noise="quantised", payload="tables_4"))
    identify.write_recording(d / "loaded.csv", loaded, rx90)
    return d, empty


@pytest.mark.slow
def test_method_1_takes_a_defaults_fit_as_the_command_does(rx90, folder, capsys):
    d, empty = folder
    fit = identify.fit(rx90, [empty])  # the defaults of rx90 identify: the processing cross-validated
    fit.save(d / "fit.json")
    assert {"OFF2", "OFF3"} <= set(fit.result.names)  # the defaults chose the offsets (not the robot's own base)
    loaded = str(d / "loaded.csv")
    by_fit = identify.payload(rx90, 1, loaded=[loaded], robot_params=fit)
    by_file = identify.payload(rx90, 1, loaded=[loaded], robot_params=d / "fit.json")
    assert main(["payload", "--method", "1", "--loaded", loaded, "--robot-params", str(d / "fit.json"),
                 "--json", str(d / "p1.json")]) == 0
    cmd = {p["name"]: p for p in json.loads((d / "p1.json").read_text())["payload"]}
    for res in (by_fit, by_file):
        np.testing.assert_allclose(res.values, [cmd[n]["value"] for n in res.names], rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(res.std, [cmd[n]["std"] for n in res.names], rtol=1e-9)
        np.testing.assert_allclose(res.bootstrap_std, [cmd[n]["bootstrap_std"] for n in res.names], rtol=1e-9)
    # The identified model's result with the fit's processing given: the same (a result brings values and offsets,
    # no processing; what a Fit brings is its identified model).
    by_result = identify.payload(rx90, 1, loaded=[loaded], robot_params=fit.model_result, **fit.filtering())
    if (fit.model.friction or {}).get("form", "coulomb") == "coulomb":
        np.testing.assert_allclose(by_result.values, by_fit.values, rtol=1e-9, atol=1e-12)
    # Against the truth: the payload of Table 4.
    truth = rx90sym.load_payload("tables_4")
    assert abs(by_fit["Mc"] / truth["Mc"] - 1) < 0.01 and abs(by_fit["MZc"] / truth["MZc"] - 1) < 0.05
    # A processing option that contradicts the fit's is refused, naming both.
    with pytest.raises(ValueError, match="cutoff=7.0 given, but the fit given as robot_params was made with"):
        identify.payload(rx90, 1, loaded=[loaded], robot_params=fit, cutoff=7.0)


def test_method_1_refuses_another_robots_fit_and_another_processing(rx90, folder, tmp_path, capsys):
    d, empty = folder
    identify.fit(rx90, [empty], identify.Processing(cutoff=12.0, estimate_delay=False), bootstrap_seed=None
                 ).save(tmp_path / "own.json")
    tx40 = rx90sym.load_robot("tx40")
    run = rx90sym.twin.simulate(tx40, multisine(tx40, 1, duration=4.0), duration=4.0, seed=1, noise="quantised")
    identify.fit(tx40, [run], identify.Processing(cutoff=10.0, estimate_delay=False), bootstrap_seed=None
                 ).save(tmp_path / "tx40.json")
    other = identify.fit(rx90, [identify.read_recording(d / "loaded.csv", rx90)],
                         identify.Processing(cutoff=7.0, estimate_delay=False), bootstrap_seed=None)
    other.save(tmp_path / "other.json")
    out = tmp_path / "p.json"
    base = ["payload", "--method", "1", "--robot", "rx90", "--loaded", str(d / "loaded.csv"), "--json", str(out)]
    assert main([*base, "--robot-params", str(tmp_path / "tx40.json")]) == 2
    assert "a fit of robot 'tx40' (6 joints), the payload runs are of 'rx90'" in capsys.readouterr().err
    assert main([*base, "--robot-params", str(tmp_path / "own.json"), "--filtering-from", str(tmp_path / "other.json")]) == 2
    err = capsys.readouterr().err
    assert "conflicting options: --filtering-from" in err and "cutoff 7.0" in err and not out.exists()
    with pytest.raises(ValueError, match="a fit of robot 'tx40'"):
        identify.payload(rx90, 1, loaded=[str(d / "loaded.csv")], robot_params=tmp_path / "tx40.json")
