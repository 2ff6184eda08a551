"""Without --start-pose, the URScript program checks that the arm is at the trajectory's start
before its first move (issue 31): the first movej never travels from an unchecked pose."""
from __future__ import annotations

import re

import numpy as np

from excitation.controller_programs import START_TOLERANCE, parse_servoj, urscript


def _check_then_move(text: str) -> tuple[int, int]:
    lines = text.splitlines()
    check = next((i for i, line in enumerate(lines) if "get_actual_joint_positions()" in line), -1)
    move = next(i for i, line in enumerate(lines) if line.strip().startswith("movej("))
    return check, move


def test_without_a_start_pose_the_program_checks_the_arm_before_its_first_move():
    q = np.linspace([0.1, -1.5, 1.2, -1.0, -1.57, 0.3], [0.2, -1.4, 1.1, -0.9, -1.5, 0.4], 5)
    text = urscript(q, 500.0)
    check, move = _check_then_move(text)
    assert 0 < check < move
    start = re.search(r"start = \[(.*)\]", text).group(1)
    assert np.allclose([float(v) for v in start.split(",")], q[0], atol=1e-9)
    assert f"> {START_TOLERANCE:g}:" in text and "halt" in text and START_TOLERANCE == 0.05
    assert np.allclose(parse_servoj(text), q, atol=1e-8)  # the samples are unchanged


def test_with_a_start_pose_the_approach_is_the_planned_one_and_no_check_is_needed():
    q = np.zeros((4, 6))
    text = urscript(q, 125.0, start_pose=[0, -1.5708, 0, -1.5708, 0, 0])
    check, move = _check_then_move(text)
    assert check == -1 and text.count("movej(") == 3


def test_the_ur_rate_comes_from_the_robot_file_and_a_urdf_without_one_is_refused(tmp_path, capsys):
    import argparse
    from pathlib import Path

    import rx90sym
    from identify.app.cli import main
    from identify.app.commands.excite import controller_rate

    assert controller_rate(argparse.Namespace(controller_rate=None), rx90sym.load_robot("ur10e")) == 500.0
    assert controller_rate(argparse.Namespace(controller_rate=125.0), rx90sym.load_robot("ur10e")) == 125.0
    ur5 = str(Path(__file__).parent / "data" / "urdf" / "ur5.urdf")
    code = main(["excite", "--robot", ur5, "--tip", "tool0", "--acceleration", "6", "--duration", "6",
                 "--harmonics", "2", "--starts", "1", "--controller", "ur", "--out", str(tmp_path / "t.csv")])
    err = capsys.readouterr().err
    assert code == 2 and "500 Hz for e-series, 125 Hz for cb3" in err and "--controller-rate" in err, err
    assert not (tmp_path / "t.csv").exists()
