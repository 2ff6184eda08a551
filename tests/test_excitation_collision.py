"""Link capsules kept apart and out of obstacle boxes (issue 15), checked independently."""
from __future__ import annotations

import numpy as np
import pytest

import excitation
from excitation.collision import Box, arm_capsules, capsule_clearances, clearance_function

rx90sym = pytest.importorskip("rx90sym")


@pytest.fixture(scope="module")
def robot():
    return rx90sym.load_robot("rx90")


def _brute_clearance(capsules, q, boxes, points=120):
    """Independent check: dense points on each segment, pairwise and box distances."""
    ends = np.asarray(capsules.segments.map(q.shape[0], "serial")(q.T)).reshape(3, -1, q.shape[0], order="F")
    s = np.linspace(0.0, 1.0, points)
    pts = ends[:, 0::2, :, None] + (ends[:, 1::2, :, None] - ends[:, 0::2, :, None]) * s  # (3, k, N, P)
    out = np.full(q.shape[0], np.inf)
    for i, j in capsules.pairs:
        d = np.linalg.norm(pts[:, i, :, :, None] - pts[:, j, :, None, :], axis=0).min(axis=(1, 2))
        out = np.minimum(out, d - capsules.radii[i] - capsules.radii[j])
    for box in boxes:
        lo, hi = np.array(box.lo)[:, None, None], np.array(box.hi)[:, None, None]
        for i, r in enumerate(capsules.radii):
            p = pts[:, i]
            gap = np.maximum(np.maximum(lo - p, p - hi), 0.0)
            outside = np.linalg.norm(gap, axis=0)
            depth = np.min(np.minimum(p - lo, hi - p), axis=0)  # > 0 inside
            out = np.minimum(out, np.where(outside > 0, outside, -depth).min(axis=1) - r)
    return out


def test_rx90_capsules_follow_the_geometry(robot):
    caps = arm_capsules(robot)
    assert caps.names[0] == "base" and len(caps.radii) == 4 and caps.pairs == ((0, 2), (0, 3), (1, 3))
    ends = np.asarray(caps.segments(np.zeros(6)))
    upper = np.linalg.norm(ends[:, 3] - ends[:, 2])
    forearm = np.linalg.norm(ends[:, 5] - ends[:, 4])
    assert upper == pytest.approx(robot.d[2]) and forearm == pytest.approx(robot.r[3])


def test_exact_clearance_matches_dense_sampling_and_ball_cover_is_conservative(robot):
    caps = arm_capsules(robot)
    box = Box((0.3, -0.3, -0.6), (0.8, 0.3, -0.2))
    q = np.random.default_rng(1).uniform(-2.5, 2.5, (150, 6))
    exact = capsule_clearances(caps, q, [box])
    brute = _brute_clearance(caps, q, [box])
    # dense points (120 per 0.5 m segment) are at most ~2 mm from the true closest points
    np.testing.assert_allclose(exact, brute, atol=5e-3)
    assert np.mean(exact < 0) > 0.1 and np.mean(exact > 0) > 0.1  # both cases covered
    cover = clearance_function(caps, [box])
    smallest = np.array([np.min(np.asarray(cover(x))) for x in q])
    # Balls contain the capsules: where the balls are apart, the capsules are at least as far
    # apart (never optimistic); inside contact both are only penetration measures.
    apart = smallest >= 0.0
    assert np.mean(apart) > 0.1 and np.all(smallest[apart] <= exact[apart] + 1e-9)


def test_box_parsing_refuses_bad_input():
    assert Box.parse("0,0,0,1,2,3") == Box((0, 0, 0), (1, 2, 3))
    with pytest.raises(ValueError, match="expected 6 numbers"):
        Box.parse("0,0,0,1,2")
    with pytest.raises(ValueError, match="must exceed min corner"):
        Box.parse("0,0,0,1,-2,3")


@pytest.mark.slow
def test_optimised_trajectory_keeps_out_of_an_obstacle_it_would_hit(robot):
    bp = rx90sym.base_parameters(robot)
    chi = robot.parameter_vector(rx90sym.default_parameters(robot))
    from excitation.fourier import FourierSeries
    from excitation.optimiser import initial_free, start_rng
    from excitation.options import OptimiserOptions
    from excitation.trajectory import sample_times

    # the optimiser's own starting motion (start 1 of seed 0): put the box where its tool goes
    model, form, options = excitation.model_from_robot(robot, chi, bp), FourierSeries(6.0, 2), OptimiserOptions()
    grid = sample_times(6.0, options.constraint_grid_rate(form.max_frequency_hz))
    z0 = initial_free(model, form, start_rng(0, 1), options.start_fraction, grid, options.margins)
    q = form.evaluate(form.rest_basis() @ z0, sample_times(6.0, 100.0))[0]
    caps = arm_capsules(robot)
    ends = np.asarray(caps.segments.map(q.shape[0], "serial")(q.T)).reshape(3, -1, q.shape[0], order="F")
    tool = ends[:, -1, np.argmax(ends[0, -1, :])]          # where the start's tool reaches furthest
    box = Box(tuple(tool - 0.1), tuple(tool + 0.1))
    assert np.min(_brute_clearance(caps, q, [box])) < -0.05  # the start goes through the box
    traj = excitation.optimise(robot, 6.0, 2, seed=0, chi_nominal=chi, base=bp, starts=1, progress=False, envelope=None,
                               collision=excitation.collision_model(robot, [box]))
    t2, q2, _, _ = traj.sample(2000.0, closed=True)         # finer than the optimiser's 1 kHz check
    assert np.min(_brute_clearance(caps, q2[::4], [box])) > -2e-3
    assert traj.usage.feasible and traj.usage.min_clearance >= 0.0


def test_capsules_touching_at_the_centre_of_the_ranges_are_refused(robot):
    box = Box((-0.2, -0.2, -0.2), (0.2, 0.2, 0.2))  # around the shoulder
    with pytest.raises(ValueError, match="capsules touch .* at the centre of the joint ranges \\(clearance -"):
        excitation.optimise(robot, 6.0, 2, starts=1, progress=False, envelope=None,
                            collision=excitation.collision_model(robot, [box]))


def test_default_radii_scale_with_the_reach(robot):
    tx40 = rx90sym.load_robot("tx40")
    big, small = arm_capsules(robot), arm_capsules(tx40)
    assert big.radii == pytest.approx((0.15, 0.10, 0.08, 0.06))
    assert np.array(small.radii) / np.array(big.radii) == pytest.approx(np.full(4, 0.485 / 0.9))
    centre = 0.5 * (np.asarray(tx40.limits.q_min) + np.asarray(tx40.limits.q_max))
    assert capsule_clearances(small, np.where(np.isfinite(centre), centre, 0.0)[None, :])[0] > 0.0


@pytest.mark.parametrize("name", ["ur10e", "panda"])
def test_default_capsules_do_not_fit_an_arm_with_offsets_but_its_own_capsules_do(robot, name):
    """Segments between frame origins do not describe an arm with offsets (a UR's wrist, a Panda):
    they touch at the centre of the ranges. The robot file's own [[capsules]] do not, so
    self-collision stays on with every non-adjacent pair checked."""
    arm = rx90sym.load_robot(name)
    centre = 0.5 * (np.asarray(arm.limits.q_min) + np.asarray(arm.limits.q_max))
    centre = np.where(np.isfinite(centre), centre, 0.0)[None, :]
    raw = arm_capsules(arm)
    assert capsule_clearances(raw, centre)[0] < 0.0  # every motion would be refused
    model = excitation.collision_model(arm)
    assert model.self_collision and model.capsules.ignored == () and model.capsules.pairs
    assert capsule_clearances(model.capsules, centre)[0] > 0.0
    rx = excitation.collision_model(robot)
    assert rx.self_collision and rx.capsules.ignored == ()


@pytest.mark.parametrize("name", ["rx90", "tx40"])
def test_the_optimisers_ball_cover_leaves_the_clearance_margin_at_the_centre_of_the_ranges(name):
    """The repair imposes the ball cover >= margin on the whole grid: if the centre of the ranges
    breaks it, IPOPT declares the repair infeasible (the TX40's base column with 5 balls of
    inflated radius r + spacing/2: 0.013 m at the centre against a 0.03 m margin). Balls at most one
    radius apart leave most of the exact clearance to the optimiser."""
    arm = rx90sym.load_robot(name)
    model = excitation.collision_model(arm)
    assert model.self_collision
    centre = 0.5 * (np.asarray(arm.limits.q_min) + np.asarray(arm.limits.q_max))
    centre = np.where(np.isfinite(centre), centre, 0.0)
    exact = model.exact(centre[None, :])[0]
    cover = float(np.min(np.asarray(model.clearance(centre))))
    assert excitation.OptimiserOptions().margins.clearance < cover <= exact
    assert exact - cover < 0.5 * min(model.capsules.radii) + 0.5 * max(model.capsules.radii)
    # One smooth row per checked pair (the soft minimum over its ball pairs), none for the
    # pairs never close in random poses.
    caps = model.capsules
    assert model.clearance.size1_out(0) == len(caps.pairs) - len(caps.never)
