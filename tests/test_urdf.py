"""URDF import and export against Pinocchio (an independent parser and dynamics) and by hand."""
from __future__ import annotations

import math
import re
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import rx90sym
from rx90sym import UrdfError, load_urdf, urdf_parameters, write_urdf
from rx90sym.urdf_export import companion_path

from conftest import random_body

DATA = Path(__file__).parent / "data" / "urdf"
ARMS = [("ur10_robot.urdf", "tool0"), ("panda.urdf", "panda_link8"),
        ("kinova.urdf", "j2s6s200_end_effector")]


def _load(path, tip, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the default acceleration limits warning
        return load_urdf(path, tip, **kw)


def _pinocchio_chain(path, robot):
    """Pinocchio's model of the URDF, every joint off the chain locked at 0 (buildReducedModel)."""
    model = pin.buildModelFromUrdf(str(path))
    keep = set(robot.urdf.joints)
    lock = [i for i in range(1, model.njoints) if model.names[i] not in keep]
    reduced = pin.buildReducedModel(model, lock, pin.neutral(model))
    assert [reduced.names[i] for i in range(1, reduced.njoints)] == list(robot.urdf.joints)
    return reduced


def _pin_q(model, q):
    """Pinocchio's configuration of joint angles q (continuous joints are (cos, sin))."""
    out = []
    for i in range(1, model.njoints):
        out += [math.cos(q[i - 1]), math.sin(q[i - 1])] if model.joints[i].nq == 2 else [q[i - 1]]
    return np.array(out)


def _rigid(robot, chi):
    """chi without friction and rotor inertia (Pinocchio's rnea has neither)."""
    chi = np.array(chi, dtype=float)
    for j in range(robot.n):
        chi[13 * j + 10:13 * j + 13] = 0.0
    return chi


def _max_torque_error(robot, chi, model, seed, samples=6):
    """max over random states of ||tau - rnea||_inf / max(1 N m, ||rnea||_inf)."""
    rng = np.random.default_rng(seed)
    data = model.createData()
    worst = 0.0
    for _ in range(samples):
        q, qd, qdd = rng.uniform(-np.pi, np.pi, robot.n), rng.normal(0, 1.5, robot.n), rng.normal(0, 3, robot.n)
        tau = np.array(robot.inverse_dynamics(q, qd, qdd, chi)).ravel()
        ref = pin.rnea(model, data, _pin_q(model, q), qd, qdd)
        worst = max(worst, np.abs(tau - ref).max() / max(1.0, np.abs(ref).max()))
    return worst


@pytest.mark.parametrize("name,tip", ARMS)
def test_imported_parameters_give_pinocchio_torques(name, tip):
    robot = _load(DATA / name, tip)
    chi = _rigid(robot, robot.parameter_vector(urdf_parameters(robot)))
    model = _pinocchio_chain(DATA / name, robot)
    for seed in range(3):
        assert _max_torque_error(robot, chi, model, seed) <= 1e-9


def test_hand_and_fingers_beyond_the_tip_are_lumped_into_link_7():
    robot = _load(DATA / "panda.urdf", "panda_link8")
    assert robot.n == 7
    assert {"panda_hand", "panda_leftfinger", "panda_rightfinger"} <= set(robot.urdf.lumped[6])
    # Total mass: the arm's links plus the hand and fingers, nothing of the fixed base.
    masses = {l: b.m for l, b in robot.urdf.tree.inertials.items()}
    expected = sum(m for l, m in masses.items() if l != "panda_link0")
    assert sum(urdf_parameters(robot)[f"M{j}"] for j in range(1, 8)) == pytest.approx(expected, rel=1e-12)


def test_limits_friction_and_continuous_joints_come_from_the_urdf():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the assumed accelerations are said by excite and simulate, not here
        panda = load_urdf(DATA / "panda.urdf", "panda_link8")
    assert panda.limits.q_min[0] == -2.8973 and panda.limits.q_max[3] == -0.0698
    assert panda.limits.tau_max[0] == 87.0 and panda.limits.qd_max[6] == 2.61
    # No acceleration in a URDF: 2 x the velocity limit, at most 10 rad/s^2 (2.61 rad/s -> 5.22; 2.175 -> 4.35).
    np.testing.assert_allclose(panda.limits.qdd_max, np.minimum(2 * panda.limits.qd_max, 10.0), rtol=0)
    from rx90sym.urdf import default_acceleration

    assert panda.limits.qdd_max[6] == 5.22 and default_acceleration(panda)
    assert urdf_parameters(panda)["FV3"] == 0.003  # <dynamics damping="0.003">
    kinova = _load(DATA / "kinova.urdf", "j2s6s200_end_effector", acceleration=4.0)
    assert np.isinf(kinova.limits.q_max[0]) and np.isinf(kinova.limits.q_min[3])  # continuous
    assert np.isfinite(kinova.limits.q_max[1])
    assert np.all(kinova.limits.qdd_max == 4.0)


def _tilted_ur10(tmp_path, rpy="0.3 -0.2 0.1", xyz="0.1 0.05 0.1273"):
    text = (DATA / "ur10_robot.urdf").read_text()
    old = '<origin rpy="0.0 0.0 0.0" xyz="0.0 0.0 0.1273"/>'
    assert text.count(old) == 1
    path = tmp_path / "ur10_tilted.urdf"
    path.write_text(text.replace(old, f'<origin rpy="{rpy}" xyz="{xyz}"/>'))
    return path


def test_tilted_base_gives_gravity_in_frame_0_and_makes_MX1_MY1_identifiable(tmp_path):
    path = _tilted_ur10(tmp_path)
    robot = _load(path, "tool0")
    g = robot.gravity_vector
    assert np.linalg.norm(g) == pytest.approx(9.81) and abs(g[2]) < 9.81 - 0.1
    chi = _rigid(robot, robot.parameter_vector(urdf_parameters(robot)))
    model = _pinocchio_chain(path, robot)
    assert _max_torque_error(robot, chi, model, seed=4) <= 1e-9
    upright = rx90sym.base_parameters(_load(DATA / "ur10_robot.urdf", "tool0"))
    tilted = rx90sym.base_parameters(robot)
    numeric = rx90sym.base_parameters(robot, method="numeric")
    assert tilted.names == numeric.names
    first = {n.rstrip("R") for n in tilted.names if n.rstrip("R").endswith("1")}
    assert {"MX1", "MY1"} <= first
    assert not {"MX1", "MY1"} & {n.rstrip("R") for n in upright.names}
    assert tilted.nb == upright.nb + 2
    # The base parameters reproduce the standard model on the tilted robot.
    rng = np.random.default_rng(5)
    q, qd, qdd = rng.uniform(-3, 3, robot.n), rng.normal(0, 1, robot.n), rng.normal(0, 2, robot.n)
    phi_b = np.array(tilted.regressor(q, qd, qdd))
    tau = np.array(robot.inverse_dynamics(q, qd, qdd, chi)).ravel()
    assert np.abs(phi_b @ tilted.beta(chi) - tau).max() <= 1e-9 * max(1.0, np.abs(tau).max())


def test_ur10_urdf_and_its_dh_table_give_the_same_base_parameters():
    # UR10 published (standard) DH: a2 = -0.612, a3 = -0.5723, d4 = 0.163941, d5 = 0.1157,
    # alpha1 = alpha4 = pi/2, alpha5 = -pi/2. Written in Khalil's convention with x_j pointing
    # from z_j to z_j+1 (so the lengths are positive and x turns by pi where DH has a < 0).
    p = math.pi
    rows = [(0, 0, 0, 0, 0), (0, p / 2, 0, p, 0), (0, 0, 0.612, 0, 0),
            (0, 0, 0.5723, p, 0.163941), (0, p / 2, 0, p, 0.1157), (0, p / 2, 0, 0, 0)]
    dh = rx90sym.robot_from_table(rows, name="ur10_dh")
    urdf = _load(DATA / "ur10_robot.urdf", "tool0")
    a, b = rx90sym.base_parameters(dh), rx90sym.base_parameters(urdf)
    assert a.names == b.names
    np.testing.assert_allclose(a.K, b.K, atol=1e-12)
    # and the geometry is the same: the same torques for the same parameters and angles
    chi = _rigid(urdf, urdf.parameter_vector(urdf_parameters(urdf)))
    q = np.random.default_rng(6).uniform(-3, 3, 6)
    np.testing.assert_allclose(np.array(dh.inverse_dynamics(q, q, q, chi)),
                               np.array(urdf.inverse_dynamics(q, q, q, chi)), rtol=1e-12, atol=1e-12)


def _scaled(robot, seed):
    """The URDF's parameters changed consistently: each link scaled by 1..1.5 plus a random
    physical body (a sum of physical bodies is physical, and stays so minus the children)."""
    rng = np.random.default_rng(seed)
    chi = robot.parameter_vector(urdf_parameters(robot))
    for j in range(robot.n):
        block = slice(13 * j, 13 * j + 10)
        chi[block] = rng.uniform(1.0, 1.5) * chi[block] + 0.2 * random_body(rng)
        chi[13 * j + 10:13 * j + 13] = rng.uniform(0.1, 1.0, 3)
    return chi


def _without_inertials(text):
    """The text without <inertial> and <dynamics> (the elements write_urdf changes)."""
    text = re.sub(r"<inertial\b.*?</inertial\s*>", "", text, flags=re.S)
    return re.sub(r"\s*<dynamics\b[^>]*/>", "", text)


@pytest.mark.parametrize("name,tip", ARMS)
def test_written_urdf_reloaded_by_pinocchio_gives_the_same_torques(tmp_path, name, tip):
    robot = _load(DATA / name, tip)
    chi = _scaled(robot, seed=7)
    out = tmp_path / "identified.urdf"
    written = write_urdf(robot, chi, out)
    assert written == [out, companion_path(out)]
    model = _pinocchio_chain(out, robot)
    assert _max_torque_error(robot, _rigid(robot, chi), model, seed=8) <= 1e-9
    # and our own import of the written file gives the parameters back
    again = _load(out, tip)
    np.testing.assert_allclose(_rigid(again, again.parameter_vector(urdf_parameters(again))),
                               _rigid(robot, chi), rtol=1e-9, atol=1e-12)
    # everything but the inertials and the chain joints' dynamics is kept as it was
    assert _without_inertials(out.read_text()) == _without_inertials((DATA / name).read_text())
    import json
    joints = json.loads(companion_path(out).read_text())["joints"]
    assert joints[robot.urdf.joints[2]]["FV"] == chi[13 * 2 + 12]


def test_write_urdf_refuses_a_non_physical_link_and_writes_nothing(tmp_path):
    robot = _load(DATA / "ur10_robot.urdf", "tool0")
    chi = robot.parameter_vector(urdf_parameters(robot))
    chi[13 * 2 + 9] = -1.0  # M3 < 0
    out = tmp_path / "x.urdf"
    with pytest.raises(UrdfError, match="forearm_link"):
        write_urdf(robot, chi, out)
    assert not out.exists() and not companion_path(out).exists()


def test_write_urdf_refuses_a_body_lighter_than_the_hand_it_carries(tmp_path):
    robot = _load(DATA / "panda.urdf", "panda_link8")
    chi = robot.parameter_vector(urdf_parameters(robot))
    chi[13 * 6:13 * 6 + 10] *= 0.5  # link 7 with hand and fingers, halved: lighter than the hand
    with pytest.raises(UrdfError, match="panda_link7.*panda_hand"):
        write_urdf(robot, chi, tmp_path / "x.urdf")


def _edit(tmp_path, old, new, count=1):
    text = (DATA / "ur10_robot.urdf").read_text()
    assert text.count(old) >= 1
    path = tmp_path / "bad.urdf"
    path.write_text(text.replace(old, new, count))
    return path


def test_bad_urdfs_are_refused_naming_the_element(tmp_path):
    loop = _edit(tmp_path, "</robot>", '<joint name="closing" type="fixed"><parent link="wrist_3_link"/>'
                 '<child link="shoulder_link"/></joint></robot>')
    with pytest.raises(UrdfError, match="'closing'.*loop"):
        _load(loop, "tool0")
    with pytest.raises(UrdfError, match="tip link 'tool1' is not a <link>.*'tool0'"):
        _load(DATA / "ur10_robot.urdf", "tool1")
    with pytest.raises(UrdfError, match="tip 'world' is the root link"):
        _load(DATA / "ur10_robot.urdf", "world")
    with pytest.raises(UrdfError, match="no movable joint between the root 'world' and tip 'base_link'"):
        _load(DATA / "ur10_robot.urdf", "base_link")
    two_arms = tmp_path / "two_arms.urdf"  # two moving branches: the chain's end must be chosen
    two_arms.write_text('<robot name="y"><link name="b"/><link name="l"/><link name="r"/>'
                        '<joint name="jl" type="revolute"><parent link="b"/><child link="l"/><axis xyz="0 0 1"/>'
                        '<limit lower="-1" upper="1" velocity="1" effort="1"/></joint>'
                        '<joint name="jr" type="revolute"><parent link="b"/><child link="r"/><axis xyz="0 0 1"/>'
                        '<limit lower="-1" upper="1" velocity="1" effort="1"/></joint></robot>')
    with pytest.raises(UrdfError, match=r"several leaf links \['l', 'r'\]: choose the chain's end"):
        _load(two_arms, None)
    unknown = _edit(tmp_path, '<child link="shoulder_link"/>', '<child link="shoulder_lnk"/>')
    with pytest.raises(UrdfError, match="shoulder_pan_joint.*'shoulder_lnk' is not a <link>"):
        _load(unknown, "tool0")


def test_load_robot_dispatches_on_the_urdf_suffix():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = rx90sym.load_robot(str(DATA / "ur10_robot.urdf"), tip="tool0", offsets=True)
    assert robot.urdf is not None and robot.parameter_names[-1] == "OFF6"
    with pytest.raises(rx90sym.RobotFileError, match="tip"):
        rx90sym.load_robot("rx90", tip="tool0")


def _recording(robot, chi, seed, path=None):
    """A noise-free motion of the robot with parameters chi, written as a recording (URDF angles)."""
    from identify.io.recordings import recording_from_arrays, write_recording
    from motions import multisine

    t = np.arange(0, 20, 1 / 200)
    q, qd, qdd = multisine(robot, seed, 20)(t)
    tau = np.array(robot.inverse_dynamics.map(len(t))(q.T, qd.T, qdd.T, np.tile(chi[:, None], (1, len(t))))).T
    if path is not None:
        write_recording(path, recording_from_arrays(t, q, tau, robot), robot, convention="khalil")
    return q, qd, qdd, tau


@pytest.mark.slow
def test_cli_identify_consistent_writes_a_urdf_that_predicts_held_out_torques(tmp_path):
    import subprocess
    import sys

    robot = _load(DATA / "ur10_robot.urdf", "tool0")
    rng = np.random.default_rng(0)
    chi = robot.parameter_vector(urdf_parameters(robot))
    for j in range(robot.n):
        chi[13 * j:13 * j + 10] *= rng.uniform(1.0, 1.3)
        chi[13 * j + 10:13 * j + 13] = [0.0, 0.5, 1.0]
    _recording(robot, chi, 1, tmp_path / "run.csv")
    out = tmp_path / "identified.urdf"
    base = [sys.executable, "-m", "identify.app.cli", "identify", str(tmp_path / "run.csv"), "--robot",
            str(DATA / "ur10_robot.urdf"), "--tip", "tool0", "--convention", "khalil", "--spring", "none",
            "--min-velocity", "0"]  # noise-free twin: its Coulomb sign is exact even near rest
    # The default fit writes its identified model; --method consistent prints that model as its result and
    # writes the same file.
    default = subprocess.run(base + ["--urdf-out", str(tmp_path / "default.urdf")], capture_output=True, text=True,
                             timeout=300)
    assert default.returncode == 0, default.stderr
    done = subprocess.run(base + ["--method", "consistent", "--urdf-out", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert out.read_text() == (tmp_path / "default.urdf").read_text()
    # Held-out motion: Pinocchio on the written URDF against the true rigid-body torques.
    model = _pinocchio_chain(out, robot)
    data = model.createData()
    q, qd, qdd, _ = _recording(robot, _rigid(robot, chi), 2)
    ref = np.array([np.array(robot.inverse_dynamics(a, b, c, _rigid(robot, chi))).ravel()
                    for a, b, c in zip(q[::4], qd[::4], qdd[::4])])
    got = np.array([pin.rnea(model, data, a, b, c) for a, b, c in zip(q[::4], qd[::4], qdd[::4])])
    rel = np.sqrt(((ref - got) ** 2).mean(0)) / np.sqrt((ref ** 2).mean(0))
    assert rel.max() < 0.05  # measured 1.3e-2 (joint 1, no gravity), others < 1e-3


def _random_urdf(path, seed):
    """A random tree: 5 chain joints (revolute, prismatic, continuous) with random placements and
    axes, including a parallel and an intersecting pair; a fixed child with an inertial on link 2
    and a revolute branch off the chain on link 3 (locked at 0)."""
    rng = np.random.default_rng(seed)

    def inertial():
        m = rng.uniform(0.5, 5)
        d = rng.uniform(0.01, 0.1, 3)
        I = np.diag([d[1] + d[2], d[0] + d[2], d[0] + d[1]]) * m
        rpy = " ".join(repr(float(x)) for x in rng.uniform(-3, 3, 3))
        xyz = " ".join(repr(float(x)) for x in rng.uniform(-0.2, 0.2, 3))
        m, (a, b, c) = float(m), (float(x) for x in np.diag(I))
        return (f'<inertial><origin xyz="{xyz}" rpy="{rpy}"/><mass value="{m!r}"/><inertia ixx="{a!r}" '
                f'ixy="0" ixz="0" iyy="{b!r}" iyz="0" izz="{c!r}"/></inertial>')

    def joint(name, jtype, parent, child, xyz, rpy, axis):
        f = lambda v: " ".join(repr(float(x)) for x in v)  # noqa: E731
        return (f'<joint name="{name}" type="{jtype}"><parent link="{parent}"/><child link="{child}"/>'
                f'<origin xyz="{f(xyz)}" rpy="{f(rpy)}"/><axis xyz="{f(axis)}"/>'
                f'<limit lower="-1" upper="1" effort="10" velocity="1"/></joint>')

    types = ["revolute", "prismatic", "continuous", "revolute", "revolute"]
    parts = ['<robot name="random">', '<link name="base"/>']
    axis1 = rng.normal(size=3)
    prev_axis = axis1
    for k, jtype in enumerate(types):
        parent = "base" if k == 0 else f"l{k}"
        xyz, rpy, axis = rng.uniform(-0.4, 0.4, 3), rng.uniform(-np.pi, np.pi, 3), rng.normal(size=3)
        if k == 3:  # parallel to joint 3's axis, offset
            rpy, axis = np.zeros(3), prev_axis
        if k == 4:  # intersecting joint 4's axis at its origin
            xyz = np.zeros(3)
        parts.append(joint(f"j{k + 1}", jtype, parent, f"l{k + 1}", xyz, rpy, axis if k else axis1))
        parts.append(f'<link name="l{k + 1}">{inertial()}</link>')
        prev_axis = axis
    parts.append(joint("fixed_on_2", "fixed", "l2", "box", rng.uniform(-0.3, 0.3, 3), rng.uniform(-3, 3, 3), [1, 0, 0]))
    parts.append(f'<link name="box">{inertial()}</link>')
    parts.append(joint("branch", "revolute", "l3", "side", rng.uniform(-0.3, 0.3, 3), rng.uniform(-3, 3, 3), rng.normal(size=3)))
    parts.append(f'<link name="side">{inertial()}</link>')
    parts.append("</robot>")
    path.write_text("\n".join(parts))
    return path


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_trees_with_prismatic_parallel_and_intersecting_axes_match_pinocchio(tmp_path, seed):
    path = _random_urdf(tmp_path / "random.urdf", seed)
    robot = _load(path, "l5")
    assert robot.sigma == (0, 1, 0, 0, 0)
    assert robot.d[4] == 0.0  # intersecting axes: no common normal length
    chi = _rigid(robot, robot.parameter_vector(urdf_parameters(robot)))
    model = _pinocchio_chain(path, robot)
    assert _max_torque_error(robot, chi, model, seed) <= 1e-9
    assert rx90sym.base_parameters(robot).names == rx90sym.base_parameters(robot, method="numeric").names
    chi2 = _scaled(robot, seed)
    write_urdf(robot, chi2, tmp_path / "out.urdf")
    assert _max_torque_error(robot, _rigid(robot, chi2), _pinocchio_chain(tmp_path / "out.urdf", robot), seed) <= 1e-9


def test_payload_of_a_urdf_robot_is_given_in_the_tip_frame(tmp_path):
    robot = _load(DATA / "ur10_robot.urdf", "tool0")
    body = random_body(np.random.default_rng(9))  # about the tool0 origin, tool0 axes
    payload = dict(zip(rx90sym.PAYLOAD_NAMES, body))
    chi = rx90sym.add_payload(robot, _rigid(robot, robot.parameter_vector(urdf_parameters(robot))), payload)
    # The same payload as a URDF link fixed on tool0: Pinocchio lumps it into wrist_3_link.
    from rx90sym.rigid_body import RigidBody

    c, I = RigidBody.from_vector(body).com_inertia()
    I = [[float(x) for x in row] for row in I]
    f = lambda v: " ".join(repr(float(x)) for x in v)  # noqa: E731
    link = (f'<joint name="grip" type="fixed"><parent link="tool0"/><child link="load"/></joint>'
            f'<link name="load"><inertial><origin xyz="{f(c)}"/><mass value="{float(body[9])!r}"/>'
            f'<inertia ixx="{I[0][0]!r}" ixy="{I[0][1]!r}" ixz="{I[0][2]!r}" iyy="{I[1][1]!r}" '
            f'iyz="{I[1][2]!r}" izz="{I[2][2]!r}"/></inertial></link></robot>')
    loaded = tmp_path / "loaded.urdf"
    loaded.write_text((DATA / "ur10_robot.urdf").read_text().replace("</robot>", link))
    assert _max_torque_error(robot, chi, _pinocchio_chain(loaded, robot), seed=10) <= 1e-9
    back, _ = rx90sym.urdf.payload_in_tip_frame(robot, rx90sym.urdf.payload_matrix(robot) @ body)
    np.testing.assert_allclose(back, body, rtol=1e-12, atol=1e-14)


def test_payload_identified_on_a_urdf_robot_is_reported_in_the_tip_frame():
    from identify.payloads.methods import payload
    from identify.io.recordings import recording_from_arrays

    robot = _load(DATA / "ur10_robot.urdf", "tool0")
    chi = robot.parameter_vector(urdf_parameters(robot))
    for j in range(robot.n):
        chi[13 * j + 10:13 * j + 13] = [0.0, 0.5, 1.0]
    body = random_body(np.random.default_rng(3))
    body *= 2.0 / body[9]  # a 2 kg load, given in the tool0 frame
    loaded = rx90sym.add_payload(robot, chi, dict(zip(rx90sym.PAYLOAD_NAMES, body)))
    q, _, _, tau = _recording(robot, loaded, 4)
    rec = recording_from_arrays(np.arange(len(q)) / 200, q, tau, robot)
    res = payload(robot, 1, loaded=[rec], robot_params=dict(zip(robot.parameter_names, chi)))
    # noise-free data: only the filtering bias is left (measured <= 2e-5 absolute)
    np.testing.assert_allclose(res.values, body, rtol=1e-2, atol=1e-4)


def test_write_urdf_adds_an_inertial_to_a_link_that_had_none(tmp_path):
    text = (DATA / "ur10_robot.urdf").read_text()
    block = re.search(r'<link name="wrist_1_link">.*?</link>', text, flags=re.S).group(0)
    bare = tmp_path / "bare.urdf"
    bare.write_text(text.replace(block, '<link name="wrist_1_link"/>'))
    robot = _load(bare, "tool0")
    assert urdf_parameters(robot)["M4"] == 0.0
    chi = _scaled(robot, seed=11)
    write_urdf(robot, chi, tmp_path / "out.urdf")
    assert _max_torque_error(robot, _rigid(robot, chi), _pinocchio_chain(tmp_path / "out.urdf", robot), 11) <= 1e-9


def test_right_angles_written_with_five_digits_are_snapped_by_default_and_kept_with_snap_0(tmp_path):
    text = (DATA / "ur10_robot.urdf").read_text().replace("1.57079632679", "1.5708")
    path = tmp_path / "short.urdf"
    path.write_text(text)
    with pytest.warns(UserWarning, match="snapping off.*shoulder_lift_joint"):
        raw = load_urdf(path, "tool0", acceleration=5.0, snap=0)
    with pytest.warns(UserWarning, match="snapped.*'shoulder_lift_joint': rpy 0 1.5708 0 -> 0 pi/2 0"):
        snapped = load_urdf(path, "tool0", acceleration=5.0)
    exact = _load(DATA / "ur10_robot.urdf", "tool0")
    gap = max(abs(math.remainder(a - b, 2 * math.pi)) for f in ("alpha", "d", "theta", "r")
              for a, b in zip(getattr(raw, f), getattr(exact, f)))
    assert 0 < gap < 1e-5  # kept as written: the table is a little off the right angles
    assert snapped.alpha == exact.alpha and snapped.d == exact.d and snapped.r == exact.r
    assert rx90sym.base_parameters(snapped).names == rx90sym.base_parameters(exact).names


def test_leaves_that_hang_by_fixed_joints_from_one_link_end_the_chain_there():
    """A maker's URDF with two frames after the last joint (UR: ee_link and tool0): without tip= the
    chain ends at the last moving link, with a warning naming the leaves; its model is the one with
    either leaf as the tip (fixed children are carried by the moving link): torques equal to 1e-12."""
    with pytest.warns(UserWarning, match=r"leaf links \['ee_link', 'tool0'\] hang by fixed joints from "
                                         r"'wrist_3_link'"):
        free = load_urdf(DATA / "ur10_robot.urdf")
    tooled = load_urdf(DATA / "ur10_robot.urdf", "tool0")
    assert free.urdf.tip == "wrist_3_link" and free.n == tooled.n == 6
    chi = tooled.parameter_vector(urdf_parameters(tooled))
    np.testing.assert_allclose(free.parameter_vector(urdf_parameters(free)), chi, rtol=0, atol=1e-12)
    rng = np.random.default_rng(0)
    q, qd, qdd = (rng.uniform(-2, 2, (5, 6)) for _ in range(3))
    np.testing.assert_allclose(free.regressor_batch(q, qd, qdd) @ chi, tooled.regressor_batch(q, qd, qdd) @ chi,
                               rtol=0, atol=1e-12 * max(1.0, float(np.abs(tooled.regressor_batch(q, qd, qdd) @ chi).max())))
