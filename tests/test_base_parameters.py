"""Base parameters: the paper's Table 2 and eq. 19, and symbolic = numeric for any robot."""
from __future__ import annotations

import numpy as np
import pytest

import rx90sym

from conftest import random_states

TABLE_2 = [  # inertial base parameters of Table 2, row by row
    "ZZ1R",
    "XX2R", "XY2", "XZ2R", "YZ2", "ZZ2R", "MX2R", "MY2",
    "XX3R", "XY3", "XZ3", "YZ3", "ZZ3R", "MX3", "MY3R", "IA3",
    "XX4R", "XY4", "XZ4", "YZ4", "ZZ4R", "MX4", "MY4R", "IA4",
    "XX5R", "XY5", "XZ5", "YZ5", "ZZ5R", "MX5", "MY5R", "IA5",
    "XX6R", "XY6", "XZ6", "YZ6", "ZZ6", "MX6", "MY6", "IA6",
]


def eq19(p, d3, rl4):
    """Eq. 19 of the paper, typed in (IA2 goes into ZZ2R as in Table 2)."""
    m36 = p["M3"] + p["M4"] + p["M5"] + p["M6"]
    m46 = p["M4"] + p["M5"] + p["M6"]
    return {
        "ZZ1R": p["IA1"] + d3**2 * m36 + p["YY2"] + p["YY3"] + p["ZZ1"],
        "XX2R": -d3**2 * m36 + p["XX2"] - p["YY2"],
        "XZ2R": -d3 * p["MZ3"] + p["XZ2"],
        "ZZ2R": p["IA2"] + d3**2 * m36 + p["ZZ2"],
        "MX2R": d3 * m36 + p["MX2"],
        "XX3R": 2 * p["MZ4"] * rl4 + m46 * rl4**2 + p["XX3"] - p["YY3"] + p["YY4"],
        "ZZ3R": 2 * p["MZ4"] * rl4 + m46 * rl4**2 + p["YY4"] + p["ZZ3"],
        "MY3R": p["MY3"] - p["MZ4"] - m46 * rl4,
        "XX4R": p["XX4"] - p["YY4"] + p["YY5"],
        "ZZ4R": p["YY5"] + p["ZZ4"],
        "MY4R": p["MY4"] + p["MZ5"],
        "XX5R": p["XX5"] - p["YY5"] + p["YY6"],
        "ZZ5R": p["YY6"] + p["ZZ5"],
        "MY5R": p["MY5"] - p["MZ6"],
        "XX6R": p["XX6"] - p["YY6"],
    }


@pytest.fixture(scope="module")
def bp_rx90(rx90):
    return rx90sym.base_parameters(rx90, method="symbolic")


def test_rx90_has_the_54_base_parameters_of_table_2(bp_rx90):
    friction = [f"F{k}{j}" for j in range(1, 7) for k in "SV"]
    assert bp_rx90.nb == 54
    assert set(bp_rx90.names) == set(TABLE_2) | set(friction) | {"FVM6", "FSM6"}
    assert bp_rx90.names[:4] == ("ZZ1R", "FS1", "FV1", "XX2R")


@pytest.mark.parametrize("d3, rl4", [(0.45, 0.45), (0.31, 0.77)])
def test_every_formula_is_eq19_for_two_geometries(bp_rx90, d3, rl4):
    K = np.array(bp_rx90.K_symbolic(np.array([d3, rl4])))
    assert bp_rx90.geometry_names == ("D3", "RL4")
    rng = np.random.default_rng(0)
    names = bp_rx90.robot.parameter_names
    for _ in range(3):
        chi = rng.normal(size=len(names))
        p = dict(zip(names, chi))
        beta = dict(zip(bp_rx90.names, K @ chi))
        expected = eq19(p, d3, rl4)
        for name, value in beta.items():
            ref = expected[name] if name in expected else p[name]  # plain names: themselves
            assert abs(value - ref) < 1e-12, name
    # The numeric K at the bundled geometry is the symbolic one evaluated there.
    if (d3, rl4) == (0.45, 0.45):
        assert np.allclose(K, bp_rx90.K, atol=1e-15)


def test_expressions_read_like_eq19(bp_rx90):
    e = bp_rx90.expressions
    assert e["MY5R"] == "MY5 - MZ6"
    assert e["MX2R"] == "MX2 + D3*(M3 + M4 + M5 + M6)"
    assert "RL4**2*(M4 + M5 + M6)" in e["ZZ3R"] and "2*RL4*MZ4" in e["ZZ3R"]
    table = bp_rx90.table()
    for name in TABLE_2:
        assert name in table
    assert "XX6R = XX6 - YY6" in table


@pytest.mark.parametrize("which", ["rx90", "tx40", "tx40-offsets", "random"])
def test_symbolic_and_numeric_agree_and_reproduce_the_model(which, rx90, tx40, random_robot):
    robot = {"rx90": rx90, "tx40": tx40, "random": random_robot,
             "tx40-offsets": rx90sym.load_robot("tx40", offsets=True)}[which]
    sym = rx90sym.base_parameters(robot, "symbolic")
    num = rx90sym.base_parameters(robot, "numeric", seed=11)
    assert sym.nb == num.nb and sym.names == num.names
    assert np.allclose(sym.K, num.K, atol=1e-9)
    rng = np.random.default_rng(8)
    Q, QD, QDD = random_states(robot, rng, 40)
    Phi = robot.regressor_batch(Q, QD, QDD)
    Phib = sym.regressor_batch(Q, QD, QDD)
    for _ in range(3):
        chi = rng.normal(size=len(robot.parameter_names))
        lhs = Phi @ chi
        assert np.max(np.abs(lhs - Phib @ sym.beta(chi))) < 1e-9 * max(1, np.abs(lhs).max())
        assert np.max(np.abs(lhs - Phib @ num.beta(chi))) < 1e-9 * max(1, np.abs(lhs).max())
    # Phi_b on random states has full column rank.
    W = Phib.reshape(-1, sym.nb)
    assert np.linalg.matrix_rank(W / np.linalg.norm(W, axis=0)) == sym.nb


def test_tx40_r3_groups_into_the_shoulder(tx40):
    bp = rx90sym.base_parameters(tx40)
    assert bp.nb == 54
    assert "D3*RL3*(M3 + M4 + M5 + M6)" in bp.expressions["XZ2R"]


def test_numeric_rank_equals_symbolic_count_for_every_bundled_robot():
    from rx90sym.base_parameters import numeric_rank, stacked_regressor

    for name in rx90sym.bundled_robots():
        robot = rx90sym.load_robot(name)
        W = stacked_regressor(robot, 80, 3)
        assert numeric_rank(W) == rx90sym.base_parameters(robot).nb


def test_unknown_method_is_refused(rx90):
    with pytest.raises(ValueError, match="method must be"):
        rx90sym.base_parameters(rx90, method="magic")
