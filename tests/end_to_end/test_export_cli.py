"""``rx90 export`` end to end: a consistent fit of a UR10e twin -> URDF and MJCF that reproduce
the fit's own inverse dynamics; bad input refused with exit 2 and nothing written."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import rx90sym
from identify.app.cli import main
from rx90sym.flange_payload import flange_payload
from identify.io.recordings import recording_from_arrays, write_recording

from motions import multisine
from test_export_models import moving_states, pinocchio_of


def _twin_recording(robot, chi, path: Path, seed: int) -> None:
    """A noise-free 10 s motion at 200 Hz, written in the controller's angles."""
    t = np.arange(0, 10, 1 / 200)
    q, qd, qdd = multisine(robot, seed, 10)(t)
    tau = np.array(robot.inverse_dynamics.map(len(t))(q.T, qd.T, qdd.T, np.tile(chi[:, None], (1, len(t))))).T
    write_recording(path, recording_from_arrays(t, q, tau, robot), robot, convention="controller")


@pytest.fixture(scope="module")
def fits(tmp_path_factory):
    """A UR10e twin with its nominal parameters, identified with the defaults (method "wls": the file's identified
    model is what exports); wls.json: the same identification as a fit file written before the identified model
    (no standard parameters)."""
    folder = tmp_path_factory.mktemp("ur10e_fit")
    robot = rx90sym.load_robot("ur10e")
    chi = robot.parameter_vector(rx90sym.nominal_parameters(robot))
    _twin_recording(robot, chi, folder / "run.csv", seed=3)
    common = [str(folder / "run.csv"), "--robot", "ur10e", "--min-velocity", "0"]
    assert main(["identify", *common, "--json", str(folder / "id.json")]) == 0
    wls = json.loads((folder / "id.json").read_text())
    wls["method"] = "wls"
    for key in ("standard", "extras", "cost", "wls_cost", "cost_increase_pct", "wls_was_consistent", "identified"):
        wls.pop(key, None)
    (folder / "wls.json").write_text(json.dumps(wls))
    return robot, folder


def test_exported_urdf_and_mjcf_reproduce_the_fits_inverse_dynamics(fits, tmp_path):
    mujoco = pytest.importorskip("mujoco", reason="needs the mujoco extra")
    robot, folder = fits
    urdf, mjcf = tmp_path / "ur10e.urdf", tmp_path / "ur10e.xml"  # one name: the companions are per format
    assert main(["export", str(folder / "id.json"), "--urdf", str(urdf), "--mjcf", str(mjcf)]) == 0
    assert json.loads((tmp_path / "ur10e.mjcf.actuation.json").read_text())["kind"] == "mjcf"
    fit = json.loads((folder / "id.json").read_text())["identified"]["standard"]  # the model of the defaults
    chi = robot.parameter_vector({k: v for k, v in fit.items() if k in robot.parameter_names})
    side = json.loads(urdf.with_name("ur10e.actuation.json").read_text())
    # The exported joints carry the robot's ROS names, so a /joint_states message drives them.
    assert list(side["joints"]) == list(robot.ros_joint_names()) == ["shoulder_pan_joint", "shoulder_lift_joint",
                                                                     "elbow_joint", "wrist_1_joint", "wrist_2_joint",
                                                                     "wrist_3_joint"]
    IA = np.array([side["joints"][name]["IA"] for name in robot.ros_joint_names()])
    model, data = pinocchio_of(urdf, robot)
    mj = mujoco.MjModel.from_xml_path(str(mjcf))
    mj.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT | mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS)
    mjd = mujoco.MjData(mj)
    smooth = chi.copy()
    smooth[[i for i, n in enumerate(robot.parameter_names) if n.startswith("FS")]] = 0.0
    for qc, qd, qdd in zip(*moving_states(robot, np.random.default_rng(5), 8)):
        q = robot.to_model(qc)
        ref = np.array(robot.inverse_dynamics(q, qd, qdd, chi)).ravel()
        tau = pin.rnea(model, data, qc, qd, qdd) + IA * qdd + model.damping * qd + model.friction * np.sign(qd)
        assert np.abs(tau - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max())
        mjd.qpos[:], mjd.qvel[:], mjd.qacc[:] = qc, qd, qdd
        mujoco.mj_inverse(mj, mjd)
        ref = np.array(robot.inverse_dynamics(q, qd, qdd, smooth)).ravel()
        assert np.abs(mjd.qfrc_inverse - ref).max() <= 1e-8 * max(1.0, np.abs(ref).max())


def test_the_library_exports_a_loaded_fit_like_the_command(fits, tmp_path):
    """identify.export_urdf / export_mjcf on identify.load_fit; a fit file without bodies (written before
    the identified model) is refused."""
    import identify

    robot, folder = fits
    a, b, c = tmp_path / "a.urdf", tmp_path / "b.urdf", tmp_path / "c.xml"
    assert main(["export", str(folder / "id.json"), "--urdf", str(a)]) == 0
    fit = identify.load_fit(folder / "id.json")
    assert identify.export_urdf(fit, b) == [b, tmp_path / "b.actuation.json"]
    assert a.read_text() == b.read_text()
    identify.export_mjcf(fit, c)
    assert c.read_text().startswith('<mujoco model="ur10e">')
    with pytest.raises(ValueError, match="base parameters only"):
        identify.export_urdf(identify.load_fit(folder / "wls.json"), tmp_path / "w.urdf")
    assert not (tmp_path / "w.urdf").exists()


def _payload_json(path: Path, values: dict, flange: dict) -> Path:
    path.write_text(json.dumps({"method": 3, "constrained": False,
                                "payload": [{"name": k, "value": v} for k, v in values.items()],
                                "flange": flange}))
    return path


@pytest.mark.parametrize("case, needle", [
    ("wls", "identify again"),
    ("other robot", "has 7 joints"),
    ("no folder", "output folder"),
    ("payload not physical", "--constrained"),
    ("franka form for a UR payload", "not in the form or the flange frame of a franka controller"),
    ("nothing asked", "nothing to export"),
])
def test_bad_input_exits_2_with_a_message_and_writes_nothing(fits, tmp_path, capsys, case, needle):
    robot, folder = fits
    out = tmp_path / "out"
    out.mkdir()
    target = str(out / "x.urdf")
    args = {"wls": [str(folder / "wls.json"), "--urdf", target],
            "other robot": [str(folder / "id.json"), "--robot", "panda", "--urdf", target],
            "no folder": [str(folder / "id.json"), "--urdf", str(out / "missing" / "x.urdf")],
            "nothing asked": [str(folder / "id.json")]}
    if case == "payload not physical":
        load = rx90sym.load_payload("tables_4")
        flange = flange_payload(robot, {**load, "ZZc": 5.0}).to_dict()
        args[case] = [str(_payload_json(tmp_path / "p.json", load, flange)), "--ur", str(out / "p.script")]
    if case == "franka form for a UR payload":
        load = rx90sym.load_payload("tables_4")
        flange = flange_payload(robot, load).to_dict()
        args[case] = [str(_payload_json(tmp_path / "p.json", load, flange)), "--ur", str(out / "p.script"),
                      "--franka", str(out / "p.json")]
    assert main(["export", *args[case]]) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1, err
    assert list(out.iterdir()) == []


@pytest.mark.parametrize("robot_name, option", [("ur10e", "--ur"), ("panda", "--franka")])
def test_the_library_writes_the_payload_form_the_command_writes(tmp_path, robot_name, option):
    """rx90sym.flange_payload + ur_script / franka_load: the bytes of rx90 export --ur / --franka."""
    robot = rx90sym.load_robot(robot_name)
    load = rx90sym.load_payload("tables_4")
    flange = rx90sym.flange_payload(robot, load)
    out = tmp_path / "p.out"
    assert main(["export", str(_payload_json(tmp_path / "p.json", load, flange.to_dict())), option, str(out)]) == 0
    text = (rx90sym.ur_script(flange) if option == "--ur"
            else json.dumps(rx90sym.franka_load(flange), indent=1) + "\n")
    assert out.read_text() == text
    assert abs(flange.mass - load["Mc"]) <= 1e-12 * load["Mc"]  # a rigid move keeps the mass


def test_a_default_fit_file_gives_its_identified_model_as_parameters(fits):
    """rx90 simulate --params and --prior FILE read a fit file made with the defaults: its identified model's
    standard parameters; a fit file written before the identified model is refused, naming the fix."""
    from rx90sym.nominal import read_parameter_file

    robot, folder = fits
    model = json.loads((folder / "id.json").read_text())["identified"]["standard"]
    got = read_parameter_file(robot, folder / "id.json")
    shared = [n for n in robot.parameter_names if n in model]
    assert len(shared) >= 10 * robot.n and all(got[n] == model[n] for n in shared)
    with pytest.raises(ValueError, match="written before the identified model"):
        read_parameter_file(robot, folder / "wls.json")
