"""Neutral words: controller / model angles, with the old staubli / khalil names accepted."""
from __future__ import annotations

import numpy as np
import pytest

import rx90sym
from identify.io.recordings import RecordingError, recording_from_arrays, read_recording, write_recording


def test_controller_and_model_angles_with_old_names(tmp_path):
    robot = rx90sym.load_robot("rx90")
    rng = np.random.default_rng(0)
    t = np.arange(100) / 250
    q = np.cumsum(rng.normal(0, 1e-3, (100, 6)), axis=0)
    rec = recording_from_arrays(t, q, rng.normal(size=(100, 6)), robot)
    write_recording(tmp_path / "c.csv", rec, robot)
    lines = (tmp_path / "c.csv").read_text().splitlines()
    assert lines[0] == "# convention: controller"
    raw = np.loadtxt(tmp_path / "c.csv", delimiter=",", comments="#", skiprows=3)
    # Controller angles = model angles + the robot file's [controller] offsets (pi/2, -pi/2).
    np.testing.assert_allclose(raw[:, 1:7] - q, np.tile([0, np.pi / 2, -np.pi / 2, 0, 0, 0], (100, 1)),
                               atol=1e-15)
    for word in (None, "controller", "staubli", "Stäubli"):
        np.testing.assert_allclose(read_recording(tmp_path / "c.csv", robot, convention=word).q, q, atol=1e-15)
    with pytest.raises(RecordingError, match="'khalil' \\(model angles\\)"):
        read_recording(tmp_path / "c.csv", robot, convention="khalil")
    old = tmp_path / "old.csv"
    old.write_text((tmp_path / "c.csv").read_text().replace("convention: controller", "convention: staubli"))
    np.testing.assert_allclose(read_recording(old, robot).q, q, atol=1e-15)
    write_recording(tmp_path / "m.csv", rec, robot, convention="model")
    assert (tmp_path / "m.csv").read_text().startswith("# convention: model")
    np.testing.assert_array_equal(read_recording(tmp_path / "m.csv", robot, convention="khalil").q, q)
    with pytest.warns(DeprecationWarning, match="to_controller"):  # the former word, one release
        former = robot.to_staubli(q)
    np.testing.assert_array_equal(robot.to_controller(q), former)
    with pytest.warns(DeprecationWarning, match="controller_offsets"):
        np.testing.assert_array_equal(robot.staubli_offsets, robot.controller_offsets)
