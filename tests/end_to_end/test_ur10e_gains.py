"""UR10e drive gains on the real 14-harmonic pair (issue 12): the payload mass on held-out samples.

The logs have no licence: read in place from ../shared, skipped when absent.
"""
from __future__ import annotations

import numpy as np
import pytest

from conftest import SHARED, benchmark_module

DATA = SHARED / "data" / "ur10e"
needs_data = pytest.mark.skipif(not (DATA / "ur-20_02_19_14harm50sec.csv").exists(),
                                reason=f"UR10e logs not found in {DATA} (../shared is absent)")
# UR's published standard DH of the UR10e (README): d, a, alpha per joint.
UR10E_DH = [(0.1807, 0.0, np.pi / 2), (0.0, -0.6127, 0.0), (0.0, -0.57155, 0.0),
            (0.17415, 0.0, np.pi / 2), (0.11985, 0.0, -np.pi / 2), (0.11655, 0.0, 0.0)]


def _bench():
    return benchmark_module("ur10e_gains")


def _standard_dh(q: np.ndarray) -> np.ndarray:
    """T0-6 = prod Rz(q) Tz(d) Tx(a) Rx(alpha), written out here (independent of rx90sym)."""
    T = np.eye(4)
    for qi, (d, a, alpha) in zip(q, UR10E_DH):
        c, s, ca, sa = np.cos(qi), np.sin(qi), np.cos(alpha), np.sin(alpha)
        T = T @ np.array([[c, -s * ca, s * sa, a * c], [s, c * ca, -c * sa, a * s], [0, sa, ca, d], [0, 0, 0, 1]])
    return T


def test_the_benchmark_robot_is_urs_kinematics():
    robot = _bench().ur10e_robot()
    rng = np.random.default_rng(0)
    for q in rng.uniform(-np.pi, np.pi, (20, 6)):
        T = np.array(robot.forward_kinematics(q)[0])
        np.testing.assert_allclose(T, _standard_dh(q), atol=1e-12)


@pytest.fixture(scope="module")
def ur():
    b = _bench()
    robot = b.ur10e_robot()
    empty = b.load_run(DATA / b.EMPTY[0], b.EMPTY[1])
    loaded = b.load_run(DATA / b.LOADED[0], b.LOADED[1])
    return b, robot, empty, loaded


@needs_data
@pytest.mark.slow
def test_gains_fitted_on_25_s_give_the_mass_on_the_rest(ur, ur10e_gains_25s):
    b, robot, p, (e, l), res, cut = ur10e_gains_25s
    empty = ur[2]
    assert p.gap < 0.005  # the same trajectory, run ~17 min apart on the controller's clock
    # Joint 1 (vertical axis) feels the payload only through its unknown inertia: flagged.
    assert res.flagged == (1,)
    # The controller's own constants (independent: its target current on its target torque)
    # agree within 12 % on the joints the payload's mass reaches (measured 2-8 %).
    ctrl = b.controller_constants(empty)
    assert np.all(np.abs(res.gains.gains[1:] / ctrl[1:] - 1) < 0.12), res.gains.gains / ctrl
    rest = (e.select(slice(cut, e.n_samples)), l.select(slice(cut, l.n_samples)))
    mine = b.held_out_mass(robot, res.gains.gains, *rest)
    source = b.held_out_mass(robot, np.array(b.SOURCE_GAINS), *rest)
    for m in (3, 4):
        assert abs(mine[m][0] / b.MASS - 1) < 0.015, (m, mine[m])
        assert source[m][0] / b.MASS - 1 < -0.08, (m, source[m])  # README: about 12 % low


@needs_data
def test_controller_constants_do_not_depend_on_the_run(ur):
    """The regression of target current on target torque is a property of the controller."""
    b, robot, empty, loaded = ur
    np.testing.assert_allclose(b.controller_constants(empty), b.controller_constants(loaded), rtol=0.01)
