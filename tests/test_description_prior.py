"""The robot's description is a prior, never a gate: non-physical inertials load with one warning, the
prior gets the nearest physical body, only the twin refuses them (rx90sym.description_prior).

Checked independently: the projection against cvxpy's (the nearest pseudo-inertia in the cone), the
prior's gravity against Pinocchio's on the file as written (mass and centre of mass kept), on the
Kinova Gen3 URDF users hold (tests/data/kinova_gen3, MIT).
"""
from __future__ import annotations

import json
import warnings
from pathlib import Path

import cvxpy as cp
import numpy as np
import pinocchio as pin
import pytest

import rx90sym
from identify.app.cli import main
from rx90sym.description_prior import (DescriptionWarning, description_prior, required_description_prior,
                                       simulation_refusal)
from rx90sym.nominal import read_parameter_file
from rx90sym.physical import DEFAULT_MARGIN, nearest_physical_body, parameter_problems
from rx90sym.rigid_body import RigidBody, physical_problem
from rx90sym.robot_file import ROBOTS_DIR

GEN3 = Path(__file__).resolve().parent / "data" / "kinova_gen3" / "gen3.urdf"


def _load_gen3() -> tuple[rx90sym.Robot, list[warnings.WarningMessage]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = rx90sym.load_robot(str(GEN3))
    return robot, caught


@pytest.fixture(scope="module")
def gen3():
    return _load_gen3()[0]


def test_gen3_urdf_loads_with_one_warning_naming_every_link_and_the_open_joints_once():
    robot, caught = _load_gen3()
    said = [str(w.message) for w in caught if issubclass(w.category, DescriptionWarning)]
    assert len(said) == 1, said
    text = said[0]
    # base_link is fixed to the ground: ignored with a note; the two moving links: moments written -> prior.
    assert "link 'base_link' is fixed to the ground (above the first joint): its inertial is ignored" in text
    assert "link 'shoulder_link' (joint 1): principal moments 0.0004041, 0.004836, 0.01457 kg m^2 break the " \
           "triangle inequality (0.0004041 + 0.004836 < 0.01457" in text
    assert "prior = nearest physical body (moments 0.0004041, 0.004836, 0.01457 -> 0.005069, 0.009501, 0.01457" in text
    assert "link 'spherical_wrist_1_link' (joint 5)" in text
    # The URDF's revolute joints without position limits: one line for the four of them.
    open_joints = [str(w.message) for w in caught if "without <limit lower upper>" in str(w.message)]
    assert len(open_joints) == 1 and "'joint_1', 'joint_3', 'joint_5', 'joint_7'" in open_joints[0]
    assert np.all(np.isinf(robot.limits.q_max[[0, 2, 4, 6]])) and np.all(np.isfinite(robot.limits.q_max[[1, 3, 5]]))
    prior = description_prior(robot)
    assert [k.status for k in prior.links] == ["projected", "physical", "physical", "physical", "projected",
                                               "physical", "physical"]
    assert prior.ground == ("base_link",) and prior.informative


def test_the_prior_keeps_each_mass_and_centre_of_mass_and_is_physical(gen3):
    """Gravity depends on the masses and centres of mass only: the prior's, through the toolkit's
    regressor, equals Pinocchio's RNEA gravity on the URDF as written (base_link and all)."""
    prior = description_prior(gen3)
    chi, written = gen3.parameter_vector(prior.values), gen3.parameter_vector(prior.as_written)
    assert not parameter_problems(gen3.parameter_names, chi, DEFAULT_MARGIN, nonnegative=())
    assert len(parameter_problems(gen3.parameter_names, written)) == 2  # links 1 and 5 as written
    assert prior.as_written == rx90sym.urdf_parameters(gen3)
    assert rx90sym.nominal_parameters(gen3) == prior.values  # every user of the nominal parameters gets the prior
    physical = [k.link for k in prior.links if k.status == "physical"]
    for j in physical:  # a physical link's prior is the file's, to the bit
        assert all(prior.values[f"{p}{j}"] == prior.as_written[f"{p}{j}"] for p in rx90sym.LINK_PARAMETERS[:10])
    model = pin.buildModelFromUrdf(str(GEN3))
    data = model.createData()
    rng = np.random.default_rng(0)
    for _ in range(5):
        q = rng.uniform(-2.0, 2.0, gen3.n)
        zero = np.zeros((1, gen3.n))
        ours = gen3.regressor_batch(q[None, :], zero, zero)[0] @ chi
        theirs = pin.computeGeneralizedGravity(model, data, q)
        # The loader snaps 1.5708 to pi/2 (Pinocchio reads it as written): ~1e-5 of the torque.
        assert np.abs(ours - theirs).max() <= 1e-4 * np.abs(theirs).max()


@pytest.mark.parametrize("seed", range(5))
def test_nearest_physical_body_is_the_projection_onto_the_cone(seed):
    """Against cvxpy: the pseudo-inertia about the centre of mass, blockdiag(S, m), nearest in the
    Frobenius norm with S >= margin, mass and centre of mass kept."""
    rng = np.random.default_rng(seed)
    while True:
        moments = rng.uniform(0.0, 1.0, 3) * np.array([1.0, 1.0, 3.0])
        if moments[0] + moments[1] < moments[2]:  # the triangle inequality broken
            break
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    body = RigidBody.from_com(2.0, rng.normal(size=3) * 0.1, R, np.diag(moments))
    assert physical_problem(body) is not None
    near = nearest_physical_body(body, DEFAULT_MARGIN)
    c0, I0 = body.com_inertia()
    c1, I1 = near.com_inertia()
    assert near.m == body.m and np.allclose(c1, c0, atol=1e-12)

    def second(I):
        return 0.5 * np.trace(I) * np.eye(3) - I

    S = cp.Variable((3, 3), symmetric=True)
    cp.Problem(cp.Minimize(cp.sum_squares(S - second(I0))), [S >> DEFAULT_MARGIN * np.eye(3)]).solve(
        solver=cp.CLARABEL, tol_gap_abs=1e-12, tol_gap_rel=1e-12, tol_feas=1e-12)
    assert np.abs(second(I1) - S.value).max() <= 1e-6 * np.abs(S.value).max()
    assert physical_problem(near) is None and physical_problem(near, DEFAULT_MARGIN) is None


def _panda_copy(tmp_path: Path, edits: list[tuple[str, str]]) -> Path:
    path = tmp_path / "panda_mine.toml"
    text = (ROBOTS_DIR / "panda.toml").read_text()
    for old, new in edits:
        assert old in text
        text = text.replace(old, new)
    path.write_text(text)
    return path


def test_robot_file_bodies_are_a_prior_and_only_the_twin_refuses_them(tmp_path, capsys):
    # Link 1: Izz far above Ixx + Iyy (no mass distribution); link 3: a negative mass (no body of that mass).
    path = _panda_copy(tmp_path, [("[[0.70337, 0.70661, 0.009117,", "[[0.70337, 0.70661, 3.0,"),
                                  ("mass = [4.970684, 0.646926, 3.228604,", "mass = [4.970684, 0.646926, -3.228604,")])
    with pytest.warns(DescriptionWarning) as caught:
        robot = rx90sym.load_robot(path)
    assert len(caught) == 1
    text = str(caught[0].message)
    assert "link 1: principal moments" in text and "triangle inequality" in text and "prior = nearest physical body" in text
    assert "link 3: mass -3.229 kg is not > 0: no prior for this link (uninformative)" in text
    prior = description_prior(robot)
    assert [k.status for k in prior.links][:3] == ["projected", "physical", "none"]
    assert all(prior.values[f"{p}3"] == 0.0 for p in rx90sym.LINK_PARAMETERS[:10])
    assert prior.as_written["M3"] == pytest.approx(-3.228604)
    # The twin alone refuses, naming both links in one message (Python and rx90 simulate alike).
    refusal = simulation_refusal(robot)
    assert "link 1:" in refusal and "link 3: mass -3.229 kg" in refusal
    with pytest.raises(ValueError, match="link 1: principal moments.*link 3: mass"):
        rx90sym.twin.simulate(robot, (np.arange(3) * 0.01, np.zeros((3, 7)), np.zeros((3, 7)), np.zeros((3, 7))))
    traj = tmp_path / "traj.csv"
    traj.write_text("t," + ",".join(f"{k}{j}" for k in ("q", "dq", "ddq") for j in range(1, 8)) + "\n"
                    + "\n".join(",".join(["%g" % (0.004 * i)] + ["0"] * 21) for i in range(3)) + "\n")
    out = tmp_path / "sim.csv"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main(["simulate", str(traj), "--robot", str(path), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and not out.exists()
    line = [x for x in err.splitlines() if ": error: " in x]
    assert len(line) == 1 and "link 1:" in line[0] and "link 3:" in line[0] and "--params FILE" in line[0]


def test_a_description_without_bodies_cannot_be_the_prior(tmp_path):
    urdf = tmp_path / "bare.urdf"  # two moving links, no <inertial> at all
    urdf.write_text('<robot name="bare"><link name="b"/><link name="l1"/><link name="l2"/>'
                    '<joint name="j1" type="revolute"><parent link="b"/><child link="l1"/><axis xyz="0 0 1"/>'
                    '<limit lower="-1" upper="1" velocity="1" effort="10"/></joint>'
                    '<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.3 0 0"/>'
                    '<axis xyz="0 1 0"/><limit lower="-1" upper="1" velocity="1" effort="10"/></joint></robot>')
    robot = rx90sym.load_robot(str(urdf))  # no warning: a massless description is no error
    prior = description_prior(robot)
    assert not prior.informative and [k.status for k in prior.links] == ["none", "none"]
    with pytest.raises(ValueError, match=r"--prior description: the description .*bare.urdf gives no body to a "
                                         r"moving link \(masses 0, 0 kg\)"):
        required_description_prior(robot)
    from conftest import robot_file_without

    bare = rx90sym.load_robot(robot_file_without(tmp_path / "tx40.toml", "tx40", "nominal"))
    assert description_prior(bare) is None
    with pytest.raises(ValueError, match="robot 'tx40' .* has no description parameters"):
        required_description_prior(bare)


def test_a_prior_file_naming_parameters_the_robot_does_not_have_is_refused(tmp_path):
    robot = rx90sym.load_robot("tx40")
    values = dict(rx90sym.nominal_parameters(robot), M7=1.0, XX7=0.1)  # a 7th link on a 6-joint arm
    path = tmp_path / "prior.json"
    path.write_text(json.dumps(values))
    with pytest.raises(ValueError, match=r"prior.json \(robot 'tx40'\): unknown parameter\(s\) \['M7', 'XX7'\]: "
                                         r"not parameters of this robot"):
        read_parameter_file(robot, path)
    # The same table as a list of {"name", "value"}: the same check, the same message.
    path.write_text(json.dumps({"parameters": [{"name": k, "value": v} for k, v in values.items()]}))
    with pytest.raises(ValueError, match=r"unknown parameter\(s\) \['M7', 'XX7'\]"):
        read_parameter_file(robot, path)
    path.write_text(json.dumps({"parameters": [{"name": k, "value": v} for k, v in values.items() if k[-1] != "7"]}))
    assert read_parameter_file(robot, path)["M1"] == values["M1"]
