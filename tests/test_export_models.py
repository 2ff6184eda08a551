"""Exported URDF and MJCF against the toolkit's own inverse dynamics, through Pinocchio and MuJoCo.

The exported files are driven by the controller's joint angles (the recordings'); the reference
is ``robot.inverse_dynamics`` at the corresponding model angles with the same parameters.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import rx90sym
from rx90sym.mjcf_export import write_mjcf
from rx90sym.model_export import export_joint_names, joint_terms

from conftest import random_chi

mujoco = pytest.importorskip("mujoco", reason="MuJoCo export tests need the mujoco extra (pip install '.[mujoco]')")

URDF_DIR = Path(__file__).parent / "data" / "urdf"


def moving_states(robot, rng, count):
    """Random controller-angle states with every joint velocity away from 0 (Coulomb defined)."""
    q = rng.uniform(-np.pi, np.pi, (count, robot.n))
    qd = rng.uniform(0.2, 2.0, (count, robot.n)) * rng.choice([-1.0, 1.0], (count, robot.n))
    return q, qd, rng.normal(0, 4.0, (count, robot.n))


def urdf_robot():
    return rx90sym.load_robot(URDF_DIR / "ur10_robot.urdf", tip="tool0")


def urdf_chi(robot, rng):
    """The URDF's own inertials (the lumped children must stay physical) with random bodies on
    the links without children, and random actuation terms."""
    chi = robot.parameter_vector(rx90sym.nominal_parameters(robot))
    other = random_chi(robot, rng)
    for j in range(robot.n):
        chi[13 * j + 10:13 * j + 13] = other[13 * j + 10:13 * j + 13]
        chi[13 * j:13 * j + 10] *= rng.uniform(0.7, 1.3)   # still a body: a positive multiple
    return chi


def coupling_terms(robot, qd, qdd, chi):
    """Eqs. 17-18's extra terms (excluded from a URDF's torques, documented in its companion)."""
    out = np.zeros(robot.n)
    if robot.coupling is None:
        return out
    names = list(robot.parameter_names)
    a, b = robot.coupling.joints
    ia, fvm, fsm = (chi[names.index(f"{k}{b + 1}")] for k in ("IA", "FVM", "FSM"))
    sa, sb = (np.sign(qd[b]), np.sign(qd[a])) if robot.coupling.coulomb_sign == "paper" else (
        np.sign(qd[a] + qd[b]),) * 2
    out[a] = ia * qdd[b] + fvm * qd[b] + fsm * sa
    out[b] = ia * qdd[a] + fvm * qd[a] + fsm * sb
    return out


def pinocchio_of(path: Path, robot) -> tuple:
    full = pin.buildModelFromUrdf(str(path))
    keep = set(export_joint_names(robot))
    lock = [i for i in range(1, full.njoints) if full.names[i] not in keep]
    model = pin.buildReducedModel(full, lock, pin.neutral(full)) if lock else full
    return model, model.createData()


@pytest.mark.parametrize("case", ["ur10e", "rx90", "urdf"])
def test_urdf_torques_equal_the_fits_inverse_dynamics(tmp_path, case):
    rng = np.random.default_rng(11)
    robot = urdf_robot() if case == "urdf" else rx90sym.load_robot(case)
    chi = urdf_chi(robot, rng) if case == "urdf" else random_chi(robot, rng)
    model_file, side = rx90sym.write_urdf(robot, chi, tmp_path / "arm.urdf")
    IA = np.array([v["IA"] for v in json.loads(side.read_text())["joints"].values()])
    model, data = pinocchio_of(model_file, robot)
    assert model.nq == robot.n
    for qc, qd, qdd in zip(*moving_states(robot, rng, 6)):
        tau = pin.rnea(model, data, qc, qd, qdd) + IA * qdd + model.damping * qd + model.friction * np.sign(qd)
        ref = np.array(robot.inverse_dynamics(robot.to_model(qc), qd, qdd, chi)).ravel()
        ref -= coupling_terms(robot, qd, qdd, chi)
        assert np.abs(tau - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max())


def test_a_tilted_gravity_gets_a_root_that_points_it_down(tmp_path):
    rng = np.random.default_rng(3)
    robot = rx90sym.load_robot("ur10e").with_options(gravity=(2.0, -3.0, -9.0))
    chi = random_chi(robot, rng)
    model, data = pinocchio_of(rx90sym.write_urdf(robot, chi, tmp_path / "t.urdf")[0], robot)
    model.gravity.linear[:] = (0.0, 0.0, -np.linalg.norm(robot.gravity_vector))
    chi[[13 * j + k for j in range(robot.n) for k in (10, 11, 12)]] = 0.0   # rigid body only
    for qc, qd, qdd in zip(*moving_states(robot, rng, 4)):
        ref = np.array(robot.inverse_dynamics(robot.to_model(qc), qd, qdd, chi)).ravel()
        assert np.abs(pin.rnea(model, data, qc, qd, qdd) - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max())


def _mujoco(path: Path):
    model = mujoco.MjModel.from_xml_path(str(path))
    # Contacts, limits and frictionloss (a constraint in MuJoCo) off: the smooth dynamics only.
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT | mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS)
    return model, mujoco.MjData(model)


def _without_coulomb(robot, chi):
    chi = chi.copy()
    chi[[i for i, n in enumerate(robot.parameter_names) if n.startswith("FS")]] = 0.0
    return chi


@pytest.mark.parametrize("case", ["ur10e", "rx90", "urdf"])
def test_mujoco_inverse_and_forward_dynamics_equal_the_fits(tmp_path, case):
    rng = np.random.default_rng(12)
    robot = urdf_robot() if case == "urdf" else rx90sym.load_robot(case)
    chi = urdf_chi(robot, rng) if case == "urdf" else random_chi(robot, rng)
    if robot.coupling is not None:
        chi = exact_tendon(robot, chi)
    model, data = _mujoco(write_mjcf(robot, chi, tmp_path / "arm.xml")[0])
    smooth = _without_coulomb(robot, chi)
    for qc, qd, qdd in zip(*moving_states(robot, rng, 6)):
        q = robot.to_model(qc)
        data.qpos[:], data.qvel[:], data.qacc[:] = qc, qd, qdd
        mujoco.mj_inverse(model, data)
        ref = np.array(robot.inverse_dynamics(q, qd, qdd, smooth)).ravel()
        assert np.abs(data.qfrc_inverse - ref).max() <= 1e-8 * max(1.0, np.abs(ref).max())
        # Forward: the fit's M(q) qdd = tau - h(q, qd) under applied joint torques.
        tau = rng.normal(0, 20.0, robot.n)
        h = np.array(robot.inverse_dynamics(q, qd, np.zeros(robot.n), smooth)).ravel()
        M = np.column_stack([np.array(robot.inverse_dynamics(q, np.zeros(robot.n), e, smooth)).ravel()
                             - np.array(robot.inverse_dynamics(q, np.zeros(robot.n), np.zeros(robot.n), smooth)).ravel()
                             for e in np.eye(robot.n)])
        expected = np.linalg.solve(M, tau - h)
        data.qpos[:], data.qvel[:], data.qfrc_applied[:], data.ctrl[:] = qc, qd, tau, 0.0
        mujoco.mj_forward(model, data)
        assert np.abs(data.qacc - expected).max() <= 1e-8 * max(1.0, np.abs(expected).max())


@pytest.mark.parametrize("options", [{"offsets": True}, {"asymmetric_coulomb": (0, 2)}])
def test_torque_offsets_and_asymmetric_coulomb_are_constant_actuator_forces(tmp_path, options):
    """The MJCF's actuators constantj: the fit's torques give its accelerations while every joint moves
    (frictionloss off: its mean Coulomb term taken off the torques as MuJoCo would apply it)."""
    rng = np.random.default_rng(13)
    robot = rx90sym.load_robot("ur10e").with_options(**options)
    chi = random_chi(robot, rng)
    model, data = _mujoco(write_mjcf(robot, chi, tmp_path / "arm.xml")[0])
    assert model.nu == robot.n + (robot.n if robot.offsets else len(robot.asymmetric_coulomb))
    _, _, mean_coulomb = joint_terms(robot, chi)
    for qc, qd, qdd in zip(*moving_states(robot, rng, 4)):
        tau = np.array(robot.inverse_dynamics(robot.to_model(qc), qd, qdd, chi)).ravel()
        data.qpos[:], data.qvel[:], data.qfrc_applied[:], data.ctrl[:] = qc, qd, tau - mean_coulomb * np.sign(qd), 0.0
        mujoco.mj_forward(model, data)
        assert np.abs(data.qacc - qdd).max() <= 1e-8 * max(1.0, np.abs(qdd).max())


def test_mjcf_holds_the_actuators_limits_gravity_and_flange(tmp_path):
    robot = rx90sym.load_robot("rx90")
    chi = robot.parameter_vector(rx90sym.nominal_parameters(robot))
    model, data = _mujoco(write_mjcf(robot, chi, tmp_path / "rx90.xml")[0])
    np.testing.assert_allclose(model.opt.gravity, robot.gravity_vector)
    np.testing.assert_allclose(model.actuator_ctrlrange[:, 1], robot.limits.tau_max)
    lower, upper = robot.to_controller(robot.limits.q_min), robot.to_controller(robot.limits.q_max)
    np.testing.assert_allclose(model.jnt_range, np.column_stack([lower, upper]))
    names = list(robot.parameter_names)
    assert model.tendon_armature[0] == pytest.approx(chi[names.index("IA6")])
    # The flange site: 85 mm beyond the wrist centre along z6 (the RX90's [flange]).
    qc = np.radians([10, 20, -30, 40, 50, 60])
    data.qpos[:] = qc
    mujoco.mj_kinematics(model, data)
    T = np.array(robot.forward_kinematics(robot.to_model(qc))[0])
    site = data.site_xpos[model.site("flange").id]
    np.testing.assert_allclose(site, T[:3, 3] + 0.085 * T[:3, 2], atol=1e-12)


def exact_tendon(robot, chi):
    """chi with the joint parts of eqs. 17-18 >= 0, so that the MJCF tendon is exact."""
    names = list(robot.parameter_names)
    chi = chi.copy()
    chi[names.index("IA5")] = chi[names.index("IA6")] + 0.2
    for j in (5, 6):
        chi[names.index(f"FV{j}")] = chi[names.index("FVM6")] + 0.1
    return chi


def test_a_payload_is_a_body_on_the_flange(tmp_path):
    """With --payload: the same torques as the fit's robot whose link n carries the payload."""
    rng = np.random.default_rng(4)
    robot = rx90sym.load_robot("rx90")
    chi = exact_tendon(robot, random_chi(robot, rng))
    load = rx90sym.load_payload("tables_4")
    both = rx90sym.add_payload(robot, chi, load)
    model, data = pinocchio_of(rx90sym.write_urdf(robot, chi, tmp_path / "p.urdf", payload=load)[0], robot)
    mj, mjd = _mujoco(write_mjcf(robot, chi, tmp_path / "p.xml", payload=load)[0])
    IA = chi[[13 * j + 10 for j in range(robot.n)]]
    for qc, qd, qdd in zip(*moving_states(robot, rng, 3)):
        q = robot.to_model(qc)
        ref = np.array(robot.inverse_dynamics(q, qd, qdd, both)).ravel() - coupling_terms(robot, qd, qdd, both)
        tau = pin.rnea(model, data, qc, qd, qdd) + IA * qdd + model.damping * qd + model.friction * np.sign(qd)
        assert np.abs(tau - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max())
        mjd.qpos[:], mjd.qvel[:], mjd.qacc[:] = qc, qd, qdd
        mujoco.mj_inverse(mj, mjd)
        ref = np.array(robot.inverse_dynamics(q, qd, qdd, _without_coulomb(robot, both))).ravel()
        assert np.abs(mjd.qfrc_inverse - ref).max() <= 1e-8 * max(1.0, np.abs(ref).max())


@pytest.mark.parametrize("writer", ["urdf", "mjcf"])
def test_a_non_physical_link_is_refused_and_nothing_written(tmp_path, writer):
    robot = rx90sym.load_robot("ur10e")
    chi = random_chi(robot, np.random.default_rng(0))
    chi[13 * 2 + 9] = -1.0   # M3 < 0
    out = tmp_path / f"x.{writer}"
    with pytest.raises(ValueError, match="link 3: not a physical rigid body"):
        (rx90sym.write_urdf if writer == "urdf" else write_mjcf)(robot, chi, out)
    assert list(tmp_path.iterdir()) == []
