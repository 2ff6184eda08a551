"""The friction choice's columns of every fold in one pass (identify.friction.folds.FoldColumns:
a column FSj_f per fold f, resting like FSj): the same numbers as the rows of the form's own FrictionBase
at that fold's scales, whatever the rest policy; and the tanh columns within an ulp of CasADi's
expression of the form."""
from __future__ import annotations

import numpy as np
import pytest

import rx90sym
from identify.friction.folds import FoldColumns
from identify.friction.forms import friction_columns, friction_function
from identify.observation.rest import coulomb_terms, own_terms
from identify.friction.columns import friction_base
from identify.observation.matrix import filtered_motions
from identify.observation.processing import Processing
from rx90sym.twin import simulate

from motions import multisine, stop_and_go


@pytest.fixture(scope="module")
def ur10e_run():
    robot = rx90sym.load_robot("ur10e")
    rec = simulate(robot, stop_and_go(multisine(robot, 3, duration=8.0)), duration=8.0, rate=100.0,
                   noise="quantised", seed=3)
    return robot, rec, rx90sym.base_parameters(robot)


def _rows(robot, rec, columns, options):
    """(Phi, usable) of the recording's motion with ``columns``."""
    m = filtered_motions(robot, [rec], Processing(**options), columns.regressor_batch, columns.names)[0][0]
    return m.Phi, m.usable


@pytest.mark.parametrize("options", [
    {"cutoff": 3.0, "decimate_to": 50.0, "min_velocity": 0.05, "rest": "crossing"},
    {"cutoff": 5.0, "decimate_to": None, "min_velocity": 0.05, "rest": "zero-coulomb", "delay": 0.004},
    {"cutoff": 4.0, "decimate_to": 25.0, "min_velocity": None, "rest": "drop"},
])
def test_every_fold_s_columns_equal_the_form_s_own_columns_at_its_scales(ur10e_run, options):
    robot, rec, base = ur10e_run
    terms = own_terms(coulomb_terms(robot, base.names))
    rng = np.random.default_rng(0)
    scales = [tuple(rng.uniform(0.005, 0.5, robot.n)) for _ in range(2)]
    for form in ["tanh", ("tanh", "coulomb", "tanh", "coulomb", "coulomb", "tanh"), "stribeck"]:
        folds = FoldColumns(base, terms, form, tuple(scales))
        Phi, usable = _rows(robot, rec, folds, options)
        names = list(folds.names)
        for f, s in enumerate(scales):
            own = friction_base(base, terms, form, s)
            ref, ref_usable = _rows(robot, rec, own, options)
            assert np.array_equal(usable, ref_usable)
            for t in terms:
                smooth = (form if isinstance(form, str) else form[t.row]) != "coulomb"
                got = Phi[:, t.row, names.index(f"FS{t.row + 1}_{f}") if smooth else t.column]
                assert np.array_equal(got, ref[:, t.row, t.column]), (form, f, t.name)   # the same numbers
                if smooth and form == "stribeck":
                    fst = list(own.names).index(f"FST{t.row + 1}")
                    assert np.array_equal(Phi[:, t.row, names.index(f"FST{t.row + 1}_{f}")], ref[:, t.row, fst])
            # The other columns are the Coulomb form's, untouched.
            c = len(base.names)
            others = [k for k in range(c) if k not in {t.column for t in terms}]
            assert np.array_equal(Phi[:, :, others], ref[:, :, others])
        if options["min_velocity"] is not None and options["decimate_to"] is None:
            # A smooth column rests like FSj: 0 where its joint rests (before any decimation filter).
            j = terms[0]
            column = Phi[:, j.row, names.index(f"FS{j.row + 1}_0")]
            assert np.any(column == 0.0) and np.any(column != 0.0)


def test_the_tanh_columns_are_casadi_s_expression_of_the_form():
    rng = np.random.default_rng(1)
    v = np.concatenate([rng.normal(0.0, 0.5, 2000), [0.0, -0.0, 1e-9, -3.0, 3.0]])
    for vs in (1e-4, 3e-3, 0.05, 0.7, 2.0):
        cols, dcols = friction_columns("tanh", v, vs)
        ref, dref = (np.asarray(a).ravel() for a in friction_function("tanh")(v.reshape(1, -1), vs))
        np.testing.assert_allclose(cols[:, 0], ref, rtol=4e-16, atol=1e-300)    # an ulp
        # -(1 - t²)·v/vs²: an ulp of t near ±1 is 2 ulp of 1 - t², times |v|/vs².
        assert np.all(np.abs(dcols[:, 0] - dref) <= 1e-15 * (np.abs(dref) + np.abs(v) / vs ** 2))
