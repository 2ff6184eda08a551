"""A fit file travels alone: it embeds the robot description it was fitted with (schema 4).

Copied to another folder, the URDF it was fitted on deleted, the file rebuilds the same robot:
the same predicted torques and the same exported URDF and MJCF. ``robot=`` (``--robot``) overrides
the embedded description and the differences are said; an arm that cannot be the same is refused.
"""
from __future__ import annotations

import json
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import identify
import rx90sym
from motions import multisine

UR5 = Path(__file__).parent / "data" / "urdf" / "ur5.urdf"
UR10 = Path(__file__).parent / "data" / "urdf" / "ur10_robot.urdf"


def _load(path, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a URDF's missing acceleration limits (documented default)
        return rx90sym.load_robot(str(path), tip="tool0", **kw)


@pytest.fixture(scope="module")
def travelled(tmp_path_factory):
    """A consistent fit of a UR5 twin made in folder A from a URDF there; the fit file then copied
    alone to folder B and folder A deleted."""
    a, b = tmp_path_factory.mktemp("a"), tmp_path_factory.mktemp("b")
    shutil.copy(UR5, a / "ur5.urdf")
    robot = _load(a / "ur5.urdf", acceleration=6.0)
    rec = rx90sym.twin.simulate(robot, multisine(robot, 2, duration=8.0), duration=8.0, noise="quantised", seed=2)
    held = rx90sym.twin.simulate(robot, multisine(robot, 5, duration=6.0), duration=6.0, noise="quantised", seed=5)
    fit = identify.fit(robot, [rec], identify.Processing(cutoff=8.0), method="consistent")
    fit.save(a / "fit.json")
    shutil.copy(a / "fit.json", b / "fit.json")
    before = fit.predict(held)
    (a / "u").mkdir(), (a / "m").mkdir()
    exported = [identify.export_urdf(fit, a / "u" / "arm.urdf"), identify.export_mjcf(fit, a / "m" / "arm.xml")]
    texts = {f"{p.parent.name}/{p.name}": p.read_text() for group in exported for p in group}
    shutil.rmtree(a)
    return b, fit, held, before, texts


def test_the_fit_file_embeds_its_description(travelled):
    b, fit, _, _, _ = travelled
    model = json.loads((b / "fit.json").read_text())["model"]
    assert json.loads((b / "fit.json").read_text())["schema_version"] == identify.fitting.fit_file.SCHEMA_VERSION
    assert model["description"]["robot_text"] == UR5.read_text()
    assert model["description"]["robot_format"] == "urdf" and model["description"]["acceleration"] == [6.0] * 6
    assert Path(model["robot_file"]).is_absolute() and model["tip"] == "tool0"


def test_a_fit_file_alone_predicts_and_exports_the_same(travelled, tmp_path):
    b, fit, held, before, texts = travelled
    again = identify.load_fit(b / "fit.json")  # its URDF no longer exists at the recorded path
    assert not Path(again.model.robot_file).exists()
    after = again.predict(held)
    np.testing.assert_allclose(after.predicted, before.predicted, rtol=0, atol=1e-12 * np.abs(before.predicted).max())
    np.testing.assert_array_equal(again.robot.limits.qdd_max, fit.robot.limits.qdd_max)
    (tmp_path / "u").mkdir(), (tmp_path / "m").mkdir()
    paths = identify.export_urdf(again, tmp_path / "u" / "arm.urdf") + identify.export_mjcf(again, tmp_path / "m" / "arm.xml")
    assert sorted(f"{p.parent.name}/{p.name}" for p in paths) == sorted(texts)
    for p in paths:  # the same files, but for where they say the description was read from
        now = p.read_text().replace(str(again.robot.source), "SOURCE")
        was = texts[f"{p.parent.name}/{p.name}"].replace(str(fit.robot.source), "SOURCE")
        assert now == was, p
    assert Path(again.robot.source).read_text() == UR5.read_text()
    assert again.model.check_robot(again.robot) == ""  # nothing at the recorded path to differ from


def test_another_robot_given_wins_and_the_differences_are_said(travelled):
    b, fit, held, before, _ = travelled
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the UR10 URDF's missing acceleration limits
        other = identify.load_fit(b / "fit.json", robot=str(UR10))
    note = other.model.check_robot(other.robot)
    assert "instead of the description embedded" in note and "joint 3: d 0.425 vs 0.612" in note
    with pytest.raises(ValueError, match="7 joints"):
        identify.load_fit(b / "fit.json", robot="panda")


def test_an_edited_embedded_description_is_refused(travelled, tmp_path):
    b = travelled[0]
    data = json.loads((b / "fit.json").read_text())
    data["model"]["description"]["robot_text"] += "\n<!-- edited -->"
    (tmp_path / "bad.json").write_text(json.dumps(data))
    with pytest.raises(ValueError, match="does not match its SHA-256"):
        identify.load_fit(tmp_path / "bad.json")
