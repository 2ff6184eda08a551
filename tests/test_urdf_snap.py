"""URDFs as makers write them (issue 29): joint origins snapped, a rank that depends on the
threshold flagged, the tolerances on the command line and in the fit file."""
from __future__ import annotations

import json
import math
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import identify
import rx90sym
from identify.app.report.identify_page import identify_summary
from identify.io.recordings import recording_from_arrays, write_recording
from rx90sym.near_dependent_columns import GAP_TOP, rank_gap
from rx90sym.urdf_export import urdf_export
from rx90sym.urdf_snap import SNAP_RAD, nearest_axis_aligned, snap_origin

from motions import multisine
from test_urdf import _max_torque_error, _pin_q, _pinocchio_chain, _rigid

Q = repr(math.pi / 2)  # how a generated URDF writes pi/2
MIXED = "-2.7549"      # the maker's mixed rpy: pi/2 and a joint-zero turn


def _twins(tmp_path: Path) -> tuple[Path, Path]:
    """A UR10e URDF (generated from the bundled robot file, its nominal inertials) with a mixed
    rpy on wrist_2, and its twin as a maker writes it: 1.5708, a mixed 1.5708 -2.7549, -1.57,
    and 1e-6 m residues."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = rx90sym.load_robot("ur10e")
        text, _ = urdf_export(robot, rx90sym.nominal_parameters(robot), tmp_path / "x.urdf")
    edits = [(f'xyz="0 -0.11985 7.338695943890514e-18" rpy="{Q} 0 0"', f'xyz="0 -0.11985 0" rpy="{Q} {MIXED} 0"')]
    exact = _edited(text, edits)
    rounded = _edited(exact, [(f'xyz="0 0 0" rpy="{Q} 0 0"', 'xyz="0 1e-06 0" rpy="1.5708 0 0"'),
                              (f'rpy="{Q} {MIXED} 0"', f'rpy="1.5708 {MIXED} 0"'),
                              (f'rpy="-{Q} 0 0"', 'rpy="-1.57 0 0"'),
                              ('xyz="-0.6127 0 0"', 'xyz="-0.6127 0 -1e-06"')])
    (tmp_path / "exact.urdf").write_text(exact)
    (tmp_path / "rounded.urdf").write_text(rounded)
    return tmp_path / "exact.urdf", tmp_path / "rounded.urdf"


def _edited(text: str, edits: list[tuple[str, str]]) -> str:
    for old, new in edits:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    return text


def _load(path: Path, **kw) -> tuple[rx90sym.Robot, list[str]]:
    """The robot and the loader's warnings (the acceleration one left out)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = rx90sym.load_robot(str(path), tip="flange", **kw)
    return robot, [str(w.message) for w in caught if "acceleration limits" not in str(w.message)]


# ------------------------------------------------------------------ one origin
def test_a_mixed_rpy_snaps_its_right_angle_exactly_and_keeps_the_other_angle():
    b = float(MIXED)
    used = snap_origin((1.5708, b, 0.0), (0.0, 1e-6, 0.2))
    Rx = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])                           # Rx(pi/2), by hand
    Ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1.0, 0], [-math.sin(b), 0, math.cos(b)]])
    assert np.array_equal(used.R, Ry @ Rx)                                        # exactly, not to 1e-16
    assert used.rpy == (math.pi / 2, b, 0.0) and used.xyz == (0.0, 0.0, 0.2) and used.rotated and used.moved
    # Pinocchio's rpy convention (independent): the written angles give the same rotation 3.7e-6 away
    gap = np.abs(pin.rpy.rpyToMatrix(1.5708, b, 0.0) - used.R).max()
    assert 1e-6 < gap < 1e-5


@pytest.mark.parametrize("written", [1.5708, 1.571, 1.57, -1.57, 3.14, 3.1416])
def test_right_angles_as_makers_write_them_are_caught_by_the_default(written):
    used = snap_origin((written, 0.0, 0.0), (0.0, 0.0, 0.0))
    k = round(written / (math.pi / 2))
    assert used.rpy[0] == k * math.pi / 2 and used.rotated
    assert np.array_equal(np.abs(used.R), np.abs(np.round(used.R)))   # entries exactly 0 or +-1


def test_a_deliberate_angle_and_snap_0_are_kept_as_written():
    off = math.pi / 2 + 3 * SNAP_RAD  # beyond the tolerance
    for rpy, kw in (((off, 0.0, 0.0), {}), ((1.5708, 0.0, 0.0), {"snap": 0.0})):
        used = snap_origin(rpy, (1e-6, 0.0, 0.0), **kw)
        assert used.rpy == rpy and not used.rotated
        np.testing.assert_allclose(used.R, pin.rpy.rpyToMatrix(*rpy), atol=1e-15)
    assert snap_origin((0.0, 0.0, 0.0), (1e-6, 0, 0), snap=0.0).xyz == (1e-6, 0.0, 0.0)  # lengths too


def test_a_gimbal_lock_rpy_of_a_right_angle_rotation_is_snapped_to_it():
    rpy = (0.3, 1.5708, 0.3)  # = Ry(pi/2) to 3.7e-6: its roll and yaw are not right angles
    used = snap_origin(rpy, (0, 0, 0))
    A, angle = nearest_axis_aligned(pin.rpy.rpyToMatrix(*rpy))
    assert angle < 1e-5 and np.array_equal(used.R, A) and used.rotated
    np.testing.assert_allclose(pin.rpy.rpyToMatrix(*used.rpy), A, atol=1e-15)


# ------------------------------------------------------------------ the twin robot
def test_a_twin_written_as_makers_do_gives_the_exact_files_model_and_says_what_it_changed(tmp_path):
    exact_path, rounded_path = _twins(tmp_path)
    exact, quiet = _load(exact_path)
    rounded, said = _load(rounded_path)
    assert quiet == []  # pi/2 written with 17 digits and 7e-18 m residues: round-off, not listed
    assert len(said) == 1
    for joint in ("'shoulder_lift_joint': rpy 1.5708 0 0 -> pi/2 0 0, xyz 0 1e-06 0 -> 0 0 0",
                  "'elbow_joint': xyz -0.6127 0 -1e-06 -> -0.6127 0 0",
                  f"'wrist_2_joint': rpy 1.5708 {MIXED} 0 -> pi/2 {MIXED} 0", "'wrist_3_joint': rpy -1.57 0 0 -> -pi/2"):
        assert joint in said[0]
    for field in ("alpha", "d", "theta", "r"):
        assert getattr(rounded, field) == getattr(exact, field)
    be, br = rx90sym.base_parameters(exact), rx90sym.base_parameters(rounded)
    assert be.names == br.names and be.nb == 52
    np.testing.assert_array_equal(be.K, br.K)
    chi = _rigid(rounded, rounded.parameter_vector(rx90sym.urdf_parameters(rounded)))
    # the snapped model is the exact file's, to Pinocchio's round-off (and 3.7e-6 off the file as written)
    assert _max_torque_error(rounded, chi, _pinocchio_chain(exact_path, rounded), 0) < 1e-9
    assert _max_torque_error(rounded, chi, _pinocchio_chain(rounded_path, rounded), 0) > 1e-7
    assert rounded.urdf.snap == SNAP_RAD and rounded.urdf.snap_length == 1e-5


def test_snap_0_keeps_the_file_as_written_and_its_model_is_near_singular(tmp_path):
    _, rounded_path = _twins(tmp_path)
    raw, said = _load(rounded_path, snap=0)
    assert len(said) == 1 and "snapping off" in said[0] and "wrist_2_joint" in said[0]
    chi = _rigid(raw, raw.parameter_vector(rx90sym.urdf_parameters(raw)))
    # the tilted axes are modelled right: Pinocchio on the file as written
    assert _max_torque_error(raw, chi, _pinocchio_chain(rounded_path, raw), 1) < 1e-9
    gap = rank_gap(rx90sym.base_parameters(raw))
    assert rx90sym.base_parameters(raw).nb == 53
    assert gap is not None and gap.columns == ("ZZ2R", "IA2") and gap.joints == (2,)
    assert max(gap.gap) < 1e-4 < 1e-2 < gap.signal  # measured 1.7e-6 against 0.13


@pytest.mark.parametrize("name", [*rx90sym.bundled_robots()])
def test_sound_models_have_no_rank_gap(name):
    assert rank_gap(rx90sym.base_parameters(rx90sym.load_robot(name, offsets=True))) is None
    assert GAP_TOP <= 1e-2  # measured: the smallest relative singular value of a sound model is 0.13


def test_bad_tolerances_are_refused_naming_them(tmp_path):
    exact_path, _ = _twins(tmp_path)
    for kw, words in (({"snap": -1e-3}, "snap = -0.001 rad is outside"), ({"snap": 0.02}, "outside [0, 0.01]"),
                      ({"snap_length": -1.0}, "snap_length = -1 m"), ({"snap": float("nan")}, "finite"),
                      ({"snap": 0.0, "snap_length": 1e-4}, "snap=0 turns snapping off")):
        with pytest.raises(ValueError, match=words.replace("[", r"\[").replace("(", r"\(")):
            _load(exact_path, **kw)
    with pytest.raises(rx90sym.RobotFileError, match="for a URDF"):
        rx90sym.load_robot("ur10e", snap=0.001)


# ------------------------------------------------------------------ the fit
def _pinocchio_recording(path: Path, robot: rx90sym.Robot, seed: int):
    """A motion of the exact URDF's robot, torques by Pinocchio's RNEA on that file plus noise."""
    model = _pinocchio_chain(path, robot)
    data = model.createData()
    t = np.arange(0, 12, 1 / 200)
    q, qd, qdd = multisine(robot, seed, 12)(t)
    tau = np.array([pin.rnea(model, data, _pin_q(model, a), b, c) for a, b, c in zip(q, qd, qdd)])
    tau += np.random.default_rng(seed).normal(0, 0.05, tau.shape)
    return recording_from_arrays(t, q, tau, robot)


def _fit(robot, rec):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify.fit(robot, [rec], identify.Processing(cutoff=10.0, estimate_delay=False, cross_validate=False,
                                                              friction="coulomb", rest="drop"))


def test_the_twin_as_written_fits_like_the_exact_file_and_with_snap_0_carries_the_rank_error(tmp_path):
    exact_path, rounded_path = _twins(tmp_path)
    exact, _ = _load(exact_path)
    rounded, _ = _load(rounded_path)
    raw, _ = _load(rounded_path, snap=0)
    rec = _pinocchio_recording(exact_path, exact, 3)
    fe, fr = _fit(exact, rec), _fit(rounded, rec)
    assert fe.result.names == fr.result.names == fe.base.names and len(fe.result.names) == 52
    np.testing.assert_allclose(fr.result.values, fe.result.values, rtol=1e-9, atol=1e-9)
    assert fe.flags == () and fr.flags == ()
    fz = _fit(raw, rec)  # the file as written: near-singular, fitted, never silent
    [flag] = [f for f in fz.flags if f.code == "rank_threshold"]
    assert flag.severity == "error" and "ZZ2R, IA2" in flag.message and "joint 2" in flag.message
    assert "1.7e-06" in flag.message or "1.8e-06" in flag.message  # the gap, measured 1.75e-6
    path = fz.save(tmp_path / "fit.json")
    record = fz.to_json()
    assert record["model"]["snap_rad"] == 0 and record["model"]["snap_length_m"] == 0
    summary = identify_summary(record)
    assert summary.headline.startswith("Do not trust")
    text = " ".join(f"{f['message']} {f['action']}" for f in summary.flags)
    assert "rank depends on the rank threshold" in text and "excites some parameters little" not in text
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        back = identify.load_fit(path)  # the robot rebuilt with the tolerances it was fitted with
    assert back.robot.urdf.snap == 0 and back.base.names == fz.base.names
    assert [f.code for f in back.flags] == ["rank_threshold"]
    # a file written before the tolerances were recorded: its URDF rebuilt as it was then read
    old = json.loads(path.read_text())
    del old["model"]["snap_rad"], old["model"]["snap_length_m"]
    (tmp_path / "old.json").write_text(json.dumps(old))
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        legacy = identify.load_fit(tmp_path / "old.json")
    assert legacy.robot.alpha == raw.alpha != rounded.alpha and legacy.base.names == fz.base.names


# ------------------------------------------------------------------ command line
def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "identify.app.cli", *args], capture_output=True, text=True,
                          timeout=300)


def _main(capsys: pytest.CaptureFixture, *args: str) -> tuple[int, str, str]:
    """rx90 in this process: exit code, stdout, stderr (argparse's refusals exit too)."""
    from identify.app.cli import main

    with warnings.catch_warnings():
        warnings.simplefilter("always")  # printed by rx90 as "[rx90] warning: ...", not raised
        try:
            code = main(list(args))
        except SystemExit as exc:
            code = exc.code
    out = capsys.readouterr()
    return code, out.out, out.err


def test_bad_snap_values_exit_2_with_the_reason_and_write_nothing(tmp_path, capsys):
    exact_path, _ = _twins(tmp_path)
    out = tmp_path / "model.json"
    base = ["model", "--robot", str(exact_path), "--tip", "flange", "--json", str(out)]
    for extra, words in ((["--snap", "-0.001"], "outside [0, 0.01] rad"), (["--snap", "0.02"], "outside [0, 0.01]"),
                         (["--snap", "abc"], "expected a number"), (["--snap-length", "-1e-6"], "outside [0, 0.001] m"),
                         (["--snap", "0", "--snap-length", "1e-4"], "--snap 0 turns snapping off")):
        code, _, err = _main(capsys, *base, *extra)
        assert code == 2 and words in err, (extra, err)
        assert not out.exists()
    code, _, err = _main(capsys, "model", "--robot", "ur10e", "--snap", "0.001", "--json", str(out))
    assert code == 2 and "for a URDF --robot" in err and not out.exists()


def test_the_command_line_prints_the_changes_once_and_snap_0_keeps_the_file(tmp_path, capsys):
    _, rounded_path = _twins(tmp_path)
    base = ["model", "--robot", str(rounded_path), "--tip", "flange", "--acceleration", "5"]
    code, out, err = _main(capsys, *base)
    assert code == 0 and err.count("joint origin(s) snapped") == 1, err
    assert "'wrist_3_joint': rpy -1.57 0 0 -> -pi/2 0 0" in err
    assert " 90 " in out.splitlines()[3]  # joint 2's alpha, degrees: exactly 90
    code, out, err = _main(capsys, *base, "--snap", "0")
    assert code == 0 and "snapping off" in err and "90.0002" in out
    code, out, err = _main(capsys, *base, "--snap", "1e-4")  # 1.5708 (3.7e-6 off) snapped, -1.57 (8e-4) kept
    assert code == 0 and "'shoulder_lift_joint'" in err and "'wrist_3_joint'" not in err


@pytest.mark.slow
def test_rx90_identify_with_snap_0_fits_the_near_singular_model_with_the_error_everywhere(tmp_path):
    exact_path, rounded_path = _twins(tmp_path)
    exact, _ = _load(exact_path)
    write_recording(tmp_path / "run.csv", _pinocchio_recording(exact_path, exact, 3), exact, convention="khalil")
    fit, report = tmp_path / "fit.json", tmp_path / "report.html"
    done = _cli("identify", str(tmp_path / "run.csv"), "--robot", str(rounded_path), "--tip", "flange",
                "--acceleration", "5", "--cutoff", "10", "--snap", "0", "--json", str(fit), "--report", str(report))
    assert done.returncode == 0, done.stderr
    assert done.stderr.count("snapping off") == 1
    assert "[rx90] error: the base-parameter regressor's rank depends on the rank threshold" in done.stderr
    assert "flag [rank_threshold]" in done.stdout and "columns ZZ2R, IA2 of joint 2" in done.stdout
    record = json.loads(fit.read_text())
    assert [f["code"] for f in record["flags"] if f["severity"] == "error"] == ["rank_threshold"]
    assert record["model"]["snap_rad"] == 0.0 and len(record["parameters"]) == 53
    page = report.read_text()
    assert "Do not trust this model yet" in page and "rank depends on the rank threshold" in page
    assert "excites some parameters little" not in page
