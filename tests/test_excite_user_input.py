"""``rx90 excite`` as a user types it (issue 19's audit): values starting with a minus sign, angles
quoted back in the controller's convention (the RX90's joints 2 and 3 are offset by 90 deg from
the model's), one warning about a URDF's acceleration limits, and a report that says its limit
usage is relative to the experiment's limits. Each refusal comes before any optimisation."""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

import rx90sym
from identify.app.cli import join_negative_values, main
from identify.app.report.excite_page import excite_page

UR5 = str(Path(__file__).parent / "data" / "urdf" / "ur5.urdf")
RX90_FILE = str(Path(rx90sym.__file__).parent / "robots" / "rx90.toml")
RX90_Q2 = np.radians(137.5)  # rx90.toml [limits]: joint 2 in controller angles, +-137.5 deg
RX90_ARM = 0.45  # [m] RX90 upper arm and forearm (Staubli's data sheet): shoulder to elbow, elbow to wrist
RX90_Z_MIN = -0.42 + 0.05  # [m] rx90.toml mounting plane in frame 0 (the shoulder) + the default margin


def _excite(tmp_path: Path, capsys: pytest.CaptureFixture, *extra: str) -> tuple[int, str]:
    code = main(["excite", "--duration", "6", "--harmonics", "2", "--starts", "1", *extra,
                 "--out", str(tmp_path / "t.csv"), "--json", str(tmp_path / "t.json")])
    assert not (tmp_path / "t.csv").exists() and not (tmp_path / "t.json").exists()
    return code, capsys.readouterr().err


def test_lists_starting_with_a_minus_sign_are_values_not_options():
    argv = ["excite", "--start-pose", "-1.5,0", "--floor", "-0.1", "--position-limits", "-2:-1,0:1", "--out", "-"]
    assert join_negative_values(argv) == ["excite", "--start-pose=-1.5,0", "--floor", "-0.1",
                                          "--position-limits=-2:-1,0:1", "--out", "-"]


@pytest.mark.parametrize("extra, message", [
    # argparse alone answered "expected one argument" to both (the value starts with '-')
    (("--position-limits", "-1:-1,-1:1,-1:1,-1:1,-1:1,-1:1"), "joint 1: max -1 rad is not above min -1 rad"),
    (("--controller", "ur", "--start-pose", "-9,0,0,0,0,0"), "joint 1 at -9 rad is outside the robot's range"),
])
def test_negative_first_values_reach_the_checks(tmp_path, capsys, extra, message):
    code, err = _excite(tmp_path, capsys, "--robot", UR5, "--tip", "tool0", "--acceleration", "6", *extra)
    assert code == 2 and message in err, err


@pytest.mark.parametrize("extra, message", [
    (("--position-limits", "-1:1,-3:3,-1:1,-1:1,-1:1,-1:1"),
     f"joint 2: [-3, 3] rad leave the robot's range [{-RX90_Q2:.6g}, {RX90_Q2:.6g}] rad (controller angles)"),
    (("--centre-pose", "0,2.3,0,0,0,0"),  # the experiment's range: 90 % of the robot's
     f"joint 2 at 2.3 rad is outside the experiment's range [{-0.9 * RX90_Q2:.6g}, {0.9 * RX90_Q2:.6g}] rad"),
    # the RX90's own file (a file is taken as named, whatever the controller)
    (("--controller", "ur", "--start-pose", "0,2.5,0,0,0,0"), f"joint 2 at 2.5 rad is outside the robot's range "
                                                               f"[{-RX90_Q2:.6g}, {RX90_Q2:.6g}]"),
])
def test_refusals_quote_the_controller_angles_the_user_typed(tmp_path, capsys, extra, message):
    code, err = _excite(tmp_path, capsys, "--robot", RX90_FILE, *extra)
    assert code == 2 and message in err, err


def test_printed_envelope_is_in_controller_angles(tmp_path, capsys):
    # a --complement recording that cannot be read fails after the envelope is printed, before any
    # optimisation (a missing one is refused before anything: see the first assertion)
    code, err = _excite(tmp_path, capsys, "--robot", "rx90", "--complement", str(tmp_path / "missing.csv"))
    assert code == 2 and "--complement: " in err and "missing.csv: no such file" in err and "safety envelope" not in err
    bad = tmp_path / "bad.csv"
    bad.write_text("t,q1\n0,0\n")
    code, err = _excite(tmp_path, capsys, "--robot", "rx90", "--complement", str(bad))
    bad.unlink()
    assert code == 2 and "bad.csv" in err, err
    q2 = np.degrees(0.9 * RX90_Q2)  # 90 % of +-137.5 deg about the centre 0
    assert f"joint ranges [deg, controller angles]: [-144, 144], [{-q2:.0f}, {q2:.0f}]," in err, err
    assert "centre pose [deg, controller angles]: 0.0, 0.0, 0.0, 0.0" in err, err  # the model's is 0, -90, 90


def test_a_urdf_without_accelerations_gets_one_warning_with_the_default_used(tmp_path, capsys):
    code, err = _excite(tmp_path, capsys, "--robot", UR5, "--tip", "tool0", "--floor", "5")
    assert code == 2 and "no pose of the arm lies inside the envelope" in err
    # the floor the user set: 5 m above the mounting plane (ur5.urdf: shoulder 0.089159 m above the base),
    # not the optimiser's further 0.01 m
    assert f"below the lowest allowed z = {5 - 0.089159:.4f} m (the optimiser keeps a further 0.01 m)" in err, err
    # One assumption, said once: 2 x the velocity limit, at most 10 rad/s^2 (the loader's and the envelope's).
    assert err.count("acceleration limits") == 1 and "2 x each joint's velocity limit per second, at most 10 rad/s^2" in err, err


def test_report_says_usage_is_of_the_experiments_limits():
    usage = {"checked_at_hz": 1000.0, "feasible": True, "position": [0.5, 0.97], "velocity": [0.98, 0.5],
             "acceleration": [0.5, 0.5], "torque": [0.97, 0.1], "violations": []}
    envelope = {"velocity_scale": 0.7, "acceleration_scale": 0.5}
    flags = {f["message"]: f["severity"] for f in excite_page(
        {"limits_usage": usage, "envelope": envelope}).summary.flags}
    assert flags == {
        "position within 5 % of the experiment's limit on joint(s) 2 (the experiment's ranges lie inside the robot's)":
            "info",
        "velocity within 5 % of the experiment's limit on joint(s) 1 (the experiment's limit is 0.7 x the robot's)":
            "info",
        "torque within 5 % of its limit on joint(s) 1": "warning"}  # torque limits are the robot's own
    bare = excite_page({"limits_usage": usage}).summary.flags  # no envelope: the robot's own limits
    assert {f["severity"] for f in bare} == {"warning"} and len(bare) == 3


def test_a_start_pose_below_the_base_is_refused_naming_the_urdf_link(tmp_path, capsys):
    # shoulder lift +90 deg: the upper arm (0.425 m in ur5.urdf) hangs straight down from the shoulder
    code, err = _excite(tmp_path, capsys, "--robot", UR5, "--tip", "tool0", "--acceleration", "6",
                        "--controller", "ur", "--start-pose", "0,1.5708,0,0,0,0")
    assert code == 2, err
    assert "outside the safety envelope: origin of frame 3 (link forearm_link) at z = -0.4250 m" in err, err
    assert "(z in frame 0, where the mounting plane is z = -0.08916 m)" in err  # ur5.urdf: shoulder 0.089159


def test_rx90_envelope_json_and_lines_give_the_typed_position_limits(tmp_path, capsys):
    # the RX90's joints 2 and 3 are offset by 90 deg between the controller's angles and the model's
    assert np.any(rx90sym.load_robot("rx90").controller_offsets != 0.0)
    given = np.array([[-1.5, 1.2], [-1.1, 0.9], [-1.0, 1.3], [-2.0, 2.0], [-1.2, 1.5], [-3.0, 3.0]])
    code = main(["excite", "--robot", "rx90", "--duration", "6", "--harmonics", "2", "--starts", "1",
                 "--position-limits", ",".join(f"{a:g}:{b:g}" for a, b in given),
                 "--out", str(tmp_path / "t.csv"), "--json", str(tmp_path / "t.json")])
    err = capsys.readouterr().err
    assert code == 0, err
    envelope = json.loads((tmp_path / "t.json").read_text())["envelope"]
    assert envelope["angles"] == "controller" and envelope["position_limits_rad"] == given.tolist()
    printed = ", ".join(f"[{np.degrees(a):.0f}, {np.degrees(b):.0f}]" for a, b in given)
    assert f"joint ranges [deg, controller angles]: {printed}" in err, err
    centre = np.array(envelope["centre_pose_rad"])
    assert np.all((given[:, 0] <= centre) & (centre <= given[:, 1]))
    # what the controller runs (the CSV: controller angles, as the logs) keeps inside the typed ranges
    q = np.loadtxt(tmp_path / "t.csv", delimiter=",", skiprows=1)[:, 1:7]
    assert np.all(q >= given[:, 0] - 1e-9) and np.all(q <= given[:, 1] + 1e-9)


@pytest.mark.parametrize("extra, quoted, q2, q3", [
    (("--centre-pose", "0,2.1,0,0,0,0"), "--centre-pose 0, 2.1, 0, 0, 0, 0 rad (controller angles) is outside the "
                                          "safety envelope: origin of frame 4", 2.1, 0.0),
    (("--controller", "ur", "--start-pose", "0,2.1,0.5,0,0,0"),
     "--start-pose 0,2.1,0.5,0,0,0 is outside the safety envelope: origin of frame 4", 2.1, 0.5),
])
def test_rx90_envelope_refusal_quotes_the_typed_pose_and_its_height(tmp_path, capsys, extra, quoted, q2, q3):
    code, err = _excite(tmp_path, capsys, "--robot", RX90_FILE, *extra)
    assert code == 2 and quoted in err, err
    # the wrist centre (frame 4) by the arm's lengths, controller angles from the vertical: the
    # height was computed at the typed pose, not at the typed numbers read as model angles
    wrist = RX90_ARM * np.cos(q2) + RX90_ARM * np.cos(q2 + q3)
    z, z_min = map(float, re.search(r"at z = (\S+) m, below the lowest allowed z = (\S+) m", err).groups())
    assert abs(z - wrist) < 1e-4 and abs(z_min - RX90_Z_MIN) < 1e-4, err
