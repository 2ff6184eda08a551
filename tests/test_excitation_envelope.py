"""The safety envelope of ``rx90 excite`` (issue 19), checked independently of the optimiser:
Pinocchio's forward kinematics of the URDF at the controller's rate, coal's capsule distances,
finite differences of the written samples."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import excitation
import rx90sym
from excitation import controller_programs as cp
from excitation.collision import _segment_distance
from excitation.envelope import pose_violations
from excitation.robot_geometry import arm_geometry, capsule_set
from command_line import run

UR5 = str(Path(__file__).parent / "data" / "urdf" / "ur5.urdf")
UR5_ARGS = ("excite", "--robot", UR5, "--tip", "tool0")


@pytest.fixture(scope="session")
def ur5_run(tmp_path_factory):
    """The issue's example with the defaults (one start instead of two, for time): 12 s,
    --controller ur, URScript, CSV and the HTML report."""
    out = tmp_path_factory.mktemp("ur5")
    proc = run(*UR5_ARGS, "--duration", "12", "--starts", "1", "--controller", "ur", "--controller-rate", "500",
               "--program", str(out / "T.script"), "--out", str(out / "T.csv"), "--json", str(out / "T.json"),
               "--report", str(out / "T.html"))
    assert proc.returncode == 0, proc.stderr
    return out, proc


def _pinocchio_frames(q: np.ndarray) -> dict[str, np.ndarray]:
    """Positions (N, 3) in the URDF root frame of every frame of the UR5 URDF, by Pinocchio."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(UR5)
    data = model.createData()
    out: dict[str, list] = {f.name: [] for f in model.frames}
    for row in q:
        pin.framesForwardKinematics(model, data, row)
        for f, placement in zip(model.frames, data.oMf):
            out[f.name].append(placement.translation.copy())
    return {k: np.array(v) for k, v in out.items()}


@pytest.mark.slow
def test_ur5_default_excitation_holds_the_envelope_by_pinocchio_at_the_controller_rate(ur5_run):
    out, proc = ur5_run
    data = np.genfromtxt(out / "T.csv", delimiter=",", names=True)
    q = np.column_stack([data[f"q{j}"] for j in range(1, 7)])
    t = data["t"]
    assert np.allclose(np.diff(t), 1.0 / 500.0)  # e-Series servoj period
    frames = _pinocchio_frames(q)
    moving = [n for n in frames if n not in ("universe", "root_joint", "base_link", "shoulder_pan_joint")]
    lowest = min(float(frames[n][:, 2].min()) for n in moving if n != "shoulder_link")
    assert lowest >= 0.05 - 1e-6, lowest  # base plane z = 0 plus the 0.05 m margin
    speed = np.linalg.norm(np.diff(frames["tool0"], axis=0), axis=1) * 500.0
    assert speed.max() <= 1.0 * 1.01, speed.max()  # the documented default, finite differences
    import pinocchio as pin

    model = pin.buildModelFromUrdf(UR5)
    assert np.all(q >= model.lowerPositionLimit - 1e-9) and np.all(q <= model.upperPositionLimit + 1e-9)
    qd = np.diff(q, axis=0) * 500.0
    assert np.all(np.abs(qd) <= 0.7 * model.velocityLimit * 1.01)
    script = (out / "T.script").read_text()
    targets = cp.parse_servoj(script)
    assert targets.shape == q.shape and np.allclose(targets, q, atol=1e-8)
    assert script.count("movej(") == 2 and "servoj(" in script
    summary = json.loads((out / "T.json").read_text())
    assert "angle_convention" not in summary and "staubli_offsets_rad" not in summary
    assert summary["envelope"]["self_collision"] and summary["envelope"]["pairs_checked"] > 0
    assert "NOT checked" not in proc.stderr and "self-collision: " in proc.stderr
    report = (out / "T.html").read_text()
    assert report.count("<img") == 2 and "largest point speed" in report


@pytest.mark.slow
def test_a_floor_with_a_start_pose_above_it_succeeds_and_is_held(tmp_path):
    home = "0,-1.5708,0,-1.5708,0,0"  # UR's upright home pose, far above z = 0.1 m
    proc = run(*UR5_ARGS, "--acceleration", "6", "--duration", "6", "--harmonics", "2", "--starts", "1",
               "--floor", "0.1", "--controller", "ur", "--controller-rate", "500", "--start-pose", home, "--out", str(tmp_path / "t.csv"),
               "--json", str(tmp_path / "t.json"))
    assert proc.returncode == 0, proc.stderr
    usage = json.loads((tmp_path / "t.json").read_text())["limits_usage"]
    assert usage["z_min_m"] == pytest.approx(0.1 - 0.089159) and usage["min_height_m"] >= usage["z_min_m"]
    data = np.genfromtxt(tmp_path / "t.csv", delimiter=",", names=True)
    q = np.column_stack([data[f"q{j}"] for j in range(1, 7)])
    assert np.allclose(q[0], [0, -1.5708, 0, -1.5708, 0, 0])  # the approach starts at the pose
    frames = _pinocchio_frames(q[::10])
    for name in ("forearm_link", "wrist_1_link", "wrist_2_link", "wrist_3_link", "tool0"):
        assert frames[name][:, 2].min() >= 0.1 - 1e-6, name  # --floor: above the URDF root's z = 0


def test_urscript_has_one_servoj_per_sample_at_the_period():
    q = np.random.default_rng(0).uniform(-1, 1, (7, 6))
    text = cp.urscript(q, 125.0, start_pose=np.zeros(6))
    assert np.allclose(cp.parse_servoj(text), q, atol=1e-9)
    assert text.count(", 0.008, 0.1, 300)") == 7 and text.count("movej(") == 3
    with pytest.raises(ValueError, match="lookahead_time"):
        cp.urscript(q, 500.0, lookahead=0.5)


def test_franka_check_names_the_broken_limit_from_finite_differences():
    t = np.arange(2000) / 1000.0
    slow = 0.1 * (1 - np.cos(np.pi * t))[:, None] * np.ones(7)
    assert cp.franka_check(slow) == []
    fast = 0.5 * np.sin(40 * t)[:, None] * np.ones(7)  # 20 rad/s: velocity, acceleration, jerk
    problems = cp.franka_check(fast)
    assert any("velocity limit of joint 1" in p for p in problems) and any("jerk" in p for p in problems)
    tau = np.cumsum(np.full((2000, 7), 2.0), axis=0)  # 2000 N m/s
    assert any("torque rate" in p for p in cp.franka_check(slow, tau))
    step = np.where(t[:, None] < 1.0, -1.0, 1.0) * np.ones(7)  # a Coulomb step at a reversal
    qd = (t - 0.9995)[:, None] * np.ones(7)  # the velocity changes sign between t = 0.999 and 1.0 s
    assert any("torque rate" in p for p in cp.franka_check(slow, step))
    assert not any("torque rate" in p for p in cp.franka_check(slow, step, qd=qd))


@pytest.mark.parametrize("name", ["rx90", "tx40", "ur10e", "panda", UR5])
def test_every_robot_has_capsules_that_fit_and_a_centre_inside_the_envelope(name):
    robot = rx90sym.load_robot(name, **({"tip": "tool0", "acceleration": 6.0} if name == UR5 else {}))
    collision = excitation.collision_model(robot)
    assert collision.self_collision and not collision.capsules.ignored and collision.capsules.pairs
    model, info = excitation.safe_model(robot, None, rx90sym.base_parameters(robot), excitation.Envelope(), collision)
    assert pose_violations(model, model.centre) == []
    assert info["pairs_checked"] == len(collision.capsules.pairs)


def test_capsule_distances_agree_with_coal():
    coal = pytest.importorskip("coal")
    robot = rx90sym.load_robot("ur10e")
    caps = capsule_set(robot, arm_geometry(robot))
    rng = np.random.default_rng(1)
    for q in rng.uniform(-np.pi, np.pi, (5, 6)):
        ends = np.asarray(caps.segments(q)).reshape(3, -1, order="F")
        for i, j in caps.pairs[:6]:
            a, b = ends[:, 2 * i], ends[:, 2 * i + 1]
            c, d = ends[:, 2 * j], ends[:, 2 * j + 1]
            mine = _segment_distance(a[None], b[None], c[None], d[None])[0] - caps.radii[i] - caps.radii[j]
            shapes = []
            for p0, p1, r in ((a, b, caps.radii[i]), (c, d, caps.radii[j])):
                axis = p1 - p0
                length = float(np.linalg.norm(axis))
                z = axis / length if length > 0 else np.array([0.0, 0.0, 1.0])
                x = np.cross(z, [1.0, 0, 0] if abs(z[0]) < 0.9 else [0, 1.0, 0])
                x /= np.linalg.norm(x)
                R = np.column_stack([x, np.cross(z, x), z])
                shapes.append((coal.Capsule(r, length), coal.Transform3s(R, 0.5 * (p0 + p1))))
            result = coal.DistanceResult()
            coal.distance(shapes[0][0], shapes[0][1], shapes[1][0], shapes[1][1], coal.DistanceRequest(), result)
            if mine > 0:
                assert result.min_distance == pytest.approx(mine, abs=1e-6)


@pytest.mark.parametrize("extra, message", [
    (("--position-limits", "0:0,-1:1,-1:1,-1:1,-1:1,-1:1"), "zero or negative width"),
    (("--controller", "ur", "--start-pose", "9,0,0,0,0,0"), "outside the robot's range"),
    (("--floor", "5"), "no pose of the arm lies inside the envelope"),  # above the arm's reach
    (("--max-tool-speed", "2"), "at most 1.5"),
    (("--controller", "ur", "--start-pose", "0,0,0,0,0,0"), "outside the safety envelope: "),
])
def test_bad_envelope_input_exits_2_and_writes_nothing(tmp_path, capsys, extra, message):
    from identify.app.cli import main  # in this process: the refusals come before any optimisation

    out = tmp_path / "t.csv"
    code = main([*UR5_ARGS, "--acceleration", "6", "--duration", "6", "--harmonics", "2", "--starts", "1",
                 *extra, "--out", str(out), "--json", str(tmp_path / "t.json")])
    err = capsys.readouterr().err
    assert code == 2, err
    assert message.replace("at most 1.5", "1.5] m/s") in err or message in err, err
    assert list(tmp_path.iterdir()) == []


def test_height_refusal_gives_the_users_floor_and_the_optimisers_margin_apart():
    from excitation.envelope import height_violation

    below = height_violation("tool point", 0.08, 0.1, 0.01)
    assert "at z = 0.0800 m, below the lowest allowed z = 0.1000 m (the optimiser keeps a further 0.01 m)" in below
    inside = height_violation("tool point", 0.105, 0.1, 0.01)  # above the floor, within the optimiser's margin
    assert "below" not in inside
    assert "less than the optimiser's further 0.01 m above the lowest allowed z = 0.1000 m" in inside
    assert height_violation("tool point", 0.08, 0.1, 0.0).endswith("below the lowest allowed z = 0.1000 m")
