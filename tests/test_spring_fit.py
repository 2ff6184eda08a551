"""The spring from data (issue 13): a twin whose spring constants the fit does not know."""
from __future__ import annotations

import numpy as np
import pytest

import identify
import rx90sym
from identify.observation.spring_fit import spring_base, spring_torque
from rx90sym.spring import Spring, SpringBasis, SpringStiffness

from motions import multisine

# Not the robot file's placeholder (k 4000, a 0.10, b 0.30, L0 0.05): what the fit must find.
UNKNOWN = Spring(joint=1, k=2500.0, a=0.12, b=0.35, L0=0.08, angle_offset=np.pi / 2)


def test_the_first_harmonic_is_grouped_with_the_gravity_parameters(rx90, rx90_base):
    sb = spring_base(rx90, SpringBasis(1), rx90_base)
    assert sb.grouped == ("SPC1_2", "SPS1_2")
    assert sb.names[-len(sb.kept):] == ("SP0_2", "SPC2_2", "SPS2_2", "SPC3_2", "SPS3_2", "SPC4_2", "SPS4_2")
    # Independent check of the alias: on joint 2 of the RX90, cos and sin of q2 times g are the
    # gravity columns of MX2R and MY2 (frame 2 origin fixed on the vertical axis 1).
    rng = np.random.default_rng(1)
    Q = rng.uniform(-3, 3, (50, 6))
    Phi = rx90_base.regressor_batch(Q, rng.normal(size=(50, 6)), rng.normal(size=(50, 6)))
    cols = Phi[:, 1, [rx90_base.names.index("MX2R"), rx90_base.names.index("MY2")]]
    first = np.c_[np.cos(Q[:, 1]), np.sin(Q[:, 1])]
    coef, *_ = np.linalg.lstsq(cols, first, rcond=None)
    np.testing.assert_allclose(cols @ coef, first, atol=1e-12)
    # With torque offsets the constant goes too (OFF2); the stiffness of a known geometry stays.
    with_offsets = rx90.with_options(offsets=True)
    assert "SP0_2" in spring_base(with_offsets, SpringBasis(1)).grouped
    assert spring_base(rx90, SpringStiffness(UNKNOWN), rx90_base).kept == ("KS_2",)
    # A planar arm with vertical axes feels no gravity: nothing is grouped, the first harmonic stays.
    scara = rx90sym.robot_from_table([(0, 0, 0, 0, 0), (0, 0, 0.4, 0, 0), (0, 0, 0.3, 0, 0)], name="scara")
    sb = spring_base(scara, SpringBasis(1, orders=(1, 2)))
    assert sb.grouped == () and sb.kept == ("SP0_2", "SPC1_2", "SPS1_2", "SPC2_2", "SPS2_2")


@pytest.fixture(scope="module")
def unknown_spring_runs(rx90):
    """Four training motions and one held-out motion of a twin with the UNKNOWN spring."""
    twin_robot = rx90.with_options(spring=UNKNOWN)
    chi = rx90.parameter_vector(rx90sym.default_parameters(rx90))
    runs = [rx90sym.twin.simulate(twin_robot, multisine(rx90, s), params=chi, duration=20.0, seed=s)
            for s in (0, 1, 2, 3, 50)]
    return twin_robot, runs[:4], runs[4]


@pytest.mark.slow
def test_spring_of_unknown_constants_identified_and_predicting_as_well_as_the_true_one(
        rx90, rx90_base, unknown_spring_runs):
    twin_robot, train, held = unknown_spring_runs
    no_spring = rx90.with_options(spring=None)
    # Reference: the true spring known and added to the measured torques (the usual path).
    known = identify.fit(twin_robot, train, identify.Processing(min_velocity=0.1, rest="drop", estimate_delay=False, cross_validate=False), base=rx90_base).result
    rms_known = identify.validate(twin_robot, known, held, base=rx90_base).rms_error
    # k for the known geometry: one coefficient, truth 2500 N/m.
    sk = spring_base(no_spring, SpringStiffness(Spring(joint=1, k=1.0, a=0.12, b=0.35, L0=0.08,
                                                       angle_offset=np.pi / 2)), rx90_base)
    res_k = identify.fit(no_spring, train, identify.Processing(min_velocity=0.1, spring=False, rest="drop", estimate_delay=False, cross_validate=False), base=sk).result
    i = res_k.names.index("KS_2")
    assert abs(res_k.values[i] - UNKNOWN.k) < 3 * res_k.std[i] and res_k.std[i] < 0.02 * UNKNOWN.k
    # A Fourier series in theta2 (shape unknown): held-out torques as good as with the true spring.
    sb = spring_base(no_spring, SpringBasis(1), rx90_base)
    res = identify.fit(no_spring, train, identify.Processing(min_velocity=0.1, spring=False, rest="drop", estimate_delay=False, cross_validate=False), base=sb).result
    rms = identify.validate(no_spring, res, held, base=sb, spring=False).rms_error
    # Measured (seeds 0-3, held-out 50): 0.942 vs 0.943 N m on joint 2, equal elsewhere.
    assert np.all(rms <= 1.02 * rms_known + 1e-3), (rms, rms_known)
    # The identified torque, first harmonic and constant aside (grouped / offset-like), follows
    # the true spring's higher harmonics within its sigma band on the visited range.
    theta = np.linspace(-1.0, 1.0, 201)
    tau, sigma = spring_torque(res, sb, theta)
    true = _model(UNKNOWN, theta)
    residual = true - tau
    fit = np.c_[np.ones_like(theta), np.cos(theta), np.sin(theta)]
    residual -= fit @ np.linalg.lstsq(fit, residual, rcond=None)[0]
    assert np.max(np.abs(residual)) < 3 * np.max(sigma) + 0.05, (np.max(np.abs(residual)), np.max(sigma))


def _model(spring: Spring, theta: np.ndarray) -> np.ndarray:
    ts = theta + spring.angle_offset
    L = np.sqrt(spring.a**2 + spring.b**2 - 2 * spring.a * spring.b * np.cos(ts))
    return -spring.k * spring.a * spring.b * np.sin(ts) * (1 - spring.L0 / L)


@pytest.mark.slow
def test_spring_in_the_basis_coefficients_within_3_sigma(rx90, rx90_base):
    coefficients = {"SP0_2": 15.0, "SPC1_2": 40.0, "SPS1_2": -25.0, "SPC2_2": 12.0, "SPS2_2": -8.0,
                    "SPC3_2": 5.0, "SPS3_2": 3.0}
    grid = np.linspace(-np.pi, np.pi, 4001)
    table = (grid, SpringBasis(1, (1, 2, 3)).torque(coefficients, grid))
    twin_robot = rx90.with_options(spring=Spring(joint=1, table=table))
    chi = rx90.parameter_vector(rx90sym.default_parameters(rx90))
    train = [rx90sym.twin.simulate(twin_robot, multisine(rx90, s), params=chi, duration=20.0, seed=s)
             for s in (10, 11, 12, 13)]
    no_spring = rx90.with_options(spring=None)
    sb = spring_base(no_spring, SpringBasis(1), rx90_base)
    res = identify.fit(no_spring, train, identify.Processing(min_velocity=0.1, spring=False, rest="drop", estimate_delay=False, cross_validate=False), base=sb).result
    z = {n: (res.values[res.names.index(n)] - coefficients.get(n, 0.0)) / res.std[res.names.index(n)]
         for n in sb.kept}
    # Measured |z| <= 0.7 on seeds 0-3 (order 4 has truth 0).
    assert max(abs(v) for v in z.values()) < 3, z


# --------------------------------------------------------------------------- command line
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

from identify.io.recordings import write_recording  # noqa: E402
from rx90sym.robot_file import ROBOTS_DIR  # noqa: E402

RX90_CLI = str(Path(sys.executable).parent / "rx90")


@pytest.fixture(scope="module")
def springless(tmp_path_factory, unknown_spring_runs):
    """A user's RX90 file without [spring], and the unknown-spring twin runs written to CSV."""
    d = tmp_path_factory.mktemp("spring_cli")
    text = (ROBOTS_DIR / "rx90.toml").read_text()
    (d / "arm.toml").write_text(text[:text.index("[spring]")])
    arm = rx90sym.load_robot(d / "arm.toml")
    twin_robot, train, held = unknown_spring_runs
    for name, rec in (("a.csv", train[0]), ("b.csv", train[1]), ("held.csv", held)):
        write_recording(d / name, rec, twin_robot)
    return d, arm


def cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([RX90_CLI, *args], capture_output=True, text=True, cwd=cwd, timeout=600)


@pytest.mark.slow
def test_cli_spring_identify_and_placeholder_labels(springless):
    d, arm = springless
    out = cli("identify", "a.csv", "b.csv", "--robot", "arm.toml", "--spring", "identify",
              "--spring-joint", "2", "--min-velocity", "0.1", "--validate", "held.csv", "--json", "s.json", cwd=d)
    assert out.returncode == 0, out.stderr
    res = json.loads((d / "s.json").read_text())
    assert res["spring"]["mode"] == "identified" and res["spring"]["grouped"] == ["SPC1_2", "SPS1_2"]
    assert set(res["spring"]["coefficients"]) == {"SP0_2", "SPC2_2", "SPS2_2", "SPC3_2", "SPS3_2", "SPC4_2", "SPS4_2"}
    assert "spring on joint 2, identified" in out.stdout
    # The bundled RX90's spring is a placeholder: said on stderr, in the table and in the JSON.
    out = cli("identify", "a.csv", "b.csv", "--robot", "rx90", "--json", "p.json", cwd=d)
    assert out.returncode == 0, out.stderr
    assert "PLACEHOLDER" in out.stderr and "PLACEHOLDER" in out.stdout
    assert json.loads((d / "p.json").read_text())["spring"]["placeholder"] is True


@pytest.mark.parametrize("args, needle", [
    (("--robot", "arm.toml", "--spring", "identify"), "has no [spring]: give --spring-joint J"),
    (("--spring", "identify", "--method", "consistent"), "--spring identify works with --method wls or ols"),
    (("--spring-joint", "3"), "--spring-joint goes with --spring FILE.csv or identify"),
])
def test_cli_spring_option_conflicts_exit_2(tmp_path, args, needle):
    text = (ROBOTS_DIR / "rx90.toml").read_text()
    (tmp_path / "arm.toml").write_text(text[:text.index("[spring]")])
    (tmp_path / "a.csv").write_text("t,q1\n")
    out = cli("identify", "a.csv", "--robot", "rx90", *args, cwd=tmp_path)
    assert out.returncode == 2 and needle in out.stderr, out.stderr


def test_spring_table_acts_on_the_robot_files_spring_joint(tmp_path):
    import argparse

    from identify.app.common import UsageError, robot_with_spring

    text = (ROBOTS_DIR / "rx90.toml").read_text()
    (tmp_path / "arm.toml").write_text(text[:text.index("[spring]")] + "[spring]\njoint = 3\n"
                                       'table = "s.csv"\n')
    (tmp_path / "s.csv").write_text("angle,torque\n-3,1\n3,2\n")

    def options(**kw):
        base = dict(robot=str(tmp_path / "arm.toml"), offsets=False, spring=str(tmp_path / "s.csv"),
                    spring_joint=None, spring_orders=None)
        return argparse.Namespace(**{**base, **kw})

    robot, model = robot_with_spring(options())
    assert model is None and robot.spring.joint == 2 and robot.spring.table is not None
    robot, _ = robot_with_spring(options(spring_joint=4))
    assert robot.spring.joint == 3
    robot, model = robot_with_spring(options(spring="identify", spring_orders="2,3"))
    assert robot.spring is None and model.joint == 2 and model.orders == (2, 3)
    with pytest.raises(UsageError, match="--spring-joint 9: robot 'rx90' has joints 1..6"):
        robot_with_spring(options(spring_joint=9))
