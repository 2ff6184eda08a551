"""The bundled robots' [nominal] and [flange] tables: physical, sourced, and the makers' numbers.

The makers' values are typed again here from their publications (not read from the files), and
the frame conversions are checked through the makers' own kinematics (test_bundled_robots).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import rx90sym
from rx90sym.robot_file import ROBOTS_DIR

from test_bundled_robots import URDF_DIR, _controller_samples, _model_frame, ur_standard_dh

BUNDLED = ("rx90", "tx40", "ur10e", "panda")
# Universal Robots support article 45257, UR10e: masses [kg], CoM [m] in UR's DH frame i.
UR10E_MASS = [7.369, 13.051, 3.989, 2.1, 1.98, 0.615]
UR10E_COM = [(0.021, 0.0, 0.027), (0.38, 0.0, 0.158), (0.24, 0.0, 0.068), (0.0, 0.007, 0.018),
             (0.0, 0.007, 0.018), (0.0, 0.0, -0.026)]


def pseudo_inertia(values: dict, j: int) -> np.ndarray:
    """4x4 pseudo-inertia [[tr(J)/2 I - J, h], [h^T, m]] of link j from its standard parameters."""
    XX, XY, XZ, YY, YZ, ZZ, MX, MY, MZ, M = (values[f"{p}{j}"] for p in rx90sym.LINK_PARAMETERS[:10])
    J = np.array([[XX, XY, XZ], [XY, YY, YZ], [XZ, YZ, ZZ]])
    out = np.zeros((4, 4))
    out[:3, :3] = 0.5 * np.trace(J) * np.eye(3) - J
    out[:3, 3] = out[3, :3] = (MX, MY, MZ)
    out[3, 3] = M
    return out


@pytest.mark.parametrize("name", BUNDLED)
def test_each_bundled_prior_is_physically_consistent_and_sourced(name):
    robot = rx90sym.load_robot(name)
    values = rx90sym.nominal_parameters(robot)
    assert set(values) == set(robot.parameter_names)
    for j in range(1, robot.n + 1):
        eig = np.linalg.eigvalsh(pseudo_inertia(values, j))
        assert eig[0] > 1e-6 * eig[-1], f"{name} link {j}: pseudo-inertia not positive definite"
        assert values[f"IA{j}"] > 0 and values[f"FV{j}"] > 0 and values[f"FS{j}"] > 0
    # The moving links weigh less than the whole arm (base included), and most of it.
    masses = robot.nominal.mass
    assert 0.6 * robot.nominal.total_mass <= masses.sum() < robot.nominal.total_mass
    for key, texts in robot.nominal.sources.items():
        assert all(text.strip() for text in texts), key
    # Torque limits, needed by the excitation and the plausibility checks, are all given.
    assert np.all(np.isfinite(robot.limits.tau_max))


def test_ur10e_masses_and_centres_of_mass_are_urs_through_urs_own_frames():
    robot = rx90sym.load_robot("ur10e")
    np.testing.assert_array_equal(robot.nominal.mass, UR10E_MASS)
    assert abs(sum(UR10E_MASS) - 29.104) < 1e-9     # the six moving links, as published
    for q in _controller_samples(robot, 4, 5):
        ur = ur_standard_dh(q)
        q_model = robot.to_model(q)
        for j in range(1, 7):
            in_ur = ur[j] @ np.array([*UR10E_COM[j - 1], 1.0])
            in_file = _model_frame(robot, q_model, j) @ np.array([*robot.nominal.com[j - 1], 1.0])
            np.testing.assert_allclose(in_file, in_ur, rtol=0, atol=1e-12)
    assert "derived" in robot.nominal.sources["shape"][0]
    assert "derived" in robot.nominal.sources["rotor_inertia"][0]


def test_panda_prior_is_franka_descriptions_inertials():
    """rnea on franka_description's URDF (hand locked away, not part of the arm) equals the
    toolkit's inverse dynamics with the [nominal] inertials (actuation terms left out)."""
    robot = rx90sym.load_robot("panda")
    full = pin.buildModelFromUrdf(str(URDF_DIR / "panda.urdf"))
    keep = {f"panda_joint{j}" for j in range(1, 8)}
    model = pin.buildReducedModel(full, [i for i in range(1, full.njoints) if full.names[i] not in keep],
                                  pin.neutral(full))
    # Joint 7's body without the hand (lumped into it through the fixed joints): panda_link7's
    # inertial alone, as the URDF gives it in panda_link7's frame.
    I7 = np.array([[0.012516, -0.000428, -0.001196], [-0.000428, 0.010027, -0.000741],
                   [-0.001196, -0.000741, 0.004815]])
    model.inertias[7] = pin.Inertia(0.735522, np.array([1.0517e-02, -4.252e-03, 6.1597e-02]), I7)
    data = model.createData()
    values = rx90sym.nominal_parameters(robot)
    for kind in ("IA", "FV", "FS"):
        values.update({f"{kind}{j}": 0.0 for j in range(1, 8)})
    chi = robot.parameter_vector(values)
    rng = np.random.default_rng(2)
    for q in _controller_samples(robot, 6, 6):
        qd, qdd = rng.normal(0, 1.0, 7), rng.normal(0, 2.0, 7)
        ref = pin.rnea(model, data, q, qd, qdd)
        tau = np.array(robot.inverse_dynamics(robot.to_model(q), qd, qdd, chi)).ravel()
        assert np.abs(tau - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max())


def test_the_rx90_prior_is_not_the_twins_truth():
    robot = rx90sym.load_robot("rx90")
    nominal = rx90sym.nominal_parameters(robot)
    truth = json.loads((Path(rx90sym.__file__).parent / "data" / "rx90_true_params.json").read_text())
    assert rx90sym.default_parameters(robot) == truth["parameters"]
    assert nominal != truth["parameters"]
    assert max(abs(nominal[f"M{j}"] - truth["parameters"][f"M{j}"]) for j in range(1, 7)) > 0.5


@pytest.mark.parametrize("name, offset", [("rx90", 0.085), ("tx40", 0.065), ("ur10e", 0.0), ("panda", 0.0)])
def test_flange_frames(name, offset):
    """RX90/TX40: frame 6 is the wrist centre, the flange further along z6; UR10e and Panda:
    the last frame is the maker's flange (test_bundled_robots checks it against their DH)."""
    robot = rx90sym.load_robot(name)
    expected = np.eye(4)
    expected[2, 3] = offset
    np.testing.assert_allclose(robot.flange, expected, atol=1e-15)


def _file(tmp_path, edit):
    text = (ROBOTS_DIR / "ur10e.toml").read_text()
    path = tmp_path / "ur10e_mine.toml"
    path.write_text(edit(text))
    return path


@pytest.mark.parametrize("edit, needle", [
    (lambda t: t.replace('mass_source = "Universal', 'mass_note = "Universal'), "unknown key 'mass_note'"),
    (lambda t: t.replace("mass_source =", "# mass_source =", 1), "'mass' has no 'mass_source'"),
    (lambda t: t.replace("radius = 0.06, length = 0.6127", "radius = 0.0, length = 0.6127"),
     "shape of link 2: cylinder radius and length must be > 0"),
    (lambda t: t.replace("rotor_inertia = [0.61, 0.61,", "rotor_inertia = [0.61,"), "'rotor_inertia' needs 6"),
    (lambda t: t.replace('rpy_deg = [0.0, 0.0, 0.0]         # roll', 'rpy_deg = [0.0, 0.0]  # roll'),
     "'rpy_deg' needs 3"),
])
def test_bad_tables_are_refused_with_the_place(tmp_path, edit, needle):
    path = _file(tmp_path, edit)
    with pytest.raises(rx90sym.RobotFileError, match="ur10e_mine.toml, line [0-9]+") as info:
        rx90sym.load_robot(path)
    assert needle in str(info.value)


