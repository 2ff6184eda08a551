"""The defaults never break on their own choices: short logs of ordinary motions fitted, never refused.

Panda twins of a few seconds (tests/short_twins.py): a joint moving one way only, a joint that never
moves, a torque channel not logged, a recording too short for the cross-validation's blocks, torques
logged beyond the delay search's bound; the columns the rows cannot separate are merged or left out and
named, the choice's table is carried by any error after it, the fit file says what was done.
"""
from __future__ import annotations

import json
import math
import warnings
from dataclasses import replace

import numpy as np
import pytest

import identify
from identify.app.cli import main
from identify.estimation.delay import refined_delay
from identify.estimation.dependent_columns import reduce_columns
from identify.fitting import passes
from identify.io.recordings import RecordingWarning
from identify.io.unlogged import constant_channels

from conftest import SHARED
from short_twins import short_twin


# --------------------------------------------------------------------------- columns the rows cannot separate

def test_reduce_columns_leaves_out_zero_columns_and_merges_dependent_ones():
    rng = np.random.default_rng(3)
    A = rng.normal(size=(200, 4))
    # columns: a, b, c, zero, -b (a one-way joint's Coulomb column against its offset), a + 2c, d
    W = np.column_stack([A[:, 0], A[:, 1], A[:, 2], np.zeros(200), -A[:, 1], A[:, 0] + 2 * A[:, 2], A[:, 3]])
    W[:, 1] *= 1e3  # units apart: the rank is judged on the column-scaled matrix
    W[:, 4] *= 1e3
    names = ["a", "b", "c", "z", "nb", "ac", "d"]
    y = W @ rng.normal(size=7) + 0.01 * rng.normal(size=200)
    red = reduce_columns(np.linalg.qr(W, mode="r"), names)
    assert red.zero == ("z",) and red.kept_names == ("a", "b", "c", "d")
    assert red.holds() == {"a": "a + ac", "b": "b - nb", "c": "c + 2·ac"}
    # The columns kept predict as the least-norm fit of every column (numpy, independent): nothing is lost.
    kept, *_ = np.linalg.lstsq(W[:, list(red.kept)], y, rcond=None)
    full, *_ = np.linalg.lstsq(W, y, rcond=None)
    assert np.allclose(W[:, list(red.kept)] @ kept, W @ full, rtol=0, atol=1e-9 * np.abs(y).max())


@pytest.fixture(scope="module")
def one_way_fit():
    """Joint 5 moves one way only, joint 7 never moves: the default fit (before: 'W is rank deficient ...
    FS5 (0.71), OFF5 (0.71)', the cross-validation having given joint 5 an offset)."""
    tw = short_twin(0, one_way=(4,), still=(6,))
    return tw, identify.fit(tw.robot, [tw.recording])


def test_a_one_way_joint_is_offered_no_offset_and_a_still_joint_loses_its_coulomb_term(one_way_fit):
    tw, f = one_way_fit
    assert f.choice["offsets_inseparable"] == [5] and 5 not in f.choice["offsets"]
    assert "no torque offset offered on joint(s) 5" in f.choice["table"]
    left = {fl.parameter: fl.message for fl in f.flags if fl.code == "column_left_out"}
    assert "FS7" in left and "joint 7 never moves" in left["FS7"] and "FS7" not in f.result.names


def test_the_robots_own_offsets_are_merged_with_a_one_way_coulomb_term_and_named(tmp_path):
    tw = short_twin(1, one_way=(4,), still=(6,), offsets=True)
    f = identify.fit(tw.robot, [tw.recording])
    merged = [fl for fl in f.flags if fl.code == "columns_merged"]
    assert [fl.parameter for fl in merged] == ["FS5"] and "OFF5" not in f.result.names
    assert "joint 5 moves one way only: its Coulomb term and offset are one column" in merged[0].message
    assert dict(f.result.holds) == {"FS5": "FS5 + OFF5"}
    # What it holds is the truth's sum, not FS5 alone (seeds 0-4: 0.012-0.105 N m from the sum, 0.57-1.23 N m
    # from FS5 alone).
    truth = tw.truth["FS5"] + tw.offsets[4]
    assert abs(f.result["FS5"] - truth) < min(0.15, 0.25 * abs(f.result["FS5"] - tw.truth["FS5"]))
    saved = json.loads(f.save(tmp_path / "fit.json").read_text())
    assert {p["name"]: p.get("holds") for p in saved["parameters"]}["FS5"] == "FS5 + OFF5"
    assert identify.load_fit(tmp_path / "fit.json").result.holds == (("FS5", "FS5 + OFF5"),)
    assert "holds FS5 + OFF5" in f.result.table()


# --------------------------------------------------------------------------- a torque channel not logged

def test_the_constant_rule_flags_one_value_and_not_a_live_sensor_at_rest():
    rng = np.random.default_rng(0)
    live = np.round(3.0 + 0.03 * rng.normal(size=(2000, 1)), 2)  # a joint at rest, 0.01 N m counts
    resampled = np.full((2000, 1), 1.7) * (1 + 1e-15 * rng.normal(size=(2000, 1)))  # one value, rounding
    x = np.hstack([live, np.zeros((2000, 1)), resampled])
    assert constant_channels(x.min(axis=0), x.max(axis=0)) == [1, 2]


@pytest.fixture(scope="module")
def not_logged_fit():
    """Joint 1's torque not logged (0 on every sample; before: 'no fold could be fitted and scored')."""
    tw = short_twin(2, not_logged=(0,))
    return tw, identify.fit(tw.robot, [tw.recording])


def test_a_torque_not_logged_leaves_its_joint_out_and_says_so(not_logged_fit, tmp_path):
    tw, f = not_logged_fit
    codes = {(fl.code, fl.parameter or fl.joint) for fl in f.flags}
    assert ("torque_not_logged", 1) in codes and ("column_left_out", "ZZ1R") in codes
    assert "ZZ1R" not in f.result.names and math.isnan(f.result.residual_rms[0]) and f.result.weights[0] == 0
    assert f.choice["chosen"]["per_joint_pct"][0] is None  # not scored in the choice
    assert f.model.torque_left_out == (1,)
    v = f.predict(tw.recording)
    assert v.not_predicted == (1,) and np.all(np.isnan(v.predicted[:, 0])) and "not predicted" in v.table()
    back = identify.load_fit(f.save(tmp_path / "fit.json"))
    assert back.predict(tw.recording).not_predicted == (1,)


def test_read_log_names_a_constant_torque_column(tmp_path):
    tw = short_twin(3, duration=2.0)
    rec, spec = tw.recording, "t,q1..q7,tau1..tau7"
    dead, live = tmp_path / "dead.csv", tmp_path / "live.csv"
    tau = rec.tau.copy()
    tau[:, 2] = 0.0  # joint 3's channel not logged
    for path, torques in ((dead, tau), (live, rec.tau)):
        np.savetxt(path, np.column_stack([rec.t, tw.robot.to_controller(rec.q), torques]), delimiter=",")
    with pytest.warns(RecordingWarning, match=r"tau3 in column 11 \(joint 3, 0 N·m\) holds one value"):
        identify.read_log(dead, tw.robot, columns=spec, header=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RecordingWarning)
        identify.read_log(live, tw.robot, columns=spec, header=False)


# --------------------------------------------------------------------------- a recording too short for the blocks

def test_a_recording_too_short_for_the_blocks_is_fitted_with_the_fixed_defaults(capsys, tmp_path):
    tw = short_twin(4, duration=1.2, one_way=range(7))  # every joint moving (no point-to-point move fits in 1.2 s)
    f = identify.fit(tw.robot, [tw.recording])
    why = f.choice["skipped"]
    assert why.startswith("the recording is 1.2 s long, too short for the cross-validation's 5 blocks")
    need = float(why.rsplit("about ", 1)[1].split(" s")[0])
    assert 1.2 < need < 4.0
    fixed = identify.fit(tw.robot, [tw.recording], identify.Processing(cross_validate=False))
    assert f.cutoff == fixed.cutoff and np.allclose(f.result.values, fixed.result.values, rtol=1e-12, atol=0)
    # The length said is enough: a recording that long is cross-validated.
    long_enough = short_twin(4, duration=math.ceil(10 * need) / 10, one_way=range(7))
    assert not identify.fit(long_enough.robot, [long_enough.recording]).choice["skipped"]
    path = tmp_path / "short.csv"
    identify.write_recording(path, tw.recording, tw.robot)
    assert main(["identify", str(path), "--robot", "panda"]) == 0
    assert "processing not cross-validated: the recording is 1.2 s long" in capsys.readouterr().out


# --------------------------------------------------------------------------- refusals after the choice

def test_an_error_after_the_choice_carries_its_table(capsys, tmp_path, monkeypatch):
    tw = short_twin(5)
    # Torques in mN m: the recorded-torque check refuses them once the processing is chosen.
    scaled = replace(tw.recording, tau=1e3 * tw.recording.tau)
    path = tmp_path / "mNm.csv"
    identify.write_recording(path, scaled, tw.robot)
    assert main(["identify", str(path), "--robot", "panda"]) == 2
    out, err = capsys.readouterr()
    assert "processing chosen by 5-block cross-validation" in out and "error:" in err
    # In the library, whatever stops the fit after the choice carries it (here the solve, made to fail).
    def failing(*args, **kwargs):
        raise ValueError("the solve fails")

    monkeypatch.setattr(passes, "solve_joint_systems", failing)
    with pytest.raises(ValueError, match="the solve fails") as info:
        identify.fit(tw.robot, [tw.recording])
    assert "processing chosen by 5-block cross-validation" in info.value.processing_choice.table()


# --------------------------------------------------------------------------- a delay at the search's bound

def test_a_delay_at_the_search_bound_is_not_found_and_not_applied():
    grid = np.linspace(-0.02, 0.02, 41)
    at_bound = refined_delay(grid, (grid + 0.03) ** 2, grid[1] - grid[0])
    inside = refined_delay(grid, (grid - 0.0061) ** 2, grid[1] - grid[0])
    assert not at_bound.found and at_bound.delay == 0.0 and at_bound.best == pytest.approx(-0.02)
    assert "not found" in at_bound.summary() and "not applied" in at_bound.summary()
    assert inside.found and inside.delay == pytest.approx(0.0061, abs=1e-4)


def test_torques_logged_beyond_the_bound_give_no_delay():
    auto = identify.Processing(delay="auto", cross_validate=False)  # the lag search alike with or without the choice
    tw = short_twin(6, lag=0.04)  # 40 ms: the search spans +-20 ms
    f = identify.fit(tw.robot, [tw.recording], auto)
    assert not f.delay_estimate.found and f.delay == 0.0 and f.delay_estimate_s is None
    lagged = short_twin(6, lag=0.01)
    g = identify.fit(lagged.robot, [lagged.recording], auto)
    # Within the bound: found and applied (10 ms, one sample at 100 Hz: 3.7-7.4 ms over seeds 6-9).
    assert g.delay_estimate.found and 0.002 < g.delay < 0.02


# --------------------------------------------------------------------------- the real Gen3 logs

GEN3 = SHARED / "data" / "kinova_gen3"
GEN3_COLUMNS = "_,q1..q7,qd1..qd7,_*7,{},_*7,_*7,{},_*28"  # Torque (computed) skipped; TorqueSm or Cur mapped


@pytest.mark.skipif(not (GEN3 / "RunTrajectory1.csv").exists(), reason=f"the Kinova Gen3 logs are not at {GEN3}")
@pytest.mark.filterwarnings("default")  # the command prints them (the URDF's inertials, snapped origins, limits)
def test_the_gen3_logs_are_converted_and_fitted(tmp_path, capsys):
    urdf = GEN3 / "gen3.urdf"  # as shipped: three inertials not physical, a prior the default fit does not use
    convert = ["convert", "--robot", str(urdf), "--period", "0.001"]
    # Sensor torques: joint 1's column holds 0 on every row (before: 'no fold could be fitted and scored').
    sensors = tmp_path / "run1.csv"
    assert main([*convert, str(GEN3 / "RunTrajectory1.csv"), "--columns", GEN3_COLUMNS.format("tau1..tau7", "_*7"),
                 "--out", str(sensors)]) == 0
    assert "tau1 in column 23 (joint 1, 0 N·m) holds one value on every row" in capsys.readouterr().err
    assert main(["identify", str(sensors), "--robot", str(urdf), "--json", str(tmp_path / "run1.json")]) == 0
    out, err = capsys.readouterr()
    fit = json.loads((tmp_path / "run1.json").read_text())
    assert fit["model"]["torque_left_out"] == [1] and "ZZ1R" not in {p["name"] for p in fit["parameters"]}
    assert "processing not cross-validated: the recording is 1.96 s long" in out
    # Nor the prior's weight: the description's bodies kept (λ = ∞), said where λ is.
    prior = fit["identified"]["prior"]
    assert prior["weight_label"] == "inf" and prior["choice"] is None
    assert "weight λ = inf (λ inf: not cross-validated, as the processing (the description kept))" in out
    # Exported, joint 1 (its torque not logged) is said not identified, on stderr and in the companion.
    assert main(["export", str(tmp_path / "run1.json"), "--mjcf", str(tmp_path / "gen3.xml")]) == 0
    assert "warning: joint 1: its torque was not in the fit (not logged)" in capsys.readouterr().err
    side = json.loads((tmp_path / "gen3.mjcf.actuation.json").read_text())
    assert [note[:8] for note in side["not_identified"]] == ["joint 1:"]
    # Currents of joint 2 alone (before: 'W is rank deficient: rank 56 < 66'): the still joints' columns left out.
    currents = tmp_path / "j2.csv"
    assert main([*convert, str(GEN3 / "joint_2_trapez.csv"), "--columns", GEN3_COLUMNS.format("_*7", "i1..i7"),
                 "--gains", "9.13,9.13,9.13,9.13,5.852,5.852,5.852", "--out", str(currents)]) == 0
    assert main(["identify", str(currents), "--robot", str(urdf), "--json", str(tmp_path / "j2.json")]) == 0
    left = {f["parameter"] for f in json.loads((tmp_path / "j2.json").read_text())["flags"]
            if f["code"] == "column_left_out"}
    assert {"FS1", "FS3", "FS4", "FS5", "FS6", "FS7"} <= left
