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


def test_a_bundled_name_is_the_bundled_robot_even_with_a_file_of_that_name_here(tmp_path, monkeypatch):
    """A folder 'tx40' (e.g. the data) or a file 'rx90' in the working directory does not hide the
    bundled robot; the file is reached as ./rx90, and a folder given as a path is named."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tx40").mkdir()
    _write(tmp_path, RX90.replace('name = "rx90"', 'name = "mine"'), "rx90")
    assert rx90sym.load_robot("tx40").name == "tx40"
    assert rx90sym.load_robot("rx90").name == "rx90"
    assert rx90sym.load_robot("./rx90").name == "mine"
    with pytest.raises(RobotFileError, match="tx40: is a folder, not a robot file"):
        rx90sym.load_robot("./tx40")


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


def _line_of(text: str, needle: str) -> int:
    return text.splitlines().index(next(line for line in text.splitlines() if needle in line)) + 1


@pytest.mark.parametrize("old, new, message", [
    # A misspelt section: its limits would otherwise be infinite.
    ("[limits]", "[limit]", ": unknown section [limit]; did you mean [limits]?"),
    ("[transmission]", "[transmision]", ": unknown section [transmision]; did you mean [transmission]?"),
    # A misspelt key inside a known section.
    ("velocity_deg_s = [", "velocty = [", ": [limits]: unknown key 'velocty'; did you mean 'velocity'?"),
    ("torque = [300.0", "torqe = [300.0", ": [limits]: unknown key 'torqe'; did you mean 'torque'?"),
    # A misspelt key in a [[joints]] row and at the top level.
    ("d = 0.45", "dd = 0.45", ": joints[3]: unknown key 'dd'; did you mean 'd'?"),
    ('description = "', 'descripton = "', ": unknown key 'descripton'; did you mean 'description'?"),
    # A unit suffix that does not exist.
    ("velocity_deg_s = [", "velocity_deg = [", ": [limits]: unknown key 'velocity_deg'; did you mean 'velocity_deg_s'?"),
])
def test_typos_are_errors_naming_file_line_and_nearest_name(tmp_path, old, new, message):
    text = RX90.replace(old, new, 1)
    assert text != RX90
    path = _write(tmp_path, text)
    with pytest.raises(RobotFileError) as err:
        rx90sym.load_robot(path)
    assert str(err.value).startswith(f"{path}, line {_line_of(text, new)}{message}")


def test_old_section_name_and_both_spellings(tmp_path):
    old = rx90sym.load_robot(_write(tmp_path, RX90.replace("[controller]", "[staubli]"), "old.toml"))
    new = rx90sym.load_robot("rx90")
    np.testing.assert_array_equal(old.controller_offsets, new.controller_offsets)
    both = RX90.replace("[controller]", "[staubli]\noffsets = [0, 0, 0, 0, 0, 0]\n\n[controller]")
    with pytest.raises(RobotFileError, match=r"\[controller\] or its old name \[staubli\]"):
        rx90sym.load_robot(_write(tmp_path, both))
    twice = RX90.replace("velocity_deg_s = [", "velocity = [1, 1, 1, 1, 1, 1]\nvelocity_deg_s = [")
    with pytest.raises(RobotFileError, match="give 'velocity' or 'velocity_deg_s', not both"):
        rx90sym.load_robot(_write(tmp_path, twice))


def test_a_partial_spring_is_refused_not_completed_with_rx90_placeholders(tmp_path):
    head = RX90[:RX90.index("[spring]")]
    path = _write(tmp_path, head + "[spring]\njoint = 3\nk = 1000.0\n")
    with pytest.raises(RobotFileError) as err:
        rx90sym.load_robot(path)
    assert f"{path}, line {head.count(chr(10)) + 1}: [spring]" in str(err.value)
    assert "missing a, b, L0, angle_offset" in str(err.value)
    full = head + "[spring]\njoint = 3\nk = 1000.0\na = 0.2\nb = 0.4\nL0 = 0.1\nangle_offset = 0.3\n"
    robot = rx90sym.load_robot(_write(tmp_path, full, "full.toml"))
    assert robot.spring.joint == 2 and not robot.spring.placeholder
    q = np.zeros(6)
    q[2] = 0.7
    tau = np.array(robot.spring_torque(q)).ravel()
    ts, L = 0.7 + 0.3, np.sqrt(0.2**2 + 0.4**2 - 2 * 0.2 * 0.4 * np.cos(1.0))
    assert tau[2] == pytest.approx(-1000 * 0.2 * 0.4 * np.sin(ts) * (1 - 0.1 / L), rel=1e-12)
    assert np.count_nonzero(tau) == 1
    assert rx90sym.load_robot("rx90").spring.placeholder


def test_line_numbers_after_multi_line_values(tmp_path):
    text = RX90.replace("velocity_deg_s = [236.0, 200.0, 286.0, 401.0, 320.0, 580.0]",
                        "velocity_deg_s = [\n  236.0, 200.0, 286.0,  # [deg/s]\n  401.0, 320.0, 580.0,\n]\n"
                        'note = """a\n[limits]\nb"""\naccelration_deg_s2 = [1, 1, 1, 1, 1, 1]')
    path = _write(tmp_path, text)
    with pytest.raises(RobotFileError) as err:
        rx90sym.load_robot(path)
    # 'note' comes first in the file: both are reported with their own line.
    assert str(err.value).startswith(f"{path}, line {_line_of(text, 'note = ')}: [limits]: unknown key 'note'")
    text = text.replace('note = """a\n[limits]\nb"""\n', "")
    path = _write(tmp_path, text)
    with pytest.raises(RobotFileError) as err:
        rx90sym.load_robot(path)
    assert str(err.value).startswith(f"{path}, line {_line_of(text, 'accelration')}: [limits]: "
                                     f"unknown key 'accelration_deg_s2'; did you mean 'acceleration_deg_s2'?")
