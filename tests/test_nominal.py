"""Nominal parameters for any robot, trajectory CSVs read back, rx90 simulate --params."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import excitation
import rx90sym

from conftest import random_chi, robot_file_without

RX90 = str(Path(sys.executable).parent / "rx90")


@pytest.fixture()
def own_rx90(tmp_path) -> Path:
    """A user's own copy of the RX90 file, still named "rx90", without a [nominal] table."""
    return robot_file_without(tmp_path / "rx90.toml", "rx90", "nominal")


def test_only_the_bundled_file_gets_the_twin_parameters(own_rx90):
    bundled = rx90sym.load_robot("rx90")
    twin = json.loads((Path(rx90sym.__file__).parent / "data" / "rx90_true_params.json").read_text())
    assert rx90sym.default_parameters(bundled) == pytest.approx(twin["parameters"], rel=0, abs=0)
    # The nominal parameters are the file's [nominal] table, not the twin's truth.
    assert rx90sym.nominal_parameters(bundled) != twin["parameters"]
    mine = rx90sym.load_robot(own_rx90)
    assert mine.name == "rx90"
    assert rx90sym.nominal_parameters(mine) is None
    with pytest.raises(ValueError, match="no default parameters for robot 'rx90'"):
        rx90sym.default_parameters(mine)


def test_parameter_file_layouts_round_trip(tmp_path, own_rx90):
    robot = rx90sym.load_robot(own_rx90)
    chi = random_chi(robot, np.random.default_rng(3))
    values = dict(zip(robot.parameter_names, chi.tolist()))
    layouts = {
        "flat.json": values,
        "twin.json": {"robot": "rx90", "parameters": values},
        # The JSON of rx90 identify --method consistent: base 'parameters' list plus 'standard'.
        "identify.json": {"robot": "rx90", "method": "consistent",
                          "parameters": [{"name": "ZZ1R", "value": 1.0}],
                          "standard": {**values, "OFF1": 0.5}},
    }
    for name, content in layouts.items():
        (tmp_path / name).write_text(json.dumps(content))
        got = rx90sym.nominal_parameters(robot, tmp_path / name)
        assert got == values, name


@pytest.mark.parametrize("content, needle", [
    ({"parameters": [{"name": "ZZ1R", "value": 1.0}]}, "holds base parameters"),
    ({"robot": "panda", "parameters": {}}, "field 'robot' is 'panda'"),
    ({"XX1": 1.0}, r"missing parameter\(s\) \['XY1'"),
])
def test_bad_parameter_file_names_the_problem(tmp_path, content, needle):
    robot = rx90sym.load_robot("rx90")
    path = tmp_path / "p.json"
    path.write_text(json.dumps(content))
    with pytest.raises(ValueError, match=needle):
        rx90sym.nominal_parameters(robot, path)
    path.write_text("{\n  \"XX1\": 1,\n}")
    with pytest.raises(ValueError, match="line 3"):
        rx90sym.nominal_parameters(robot, path)


def test_trajectory_csv_reads_back_its_samples(tmp_path):
    robot = rx90sym.load_robot("rx90")
    traj = excitation.random_trajectory(robot, 4.0, 3, seed=2)
    traj.save(tmp_path / "traj.csv", rate=100.0)
    t, q, qd, qdd = excitation.read_trajectory(tmp_path / "traj.csv", robot)
    t0, q0, qd0, qdd0 = traj.sample(100.0, closed=True)
    # The CSV holds 10 significant digits in controller angles.
    for a, b in ((t, t0), (q, q0), (qd, qd0), (qdd, qdd0)):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-8)


def test_simulate_any_robot_given_parameters(tmp_path, own_rx90):
    robot = rx90sym.load_robot(own_rx90)
    t = np.arange(0, 2.0, 1 / 250)
    q = 0.3 * np.sin(np.outer(t, np.arange(1, 7)) * 0.7)
    qd = 0.3 * 0.7 * np.arange(1, 7) * np.cos(np.outer(t, np.arange(1, 7)) * 0.7)
    qdd = -(0.7 * np.arange(1, 7)) ** 2 * q
    header = ",".join(["t"] + [f"{k}{j}" for k in ("q", "dq", "ddq") for j in range(1, 7)])
    np.savetxt(tmp_path / "traj.csv", np.c_[t, robot.to_controller(q), qd, qdd], delimiter=",",
               header=header, comments="")
    chi = random_chi(robot, np.random.default_rng(5))
    (tmp_path / "p.json").write_text(json.dumps(dict(zip(robot.parameter_names, chi.tolist()))))
    base = [RX90, "simulate", str(tmp_path / "traj.csv"), "--robot", str(own_rx90), "--noise", "ideal",
            "--out", str(tmp_path / "rec.csv")]
    refused = subprocess.run(base, capture_output=True, text=True, timeout=300)
    assert refused.returncode == 2 and "pass --params FILE" in refused.stderr
    assert not (tmp_path / "rec.csv").exists()
    done = subprocess.run(base + ["--params", str(tmp_path / "p.json")], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    from identify import read_recording

    rec = read_recording(tmp_path / "rec.csv", robot)
    # Ideal twin: tau = IDM(q; chi) - spring(q), checked against the model directly.
    tau = np.array([np.array(robot.inverse_dynamics(qi, qdi, qddi, chi)).ravel() for qi, qdi, qddi in
                    zip(rec.q, qd, qdd)]) - robot.spring_torque_batch(rec.q).reshape(len(t), 6)
    np.testing.assert_allclose(rec.tau, tau, rtol=1e-6, atol=1e-6)


def test_an_identification_of_the_same_name_in_other_frames_is_refused(tmp_path):
    """The bundled Panda (a robot file) and franka's URDF of the Panda share the name 'panda' but
    not their frames: parameters identified on one are refused for the other; the same kind of
    description passes."""
    urdf = rx90sym.load_robot(Path(__file__).parent / "data" / "urdf" / "panda.urdf", tip="panda_link8",
                              acceleration=10.0)
    bundled = rx90sym.load_robot("panda")
    assert urdf.name == bundled.name == "panda"
    params = rx90sym.nominal_parameters(urdf)
    on_urdf = tmp_path / "urdf_fit.json"
    on_urdf.write_text(json.dumps({"robot": "panda", "model": {"robot_file": str(urdf.source), "tip": "panda_link8"},
                                   "standard": params}))
    with pytest.raises(ValueError, match=r"identified on the URDF .*panda.urdf with tip 'panda_link8', not on "
                                         r"the robot file .*panda.toml"):
        rx90sym.nominal_parameters(bundled, on_urdf)
    assert rx90sym.nominal_parameters(urdf, on_urdf) == pytest.approx(params)
    rx90 = rx90sym.load_robot("rx90")
    on_file = tmp_path / "file_fit.json"
    on_file.write_text(json.dumps({"robot": "rx90", "model": {"robot_file": str(rx90.source), "tip": None},
                                   "standard": rx90sym.nominal_parameters(rx90)}))
    assert rx90sym.nominal_parameters(rx90, on_file) == pytest.approx(rx90sym.nominal_parameters(rx90))


def test_acceleration_limits_of_a_urdf_from_python_and_the_command_line(tmp_path):
    """A URDF has no acceleration limits: load_robot(acceleration=) and --acceleration set them; a
    robot file refuses the option (it has its own)."""
    path = Path(__file__).parent / "data" / "urdf" / "panda.urdf"
    robot = rx90sym.load_robot(path, tip="panda_link8", acceleration=[1, 2, 3, 4, 5, 6, 7])
    assert np.allclose(robot.limits.qdd_max, [1, 2, 3, 4, 5, 6, 7])
    with pytest.raises(rx90sym.RobotFileError, match="a robot file has its own"):
        rx90sym.load_robot("rx90", acceleration=5.0)
    with pytest.raises(ValueError, match=r"panda.urdf: acceleration limits: expected 1 or 7 numbers .*got 3"):
        rx90sym.load_robot(path, tip="panda_link8", acceleration=[1, 2, 3])
    args = ["model", "--robot", str(path), "--tip", "panda_link8"]
    quiet = subprocess.run([RX90, *args, "--acceleration", "5"], capture_output=True, text=True, timeout=300)
    assert quiet.returncode == 0 and "acceleration" not in quiet.stderr, quiet.stderr
    bad = subprocess.run([RX90, *args, "--acceleration", "5,x"], capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and "--acceleration: expected comma-separated numbers, got '5,x'" in bad.stderr
    # `model` does not use the limits: the assumed accelerations are said by excite and simulate only.
    plain = subprocess.run([RX90, *args], capture_output=True, text=True, timeout=300)
    assert plain.returncode == 0 and "acceleration" not in plain.stderr, plain.stderr
