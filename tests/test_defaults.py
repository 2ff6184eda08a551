"""One set of defaults: a library function and the command that calls it plan the same motion.

``excitation.optimise(robot)`` with its defaults is ``rx90 excite --robot`` with its defaults: the
same envelope, torque limits, criterion, starts and seed, hence the same coefficients; and the
motion it plans holds the envelope, checked independently with Pinocchio on the URDF.
"""
from __future__ import annotations

import argparse
import inspect
import io
import json

import numpy as np
import pytest

import excitation
import rx90sym
from excitation.api import DEFAULT_STARTS, NO_ENVELOPE
from command_line import run
from test_excitation_envelope import UR5, UR5_ARGS, _pinocchio_frames


def _excite_defaults() -> dict:
    from identify.app.commands import excite

    parser = argparse.ArgumentParser()
    excite.register(parser.add_subparsers(dest="command"))
    return vars(parser.parse_args(["excite", "--robot", "rx90", "--out", "x.csv"]))


def test_the_command_and_the_library_share_their_defaults():
    lib = inspect.signature(excitation.optimise).parameters
    cli = _excite_defaults()
    assert cli["starts"] == lib["starts"].default == DEFAULT_STARTS
    assert cli["seed"] == lib["seed"].default
    assert cli["duration"] in (None, lib["duration"].default) and cli["harmonics"] in (None, lib["harmonics"].default)
    assert cli["criterion"] is None and lib["criterion"].default is None  # one rule picks it in both
    assert lib["envelope"].default == "default" and lib["chi_nominal"].default == "default"
    # The command's envelope without options is the library's default one.
    from identify.app.commands.excite import _envelope

    robot = rx90sym.load_robot(UR5, tip="tool0", acceleration=6.0)
    ns = argparse.Namespace(**{**_excite_defaults(), "acceleration": 6.0})
    assert _envelope(ns, robot) == excitation.api.resolve_envelope(robot, "default")


def test_switching_the_envelope_off_says_what_is_unchecked():
    robot = rx90sym.load_robot("rx90")
    said = io.StringIO()
    assert excitation.api.resolve_envelope(robot, None, said) is None
    assert said.getvalue().strip() == NO_ENVELOPE.format(floor="")
    assert "NOT checked" in said.getvalue()
    said = io.StringIO()
    assert excitation.api.resolve_nominal(robot, None, said) is None and "torque limits" in said.getvalue()
    with pytest.raises(ValueError, match="envelope: expected 'default'"):
        excitation.api.resolve_envelope(robot, "off")


@pytest.mark.slow
def test_library_defaults_plan_the_commands_motion_and_it_is_safe(tmp_path):
    """Short motion (6 s, 2 harmonics, one start) given alike to both; everything else defaulted."""
    proc = run(*UR5_ARGS, "--acceleration", "6", "--duration", "6", "--harmonics", "2", "--starts", "1",
               "--out", str(tmp_path / "cli.csv"), "--json", str(tmp_path / "cli.json"))
    assert proc.returncode == 0, proc.stderr
    robot = rx90sym.load_robot(UR5, tip="tool0", acceleration=6.0)
    traj = excitation.optimise(robot, 6.0, 2, starts=1, progress=False)
    traj.save_json(tmp_path / "lib.json")
    cli, lib = (json.loads((tmp_path / f).read_text()) for f in ("cli.json", "lib.json"))
    for key in ("q0_rad", "a_rad_s", "b_rad_s"):
        a, b = np.array(lib["coefficients"][key]), np.array(cli["coefficients"][key])
        assert np.allclose(a, b, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(b).max())), key
    assert lib["criterion"] == cli["criterion"] == "sigma" and lib["envelope"] == cli["envelope"]
    # Safe by Pinocchio: every moving frame above the base plane plus the margin, tool speed bounded.
    t, q, _, _ = traj.sample(500.0)
    frames = _pinocchio_frames(q + robot.controller_offsets)
    moving = [n for n in frames if n not in ("universe", "root_joint", "base_link", "shoulder_pan_joint",
                                             "shoulder_link")]
    assert min(float(frames[n][:, 2].min()) for n in moving) >= 0.05 - 1e-6
    speed = np.linalg.norm(np.diff(frames["tool0"], axis=0), axis=1) * 500.0
    assert speed.max() <= 1.0 * 1.01
