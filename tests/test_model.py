"""The symbolic model against independent oracles: Pinocchio, power balance, the paper's forms."""
from __future__ import annotations

import subprocess
import shutil

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

import rx90sym
from rx90sym.compiled import BatchFunction
from rx90sym.pinocchio_bridge import pinocchio_columns, pinocchio_model

from conftest import random_chi, random_states

ROBOTS = ["rx90", "tx40", "random"]


def _robot(name, rx90, tx40, random_robot):
    return {"rx90": rx90, "tx40": tx40, "random": random_robot}[name]


@pytest.mark.parametrize("name", ROBOTS)
def test_rigid_body_part_equals_pinocchio_rnea(name, rx90, tx40, random_robot):
    robot = _robot(name, rx90, tx40, random_robot)
    rng = np.random.default_rng(1)
    for _ in range(5):
        chi = random_chi(robot, rng, actuation=False)
        model = pinocchio_model(robot, chi)
        data = model.createData()
        Q, QD, QDD = random_states(robot, rng, 4)
        for q, qd, qdd in zip(Q, QD, QDD):
            ours = np.array(robot.inverse_dynamics(q, qd, qdd, chi)).ravel()
            ref = pin.rnea(model, data, q, qd, qdd)
            assert np.max(np.abs(ours - ref)) < 1e-9 * max(1.0, np.max(np.abs(ref)))


@pytest.mark.parametrize("name", ROBOTS)
def test_regressor_times_chi_is_the_idm_and_matches_pinocchio_regressor(name, rx90, tx40, random_robot):
    robot = _robot(name, rx90, tx40, random_robot).with_options(offsets=True)
    rng = np.random.default_rng(2)
    chi = random_chi(robot, rng)
    model = pinocchio_model(robot, chi)
    data = model.createData()
    cols = pinocchio_columns(robot)
    for q, qd, qdd in zip(*random_states(robot, rng, 6)):
        Phi = np.array(robot.regressor(q, qd, qdd))
        tau = np.array(robot.inverse_dynamics(q, qd, qdd, chi)).ravel()
        assert np.max(np.abs(Phi @ chi - tau)) < 1e-9 * max(1.0, np.abs(tau).max())
        Y = pin.computeJointTorqueRegressor(model, data, q, qd, qdd)
        assert np.max(np.abs(Phi[:, cols] - Y)) < 1e-9 * max(1.0, np.abs(Y).max())


def test_power_balance_along_a_trajectory(rx90):
    """qd'(Gamma - G(q)) = dE/dt with E = 1/2 qd' M(q) qd, friction left out (chi_f = 0)."""
    robot = rx90
    rng = np.random.default_rng(3)
    chi = random_chi(robot, rng)
    for j in range(robot.n):
        chi[13 * j + 11:13 * j + 13] = 0.0
    chi[13 * robot.n:] = 0.0
    q, qd, qdd = (ca.SX.sym(s, robot.n) for s in ("q", "qd", "qdd"))
    tau = robot.inverse_dynamics(q, qd, qdd, chi)
    M = ca.Function("M", [q], [ca.jacobian(tau, qdd)])
    idm = robot.inverse_dynamics
    a = rng.uniform(0.3, 1.0, robot.n)
    w = rng.uniform(0.5, 2.0, robot.n)

    def traj(t):
        return a * np.sin(w * t), a * w * np.cos(w * t), -a * w**2 * np.sin(w * t)

    h = 1e-4
    worst = 0.0
    for t in np.linspace(0.1, 3.0, 12):
        qt, qdt, qddt = traj(t)
        power = qdt @ (np.array(idm(qt, qdt, qddt, chi)).ravel()
                       - np.array(idm(qt, 0 * qt, 0 * qt, chi)).ravel())

        def energy(s):
            qs, qds, _ = traj(s)
            return 0.5 * qds @ np.array(M(qs)) @ qds

        dE = (energy(t + h) - energy(t - h)) / (2 * h)
        worst = max(worst, abs(power - dE) / max(1.0, abs(power)))
    assert worst < 1e-6


def test_actuation_terms_have_the_papers_form(rx90):
    """Friction eq. 5, rotor inertia, the 5-6 coupling eqs. 16-18 and offsets."""
    rng = np.random.default_rng(4)
    robot = rx90.with_options(offsets=True)
    names = list(robot.parameter_names)
    q, qd, qdd = rng.normal(size=(3, 6))
    Phi = np.array(robot.regressor(q, qd, qdd))
    for j in range(6):
        e = np.eye(6)[j]
        assert np.allclose(Phi[:, names.index(f"FS{j+1}")], np.sign(qd[j]) * e)
        assert np.allclose(Phi[:, names.index(f"FV{j+1}")], qd[j] * e)
        assert np.allclose(Phi[:, names.index(f"OFF{j+1}")], e)
        if j != 5:
            assert np.allclose(Phi[:, names.index(f"IA{j+1}")], qdd[j] * e)
    # IA6 in both wrist rows (eqs. 17-18): row 5 gets qdd6, row 6 gets qdd5.
    assert np.allclose(Phi[:, names.index("IA6")], [0, 0, 0, 0, qdd[5], qdd[5] + qdd[4]])
    assert np.allclose(Phi[:, names.index("FVM6")], [0, 0, 0, 0, qd[5], qd[4]])
    assert np.allclose(Phi[:, names.index("FSM6")], [0, 0, 0, 0, np.sign(qd[5]), np.sign(qd[4])])
    motor = rx90sym.load_robot("rx90", coulomb_sign="motor")
    Phi_m = np.array(motor.regressor(q, qd, qdd))
    s = np.sign(qd[4] + qd[5])
    assert np.allclose(Phi_m[:, names.index("FSM6")], [0, 0, 0, 0, s, s])


def test_spring_torque_is_minus_the_gradient_of_its_energy(rx90):
    sp = rx90.spring
    k, a, b, L0 = sp.k, sp.a, sp.b, sp.L0

    def energy(q2):
        ts = q2 + np.pi / 2
        L = np.sqrt(a * a + b * b - 2 * a * b * np.cos(ts))
        return 0.5 * k * (L - L0) ** 2

    for q2 in np.linspace(-2.0, 2.0, 9):
        q = np.zeros(6)
        q[1] = q2
        tau = np.array(rx90.spring_torque(q)).ravel()
        h = 1e-6
        assert abs(tau[1] + (energy(q2 + h) - energy(q2 - h)) / (2 * h)) < 1e-5
        assert np.all(tau[[0, 2, 3, 4, 5]] == 0)
    Q = np.random.default_rng(0).uniform(-1, 1, (5, 6))
    assert np.allclose(rx90.spring_torque_batch(Q)[:, :, 0],
                       [np.array(rx90.spring_torque(x)).ravel() for x in Q])


def test_spring_from_a_table(tmp_path):
    src = open(rx90sym.robot_file.ROBOTS_DIR / "rx90.toml").read()
    angles = np.linspace(-3, 3, 61)
    (tmp_path / "spring.csv").write_text("angle,torque\n" + "\n".join(f"{x},{-50 * np.sin(x)}" for x in angles))
    # A table replaces the model's constants (giving both is refused).
    (tmp_path / "mine.toml").write_text(src[:src.index("[spring]")] + '[spring]\njoint = 2\ntable = "spring.csv"\n')
    robot = rx90sym.load_robot(tmp_path / "mine.toml")
    q = np.zeros(6)
    q[1] = 0.5  # on a grid point, linear interpolation is exact
    assert abs(float(robot.spring_torque(q)[1]) + 50 * np.sin(0.5)) < 1e-12


def test_forward_kinematics_matches_pinocchio(rx90, random_robot):
    for robot in (rx90, random_robot):
        model = pinocchio_model(robot)
        data = model.createData()
        q = np.random.default_rng(5).uniform(-2, 2, robot.n)
        pin.forwardKinematics(model, data, q)
        T = np.array(robot.forward_kinematics(q)[0])
        assert np.allclose(T, data.oMi[robot.n].homogeneous, atol=1e-12)
        assert np.allclose(robot.frame_origins(q), [data.oMi[j].translation for j in range(1, robot.n + 1)])


def test_rx90_reach_is_the_datasheet_one(rx90):
    # Arm stretched up (Staubli zero = vertical): wrist centre at D3 + RL4 = 0.9 m above the shoulder.
    q = rx90.to_model(np.zeros(6))
    assert np.isclose(rx90.frame_origins(q)[4, 2], 0.9)


def test_batch_regressor_compiled_and_vm_agree_with_single_calls(rx90):
    rng = np.random.default_rng(6)
    Q, QD, QDD = random_states(rx90, rng, 50)
    B = rx90.regressor_batch(Q, QD, QDD)
    vm = BatchFunction(rx90.regressor, name="vm_check", compile=False)(Q, QD, QDD)
    for i in (0, 17, 49):
        single = np.array(rx90.regressor(Q[i], QD[i], QDD[i]))
        assert np.array_equal(B[i], single) or np.allclose(B[i], single, rtol=1e-14, atol=1e-12)
    assert np.allclose(vm, B, rtol=1e-13, atol=1e-12)
    with pytest.raises(ValueError, match="different numbers of samples"):
        rx90.regressor_batch(Q, QD[:3], QDD)


@pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler")
def test_exported_c_compiles(rx90, tmp_path):
    paths = rx90.export_c(str(tmp_path))
    c_files = [p for p in paths if p.endswith(".c")]
    assert c_files and any(p.endswith(".h") for p in paths)
    cc = shutil.which("cc") or shutil.which("gcc")
    proc = subprocess.run([cc, "-c", c_files[0], "-o", str(tmp_path / "m.o")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr


def test_conventions_and_table_robot(rx90):
    q = np.random.default_rng(7).normal(size=(4, 6))
    assert np.allclose(rx90.to_model(rx90.to_controller(q)), q)
    assert np.allclose(rx90.to_controller(np.zeros(6)), [0, np.pi / 2, -np.pi / 2, 0, 0, 0])
    assert len(rx90.parameter_names) == 80 and rx90.parameter_names[-2:] == ("FVM6", "FSM6")
    tx = rx90sym.load_robot("tx40", offsets=True)
    assert tx.parameter_names[-6:] == tuple(f"OFF{j}" for j in range(1, 7))
    mine = rx90sym.robot_from_table([(0, 0, 0, 0, 0), (1, np.pi / 2, 0.1, 0, 0.2)], name="mine")
    assert mine.n == 2 and len(mine.parameter_names) == 26 and mine.coupling is None


def test_tx40_transmission_matches_its_readme(tx40):
    N = np.array([32, 32, 45, -48, 45, 32.0])
    Rq = np.diag(N)
    Rq[5, 4] = N[5]
    Rt = np.diag(N)
    Rt[4, 5] = N[5]
    assert np.array_equal(tx40.Rq, Rq) and np.array_equal(tx40.Rt, Rt)


def test_without_a_c_compiler_the_batch_falls_back_to_casadi_vm(rx90, monkeypatch):
    monkeypatch.setenv("CC", "/nonexistent/cc")
    with pytest.warns(RuntimeWarning, match="C compilation unavailable"):
        f = BatchFunction(rx90.regressor, name="no_compiler_check")
    assert f.backend == "casadi-vm"
    Q, QD, QDD = random_states(rx90, np.random.default_rng(9), 7)
    assert np.allclose(f(Q, QD, QDD), rx90.regressor_batch(Q, QD, QDD), rtol=1e-13, atol=1e-12)


def test_regressor_workspace_reuses_its_memory_and_streams_the_same_numbers(rx90, rx90_base):
    Q, QD, QDD = random_states(rx90, np.random.default_rng(11), 700)
    ws = rx90_base.regressor_workspace(chunk=256)
    first = ws.evaluate(Q, QD, QDD)
    expected = rx90_base.regressor_batch(Q, QD, QDD)
    assert np.array_equal(first, expected)
    again = ws.evaluate(Q[:500], QD[:500], QDD[:500])  # fewer samples: same memory, no new array
    assert np.shares_memory(first, again) and np.array_equal(again, expected[:500])
    blocks = [(start, block.copy()) for start, block in ws.chunks(Q, QD, QDD)]
    assert [s for s, _ in blocks] == [0, 256, 512]
    assert np.array_equal(np.concatenate([b for _, b in blocks]), expected)
    with pytest.raises(ValueError, match="chunk must be >= 1"):
        rx90.regressor_workspace(chunk=0)
