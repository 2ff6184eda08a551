"""Robot files: bundled ones load, bad ones are refused naming the file and the field."""
from __future__ import annotations

import numpy as np
import pytest

import rx90sym
from rx90sym.robot_file import ROBOTS_DIR, RobotFileError

RX90 = (ROBOTS_DIR / "rx90.toml").read_text()


def _write(tmp_path, text, name="bad.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_bundled_robots_load():
    assert {"rx90", "tx40"} <= set(rx90sym.bundled_robots())
    rx90 = rx90sym.load_robot("rx90")
    assert rx90.n == 6 and rx90.d[2] == 0.45 and rx90.r[3] == 0.45
    # Staubli limits converted once: joint 2 is +-137.5 deg Staubli -> Khalil shifted by -90 deg.
    assert np.isclose(np.degrees(rx90.limits.q_max[1]), 137.5 - 90)
    assert np.isclose(np.degrees(rx90.limits.qd_max[0]), 236)


def test_a_users_file_loads_the_same_way(tmp_path):
    path = _write(tmp_path, RX90.replace('name = "rx90"', 'name = "mine"'), "mine.toml")
    robot = rx90sym.load_robot(path)
    assert robot.name == "mine" and robot.parameter_names == rx90sym.load_robot("rx90").parameter_names


@pytest.mark.parametrize("edit, field", [
    (lambda s: s.replace("alpha_deg = -90.0\nd = 0.0\ntheta_deg = 0.0\nr = 0.0\n\n[[joints]]\nsigma = 0\nalpha_deg = 0.0\nd = 0.45",
                         "d = 0.0\ntheta_deg = 0.0\nr = 0.0\n\n[[joints]]\nsigma = 0\nalpha_deg = 0.0\nd = 0.45", 1), "'alpha'"),
    (lambda s: s.replace("sigma = 0", "sigma = 2", 1), "sigma=2"),
    (lambda s: s.replace('name = "rx90"', 'name = "rx90"\nn = 7'), "'n'"),
    (lambda s: s.replace("velocity_deg_s = [236.0, 200.0, 286.0, 401.0, 320.0, 580.0]",
                         "velocity_deg_s = [236.0, 200.0, 286.0, 401.0, 320.0]"), "'velocity_deg_s'"),
    (lambda s: s.replace("position_min_deg = [-160.0", "position_min_deg = [170.0"), "position_min > position_max"),
    (lambda s: s.replace("d = 0.45", "d = 'x'"), "'d'"),
    (lambda s: s.replace("torque = [300.0", "torque = [-1.0"), "torque limit of joint 1"),
    (lambda s: s.replace("joints = [5, 6]", "joints = [5, 9]"), "'joints'"),
])
def test_bad_robot_files_are_refused_naming_file_and_field(tmp_path, edit, field):
    text = edit(RX90)
    assert text != RX90
    path = _write(tmp_path, text)
    with pytest.raises(RobotFileError) as err:
        rx90sym.load_robot(path)
    assert str(path) in str(err.value) and field in str(err.value)


def test_unknown_robot_and_broken_toml(tmp_path):
    with pytest.raises(RobotFileError, match="unknown robot 'rx91'"):
        rx90sym.load_robot("rx91")
    path = _write(tmp_path, "name = [")
    with pytest.raises(RobotFileError, match="not valid TOML"):
        rx90sym.load_robot(path)


def test_table_rows_are_checked():
    with pytest.raises(ValueError, match="row 2: sigma"):
        rx90sym.robot_from_table([(0, 0, 0, 0, 0), (3, 0, 0, 0, 0)])
    with pytest.raises(ValueError, match="row 1: expected"):
        rx90sym.robot_from_table([(0, 0, 0, 0)])
