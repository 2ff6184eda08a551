"""The bundled UR10e and Panda files against their makers' kinematics, written out independently.

UR publishes a standard DH table (T_i = Rz Tz Tx Rx), Franka a modified DH (Craig) table with a
flange row; both with theta_i = q_i, the controller's angles. The robot files hold the
Khalil-Kleinfinger conversion; these tests multiply the makers' tables in numpy and compare.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import rx90sym
from rx90sym.pinocchio_bridge import pinocchio_model

from conftest import random_chi, random_states

URDF_DIR = Path(__file__).parent / "data" / "urdf"
P = math.pi

# UR10e, UR's published standard DH (../shared/data/ur10e/README.md): (d, a, alpha) per joint.
UR10E_DH = [(0.1807, 0.0, P / 2), (0.0, -0.6127, 0.0), (0.0, -0.57155, 0.0),
            (0.17415, 0.0, P / 2), (0.11985, 0.0, -P / 2), (0.11655, 0.0, 0.0)]
# Panda, Franka's published modified DH (Craig): (a, d, alpha) per row; the last row is the flange.
PANDA_MDH = [(0.0, 0.333, 0.0), (0.0, 0.0, -P / 2), (0.0, 0.316, P / 2), (0.0825, 0.0, P / 2),
             (-0.0825, 0.384, -P / 2), (0.0, 0.0, P / 2), (0.088, 0.0, P / 2), (0.0, 0.107, 0.0)]


def _rz(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _rx(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _tz(x):
    T = np.eye(4)
    T[2, 3] = x
    return T


def _tx(x):
    T = np.eye(4)
    T[0, 3] = x
    return T


def ur_standard_dh(q):
    """UR's frames 0..6 (the base, then after each joint) for controller angles q."""
    frames = [np.eye(4)]
    for (d, a, alpha), qi in zip(UR10E_DH, q):
        frames.append(frames[-1] @ _rz(qi) @ _tz(d) @ _tx(a) @ _rx(alpha))
    return frames


def franka_modified_dh(q):
    """Franka's frames 1..7 and the flange for controller angles q (the flange has theta = 0)."""
    frames, T = [], np.eye(4)
    for (a, d, alpha), qi in zip(PANDA_MDH, list(q) + [0.0]):
        T = T @ _rx(alpha) @ _tx(a) @ _rz(qi) @ _tz(d)
        frames.append(T)
    return frames


def _model_frame(robot, q_model, j):
    """Pose of the toolkit's frame j (1-based) in frame 0: its own forward kinematics of rows 1..j."""
    rows = list(zip(robot.sigma, robot.alpha, robot.d, robot.theta, robot.r))[:j]
    return np.array(rx90sym.robot_from_table(rows).forward_kinematics(q_model[:j])[0])


def _controller_samples(robot, seed, count):
    """Random controller joint angles inside the robot's (finite) position limits."""
    lo, hi = robot.to_controller(robot.limits.q_min), robot.to_controller(robot.limits.q_max)
    return np.random.default_rng(seed).uniform(lo, hi, (count, robot.n))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_ur10e_flange_and_joint_axes_are_urs_standard_dh(seed):
    robot = rx90sym.load_robot("ur10e")
    for q in _controller_samples(robot, seed, 10):
        q_model = robot.to_model(q)
        ur = ur_standard_dh(q)
        T = np.array(robot.forward_kinematics(q_model)[0])
        np.testing.assert_allclose(T, ur[6], rtol=0, atol=1e-12)   # the tool flange
        for j in range(1, robot.n + 1):
            # Khalil's z_j is joint j's axis: UR's z_(j-1), through UR's origin O_(j-1).
            K = _model_frame(robot, q_model, j)
            np.testing.assert_allclose(K[:3, 2], ur[j - 1][:3, 2], rtol=0, atol=1e-12)
            offset = K[:3, 3] - ur[j - 1][:3, 3]
            np.testing.assert_allclose(np.cross(offset, K[:3, 2]), 0.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_panda_frames_and_flange_are_frankas_modified_dh(seed):
    robot = rx90sym.load_robot("panda")
    for q in _controller_samples(robot, seed, 10):
        q_model = robot.to_model(q)
        franka = franka_modified_dh(q)
        for j in range(1, robot.n):       # Craig's frames 1..6 are Khalil's frames 1..6
            np.testing.assert_allclose(_model_frame(robot, q_model, j), franka[j - 1], rtol=0, atol=1e-12)
        T = np.array(robot.forward_kinematics(q_model)[0])
        np.testing.assert_allclose(T, franka[-1], rtol=0, atol=1e-12)   # frame 7 is the flange


def test_panda_file_matches_franka_descriptions_urdf():
    """franka_description's URDF (another publication of the maker, in the controller's angles):
    the same flange pose, the same limits, and with its inertials moved into the file's frames the
    same torques as Pinocchio's rnea on the URDF (hand and fingers locked on link 8)."""
    robot = rx90sym.load_robot("panda")
    full = pin.buildModelFromUrdf(str(URDF_DIR / "panda.urdf"))
    arm = [f"panda_joint{j}" for j in range(1, 8)]
    lock = [i for i in range(1, full.njoints) if full.names[i] not in arm]
    model = pin.buildReducedModel(full, lock, pin.neutral(full))
    data = model.createData()
    flange = model.getFrameId("panda_link8")

    lower, upper = model.lowerPositionLimit, model.upperPositionLimit
    np.testing.assert_allclose(robot.to_controller(robot.limits.q_min), lower, atol=1e-12)
    np.testing.assert_allclose(robot.to_controller(robot.limits.q_max), upper, atol=1e-12)
    np.testing.assert_allclose(robot.limits.qd_max, model.velocityLimit, atol=1e-12)
    np.testing.assert_allclose(robot.limits.tau_max, model.effortLimit, atol=1e-12)

    # Each link's inertia, from its URDF joint frame into the file's frame j (a constant pose).
    zero = np.zeros(robot.n)
    pin.framesForwardKinematics(model, data, zero)
    chi = np.zeros(len(robot.parameter_names))
    for j in range(1, robot.n + 1):
        K = pin.SE3(_model_frame(robot, robot.to_model(zero), j))
        inertia = model.inertias[j].se3ActionInverse(data.oMi[j].actInv(K))
        m, mx, my, mz, ixx, ixy, iyy, ixz, iyz, izz = inertia.toDynamicParameters()
        chi[13 * (j - 1):13 * (j - 1) + 10] = [ixx, ixy, ixz, iyy, iyz, izz, mx, my, mz, m]

    rng = np.random.default_rng(3)
    for q in _controller_samples(robot, 4, 8):
        pin.framesForwardKinematics(model, data, q)
        T = np.array(robot.forward_kinematics(robot.to_model(q))[0])
        np.testing.assert_allclose(T, data.oMf[flange].homogeneous, rtol=0, atol=1e-12)
        qd, qdd = rng.normal(0, 1.5, robot.n), rng.normal(0, 3, robot.n)
        ref = pin.rnea(model, data, q, qd, qdd)
        tau = np.array(robot.inverse_dynamics(robot.to_model(q), qd, qdd, chi)).ravel()
        assert np.abs(tau - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max())


@pytest.mark.parametrize("name", ["ur10e", "panda"])
def test_inverse_dynamics_equals_pinocchio_at_random_parameters(name):
    robot = rx90sym.load_robot(name)
    rng = np.random.default_rng(5)
    for _ in range(3):
        chi = random_chi(robot, rng, actuation=False)
        model = pinocchio_model(robot, chi)
        data = model.createData()
        for q, qd, qdd in zip(*random_states(robot, rng, 4)):
            tau = np.array(robot.inverse_dynamics(q, qd, qdd, chi)).ravel()
            ref = pin.rnea(model, data, q, qd, qdd)
            assert np.abs(tau - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max())


@pytest.mark.parametrize("name, n, flange_at_zero", [
    # UR10e stretched along -x0 (a2 + a3), wrists offset along -y0 (d4 + d6), up d1 - d5;
    # Panda: a7 forward, d1 + d3 + d5 - flange up (the flange points down at q = 0).
    ("ur10e", 6, (-0.6127 - 0.57155, -0.17415 - 0.11655, 0.1807 - 0.11985)),
    ("panda", 7, (0.088, 0.0, 0.333 + 0.316 + 0.384 - 0.107)),
])
def test_bundled_by_name_on_the_command_line(name, n, flange_at_zero, tmp_path):
    """``--robot NAME`` resolves the bundled file like rx90/tx40; zero angles are the makers' zero pose."""
    from identify.app.cli import main

    robot = rx90sym.load_robot(name)
    assert name in rx90sym.bundled_robots() and robot.n == n
    np.testing.assert_array_equal(robot.controller_offsets, np.zeros(n))
    T = np.array(robot.forward_kinematics(np.zeros(n))[0])
    np.testing.assert_allclose(T[:3, 3], flange_at_zero, atol=1e-12)
    out = tmp_path / "model.json"
    assert main(["model", "--robot", name, "--base", "--json", str(out)]) == 0
    summary = json.loads(out.read_text())
    assert summary["robot"] == name and summary["n"] == n
