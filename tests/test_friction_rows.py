"""The observation of another friction form built from the Coulomb form's by re-filtering its friction
columns only (identify.observation.friction_rows, what the friction choice scores its folds with): the
same numbers as the observation built whole from the form's FrictionBase, and the tanh columns within an
ulp of CasADi's expression of the form."""
from __future__ import annotations

import numpy as np
import pytest

import rx90sym
from identify.observation.friction import friction_columns, friction_function
from identify.observation.friction_model import coulomb_terms, friction_base, friction_probe
from identify.observation.friction_rows import with_friction_form
from identify.observation.matrix import observation_matrix
from rx90sym.twin import simulate

from motions import multisine, stop_and_go


@pytest.fixture(scope="module")
def ur10e_run():
    robot = rx90sym.load_robot("ur10e")
    rec = simulate(robot, stop_and_go(multisine(robot, 3, duration=8.0)), duration=8.0, rate=100.0,
                   noise="quantised", seed=3)
    return robot, rec, rx90sym.base_parameters(robot)


@pytest.mark.parametrize("options", [
    {"cutoff": 3.0, "decimate_to": 50.0, "min_velocity": 0.05, "rest": "crossing", "spring": True},
    {"cutoff": 5.0, "decimate_to": None, "min_velocity": 0.05, "rest": "drop", "spring": True, "delay": 0.004},
    {"cutoff": 4.0, "decimate_to": 25.0, "min_velocity": None, "rest": "drop", "spring": True},
])
def test_the_forms_built_from_the_coulomb_observation_equal_the_forms_built_whole(ur10e_run, options):
    robot, rec, base = ur10e_run
    terms = coulomb_terms(robot, base.names)
    coulomb = observation_matrix(robot, [rec], base=base, **options)
    scales = np.random.default_rng(0).uniform(0.005, 0.5, robot.n)
    forms = ["probe", "tanh", ("tanh", "coulomb", "tanh", "coulomb", "coulomb", "tanh"), "stribeck"]
    for form in forms:
        columns = friction_probe(robot, base)[1] if form == "probe" else friction_base(base, terms, form, scales)
        whole = observation_matrix(robot, [rec], base=columns, **options)
        got = with_friction_form(robot, [rec], coulomb, base, form, None if form == "probe" else scales, **options)
        assert got.names == whole.names
        assert np.array_equal(got.joint, whole.joint) and np.array_equal(got.Y, whole.Y)
        assert np.array_equal(got.W, whole.W), form   # the same numbers, not merely close
        if form != "stribeck":   # the Coulomb columns did change
            assert not np.array_equal(got.W, coulomb.W)


def test_the_tanh_columns_are_casadi_s_expression_of_the_form():
    rng = np.random.default_rng(1)
    v = np.concatenate([rng.normal(0.0, 0.5, 2000), [0.0, -0.0, 1e-9, -3.0, 3.0]])
    for vs in (1e-4, 3e-3, 0.05, 0.7, 2.0):
        cols, dcols = friction_columns("tanh", v, vs)
        ref, dref = (np.asarray(a).ravel() for a in friction_function("tanh")(v.reshape(1, -1), vs))
        np.testing.assert_allclose(cols[:, 0], ref, rtol=4e-16, atol=1e-300)    # an ulp
        # -(1 - t²)·v/vs²: an ulp of t near ±1 is 2 ulp of 1 - t², times |v|/vs².
        assert np.all(np.abs(dcols[:, 0] - dref) <= 1e-15 * (np.abs(dref) + np.abs(v) / vs ** 2))
