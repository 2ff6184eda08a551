"""The MJCF of a URDF robot sits where the URDF does: its world frame is the URDF root.

MuJoCo's poses of the URDF links (the sites the export puts at each link's frame) against
Pinocchio's on the URDF itself, 10 random configurations, 1e-9 m; gravity the same vector."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import rx90sym

mujoco = pytest.importorskip("mujoco", reason="MuJoCo export tests need the mujoco extra (pip install '.[mujoco]')")
pin = pytest.importorskip("pinocchio")

DATA = Path(__file__).parent / "data" / "urdf"


@pytest.mark.parametrize("name", ["ur5.urdf", "ur10_robot.urdf"])
def test_mjcf_world_is_the_urdf_root(name, tmp_path):
    path = DATA / name
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the URDF's missing acceleration limits
        robot = rx90sym.load_robot(str(path), tip="tool0")
    chi = robot.parameter_vector(rx90sym.urdf_parameters(robot))
    xml = tmp_path / "arm.xml"
    rx90sym.write_mjcf(robot, chi, xml)
    model = mujoco.MjModel.from_xml_path(str(xml))
    data = mujoco.MjData(model)
    pmodel = pin.buildModelFromUrdf(str(path))
    pdata = pmodel.createData()
    assert np.allclose(model.opt.gravity, [0.0, 0.0, -9.81], atol=1e-12)
    links = robot.urdf.links
    rng = np.random.default_rng(0)
    lo = np.maximum(robot.limits.q_min, -np.pi) + robot.controller_offsets
    hi = np.minimum(robot.limits.q_max, np.pi) + robot.controller_offsets
    for _ in range(10):
        q = rng.uniform(lo, hi)  # controller angles = the URDF's joint values
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        pin.framesForwardKinematics(pmodel, pdata, q)
        for link in links:
            site = model.site(link).id
            frame = pdata.oMf[pmodel.getFrameId(link)]
            assert np.abs(data.site_xpos[site] - frame.translation).max() <= 1e-9, link
            assert np.abs(data.site_xmat[site].reshape(3, 3) - frame.rotation).max() <= 1e-9, link
