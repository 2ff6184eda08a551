"""The rollout validation (identify.rollout): the exported MJCF in MuJoCo from the recorded state at each
window start under the recorded torques, scored at the window's end.

Twins with known truth: on a UR10e twin with the realistic noise the true model's MJCF ends near the
recorded positions (far nearer than the constant-velocity guess), the identified model near the true
one, a model without friction far from both; on exact torques the error falls to the integration's and
MuJoCo's friction floor, and only with the right delay, gains and spring. Margins measured over ten
seeds (docs/rollout.md "On the twin"); the fixtures use seed 0.
"""
from __future__ import annotations

import json
import warnings
from dataclasses import replace

import numpy as np
import pytest

import rx90sym
import identify
from identify.app.cli import main
from identify.io.gains import DriveGains
from identify.io.recordings import write_recording
from identify.rollout.model import simulator_model
from identify.rollout.run import roll_out, roll_out_fit

from conftest import robot_file_without
from motions import multisine

pytest.importorskip("mujoco", reason="the rollout needs the mujoco extra (pip install '.[mujoco]')")

RATE = 500.0  # Hz: a UR e-Series log's rate
#: The realistic profile with the plant's Coulomb friction as smooth as tests/twin_logs.py's (its 0.002
#: rad/s is too steep for the 4 kHz servo step on the UR10e's wrist: the twin refuses it).
REALISTIC = replace(rx90sym.twin.profiles()["realistic"], coulomb_smoothing=0.006)


def _without_friction(params: dict) -> dict:
    return {k: (0.0 if k[:2] in ("FS", "FV") else v) for k, v in params.items()}


@pytest.fixture(scope="module")
def realistic():
    """A 6 s UR10e twin (its [nominal] parameters as truth, realistic noise, seed 0) and its consistent fit."""
    robot = rx90sym.load_robot("ur10e")
    truth = rx90sym.nominal_parameters(robot)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the ripple's assumed gear ratio (the UR10e file gives none)
        rec = rx90sym.twin.simulate(robot, multisine(robot, 0, 6.0), truth, noise=REALISTIC, seed=0, rate=RATE,
                                    duration=6.0)
    return robot, truth, rec, identify.fit(robot, [rec], method="consistent")


@pytest.fixture(scope="module")
def exact():
    """A 4 s UR10e twin on its reference with exact torques (noise "ideal")."""
    robot = rx90sym.load_robot("ur10e")
    truth = rx90sym.nominal_parameters(robot)
    return robot, truth, rx90sym.twin.simulate(robot, multisine(robot, 0, 4.0), truth, noise="ideal", rate=RATE,
                                               duration=4.0)


def test_the_true_model_rolls_out_near_the_robot_and_the_identified_near_it(realistic):
    """Over ten seeds: true/guess (norm over the joints) at most 0.14 (0.25 s), 0.09 (0.5 s); identified/true
    per joint 0.63-1.75 and 0.33-2.0, in norm 0.80-1.28 and 0.69-1.37."""
    robot, truth, rec, fit = realistic
    ident = roll_out_fit(fit, rec, "0.25,0.5", nominal=False)
    true = roll_out(robot, truth, rec, (0.25, 0.5), cutoff=fit.cutoff, delay=fit.delay, min_velocity=fit.min_velocity,
                    nominal=False)
    for w_id, w_true in zip(ident.windows, true.windows):
        assert w_id.windows == w_true.windows >= 10
        e_true, e_id, e_guess = w_true.rms("identified"), w_id.rms("identified"), w_true.rms("guess")
        assert np.linalg.norm(e_true) <= 0.25 * np.linalg.norm(e_guess), (w_true.asked_s, e_true, e_guess)
        assert np.all(e_id <= 2.5 * e_true), (w_true.asked_s, e_id / e_true)
        assert np.linalg.norm(e_id) <= 1.6 * np.linalg.norm(e_true)


def test_a_model_without_friction_drifts(realistic):
    """The friction export matters: without Coulomb and viscous friction every joint ends at least 33
    times farther (ten seeds, 0.25 s)."""
    robot, truth, rec, fit = realistic
    options = dict(cutoff=fit.cutoff, min_velocity=fit.min_velocity, nominal=False)
    true = roll_out(robot, truth, rec, 0.25, **options).windows[0].rms("identified")
    bare = roll_out(robot, _without_friction(truth), rec, 0.25, **options).windows[0].rms("identified")
    assert np.all(bare >= 10 * true), bare / true


def test_exact_torques_roll_out_to_the_floor_only_with_the_right_delay_gains_and_block(exact):
    """Exact torques: the true model ends within 0.16-0.54 mrad after 0.25 s (MuJoCo's step and its dry
    friction constraint); torques logged 10 ms late are put back by the delay, not by its opposite; motor
    currents through their gains and any block give the same windows."""
    robot, truth, rec = exact
    options = dict(cutoff=20.0, nominal=False)
    floor = roll_out(robot, truth, rec, 0.25, **options).windows[0]
    assert floor.windows >= 10 and np.all(floor.rms("identified") <= 1e-3)
    assert np.all(floor.rms("guess") >= 20 * floor.rms("identified"))
    late = replace(rec, tau=np.column_stack([np.interp(rec.t - 0.01, rec.t, rec.tau[:, j]) for j in range(robot.n)]))
    put_back = roll_out(robot, truth, late, 0.25, delay=0.01, **options).windows[0].rms("identified")
    ignored = roll_out(robot, truth, late, 0.25, **options).windows[0].rms("identified")
    reversed_ = roll_out(robot, truth, late, 0.25, delay=-0.01, **options).windows[0].rms("identified")
    np.testing.assert_allclose(put_back, floor.rms("identified"), rtol=0.2)
    assert np.all(ignored >= 5 * put_back) and np.all(reversed_ >= 1.5 * ignored)
    gains = np.array([10.0, 10.7, 8.46, 9.0, 9.48, 10.12])
    currents = replace(rec, tau=None, current=rec.tau / gains)
    through = roll_out(robot, truth, currents, 0.25, gains=DriveGains(gains, side="joint"), **options).windows[0]
    blocks = roll_out(robot, truth, rec, 0.25, block=1000, **options).windows[0]
    for other in (through, blocks):
        np.testing.assert_allclose(other.position["identified"], floor.position["identified"], rtol=0, atol=1e-9)


def test_the_spring_and_the_coupled_wrist_are_applied_from_the_fit():
    """RX90 (spring on joint 2, wrist coupled with the paper's Coulomb form), exact torques: the true model
    ends within 0.3-3.4 mrad after 0.25 s; without the spring joint 2 ends 70 mrad off, with the tendon's
    frictionloss (q̇5 + q̇6) in place of eqs. 17-18 joints 5 and 6 end 27 and 60 mrad off."""
    robot = rx90sym.load_robot("rx90")
    truth = dict(rx90sym.twin.default_parameters(robot))
    rec = rx90sym.twin.simulate(robot, multisine(robot, 0, 4.0), truth, noise="ideal", rate=RATE, duration=4.0)
    out = roll_out(robot, truth, rec, 0.25, cutoff=20.0, nominal=False)
    e = out.windows[0].rms("identified")
    assert np.all(e <= 6e-3), e
    terms = " ".join(out.terms["identified"])
    assert "spring of joint 2" in terms and "FSM6 sign(q'6) on joint 5" in terms
    no_spring = roll_out(robot.with_options(spring=None), truth, rec, 0.25, cutoff=20.0, nominal=False)
    assert no_spring.windows[0].rms("identified")[1] >= 10 * e[1]


def test_a_smooth_friction_form_replaces_the_joints_frictionloss():
    robot = rx90sym.load_robot("ur10e")
    truth = rx90sym.nominal_parameters(robot)
    record = {"form": ["tanh", "coulomb", "coulomb", "coulomb", "coulomb", "coulomb"],
              "velocity_scale": [0.05, None, None, None, None, None]}
    sm = simulator_model(robot, truth, friction=record)
    assert sm.model.dof_frictionloss[0] == 0.0 and sm.model.dof_frictionloss[1] == truth["FS2"]
    force = sm.extra_force(np.zeros(robot.n), np.array([0.02, 0.3, 0, 0, 0, 0]))
    np.testing.assert_allclose(force, [-truth["FS1"] * np.tanh(0.02 / 0.05), 0, 0, 0, 0, 0], atol=1e-12)
    assert "joint 1: tanh friction" in " ".join(sm.terms)
    assert 0 < sm.max_step < np.inf   # explicit steps kept below the tanh's slope FS1/vs
    # Stribeck on joint 2 beside tanh on joint 1: the fit's own columns (friction_columns) times FS and FST.
    from identify.friction.forms import friction_columns

    record = {"form": ["tanh", "stribeck", "coulomb", "coulomb", "coulomb", "coulomb"],
              "velocity_scale": [0.05, 0.03, None, None, None, None]}
    sm = simulator_model(robot, truth, friction=record, extra={"FST2": 1.7 * truth["FS2"]})
    for v in (-0.3, -0.02, 0.0, 0.01, 0.2):
        qd = np.array([0.02, v, 0, 0, 0, 0])
        cols, _ = friction_columns("stribeck", np.array([v]), 0.03)
        expected = -(truth["FS2"] * cols[0, 0] + 1.7 * truth["FS2"] * cols[0, 1])
        np.testing.assert_allclose(sm.extra_force(np.zeros(robot.n), qd)[1], expected, rtol=1e-12, atol=1e-12)


def test_the_nominal_model_is_the_descriptions_bodies_and_absent_without_them(exact, tmp_path):
    robot, truth, rec = exact
    with_bodies = roll_out(robot, truth, rec, 0.25, cutoff=20.0)
    assert with_bodies.models == ("identified", "nominal")   # the truth IS the UR10e's [nominal]: same bodies
    np.testing.assert_allclose(with_bodies.windows[0].rms("nominal"), with_bodies.windows[0].rms("identified"),
                               rtol=1e-9)
    bare = rx90sym.load_robot(str(robot_file_without(tmp_path / "ur10e_bare.toml", "ur10e", "nominal")))
    without = roll_out(bare, truth, rec, 0.25, cutoff=20.0)
    assert without.models == ("identified",) and "no bodies" in without.nominal


@pytest.fixture(scope="module")
def files(realistic, tmp_path_factory):
    """The realistic twin as a recording file, its consistent fit and the same fit as a WLS one writes it."""
    robot, truth, rec, fit = realistic
    folder = tmp_path_factory.mktemp("rollout")
    write_recording(folder / "run.csv", rec, robot)
    fit.save(folder / "id.json")
    wls = json.loads((folder / "id.json").read_text())
    wls["method"] = "wls"
    for key in ("standard", "cost", "wls_cost", "cost_increase_pct", "wls_was_consistent"):
        wls.pop(key, None)
    (folder / "wls.json").write_text(json.dumps(wls))
    return folder


def test_rx90_predict_rollout_writes_the_librarys_figures_and_a_report(files, tmp_path):
    out_json, report = tmp_path / "pred.json", tmp_path / "pred.html"
    assert main(["predict", str(files / "run.csv"), "--identification", str(files / "id.json"), "--rollout",
                 "0.25,0.5", "--json", str(out_json), "--report", str(report)]) == 0
    got = json.loads(out_json.read_text())["rollout"]
    lib = roll_out_fit(identify.load_fit(files / "id.json"), files / "run.csv", (0.25, 0.5)).to_dict()
    assert got == json.loads(json.dumps(lib))
    assert [w["window_s"] for w in got["windows"]] == [0.25, 0.5] and got["models"] == ["identified", "nominal"]
    assert got["windows"][0]["windows_scored"] >= 10
    page = report.read_text()
    assert "fig-rollout" in page and "Rollout in MuJoCo" in page


def test_a_validation_with_a_rollout_is_in_the_fit_file_and_its_report(realistic):
    """identify --validate V --rollout: the fit file's validation holds the rollout, the report a section."""
    from identify.app.report.identify_page import identify_page

    robot, truth, rec, fit = realistic
    record = fit.validated(rec, rollout=0.25).to_json()
    rollout = record["validation"]["rollout"]
    assert rollout["windows"][0]["windows_scored"] >= 10 and rollout["models"] == ["identified", "nominal"]
    page = identify_page(record)
    section = next(s for s in page.sections if s.id == "rollout")
    assert any(getattr(b, "id", "") == "rollout-0" for b in section.blocks)
    # identify.predict rolls out a consistent result's bodies with the processing it is given: the same windows
    # (its positions differ where the fit's smooth friction form, applied from the fit, is not given)
    alone = identify.predict(robot, fit.result, rec, cutoff=fit.cutoff, min_velocity=fit.min_velocity, rollout=0.25)
    own = roll_out_fit(fit, rec, 0.25).windows[0]
    got = alone.rollout.windows[0]
    assert (got.windows, got.skipped_rest, got.skipped_bridged) == (own.windows, own.skipped_rest, own.skipped_bridged)
    np.testing.assert_array_equal(got.position["guess"], own.position["guess"])  # the same windows, the same guess


def test_a_window_where_mujoco_gives_up_is_counted_not_scored(exact, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # MuJoCo writes its warning to MUJOCO_LOG.TXT in the working folder
    robot, truth, rec = exact
    wild = replace(rec, tau=rec.tau * 1e300)
    w = roll_out(robot, truth, wild, 0.5, cutoff=20.0, nominal=False).windows[0]
    assert w.diverged["identified"] == w.windows > 0 and np.all(np.isnan(w.position["identified"]))
    assert np.all(w.beats_guess("identified") == 0)


@pytest.mark.parametrize("case, argv, message", [
    ("zero", ["--rollout", "0"], "duration > 0"),
    ("longer", ["--rollout", "0.25,30"], "longer than the recording"),
    ("no-bodies", ["--rollout", "0.25"], "holds base parameters only"),
    ("at-rest", ["--rollout", "0.25"], "no window of 0.25 s while the arm moves"),
])
def test_bad_rollouts_exit_2_with_the_reason_and_write_nothing(files, tmp_path, capsys, case, argv, message):
    recording, fit = files / "run.csv", files / "id.json"
    if case == "no-bodies":  # a fit file written before the identified model: the paper's estimates only
        record = json.loads((files / "wls.json").read_text())
        record.pop("identified")
        fit = tmp_path / "old.json"
        fit.write_text(json.dumps(record))
    if case == "at-rest":   # the twin's first 6 s held still: every window at rest
        robot, rec = rx90sym.load_robot("ur10e"), identify.read_recording(recording, rx90sym.load_robot("ur10e"))
        still = replace(rec, q=np.tile(rec.q[:1], (rec.n_samples, 1)))
        recording = tmp_path / "still.csv"
        write_recording(recording, still, robot)
    outputs = [tmp_path / "p.json", tmp_path / "p.html", tmp_path / "p.csv"]
    try:
        code = main(["predict", str(recording), "--identification", str(fit), *argv, "--json", str(outputs[0]),
                     "--report", str(outputs[1]), "--out", str(outputs[2])])
    except SystemExit as exc:  # refused by the option's parser
        code = exc.code
    assert code == 2
    assert message in capsys.readouterr().err
    assert not any(p.exists() for p in outputs)


def test_identify_rollout_needs_validate(files, capsys):
    assert main(["identify", str(files / "run.csv"), "--method", "consistent", "--rollout", "0.25"]) == 2
    assert "give --validate" in capsys.readouterr().err
