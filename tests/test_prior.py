"""The prior of the consistent fit on the RX90 twin: base parameters from the data, the directions the
data cannot see from the prior (not an arbitrary vertex of the feasible set)."""
from __future__ import annotations

import numpy as np
import pytest

import rx90sym
from identify import Processing, fit
from identify.estimation.consistency.prior import Ellipsoid, PhysicalPrior, bodies_table
from identify.estimation.consistency.prior_fit import unseen_distance
from rx90sym.rigid_body import RigidBody

from motions import multisine

FIELDS = ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")


def perturbed(truth: dict, rng: np.random.Generator, by: float = 0.3) -> dict:
    """Each link's mass, CoG coordinates and inertia at the CoG, and each IA, off by +-30 %
    (a physical body again: the inertia is scaled as a whole)."""
    out = dict(truth)
    for j in range(1, 7):
        body = RigidBody.from_vector(np.array([truth[f"{p}{j}"] for p in FIELDS]))
        c, I = body.com_inertia()
        f = lambda size=None: 1 + rng.choice([-by, by], size)  # noqa: E731
        moved = RigidBody.from_com(body.m * f(), c * f(3), np.eye(3), I * f())
        out.update(zip([f"{p}{j}" for p in FIELDS], moved.vector()))
        out[f"IA{j}"] = truth[f"IA{j}"] * f()
    return out


@pytest.fixture(scope="module")
def twin_fit(rx90):
    """Two 20 s motions of the twin with quantisation and white torque noise (the model holds at
    rest too: no rest mask); the WLS fit."""
    from identify.fitting.fit import _honest_covariance

    recs = [rx90sym.twin.simulate(rx90, multisine(rx90, s), duration=20.0, noise="quantised", seed=s)
            for s in (0, 1)]
    wls = fit(rx90, recs, Processing(min_velocity=None, estimate_delay=False))
    without = fit(rx90, recs, method="consistent", base=wls.base, observation=wls.observation,
                  physical_prior=None).result
    # The covariance fit() computes for the prior's budget, once for the three priors.
    return recs, wls, without, _honest_covariance(wls.observation, wls.result)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_perturbed_prior_keeps_the_data_and_fills_what_they_cannot_see(rx90, twin_fit, seed):
    recs, wls, without, covariance = twin_fit
    truth = rx90sym.default_parameters(rx90)
    base = wls.base
    beta_truth = base.beta(rx90.parameter_vector(truth))
    prior = PhysicalPrior(perturbed(truth, np.random.default_rng(seed)), "truth +-30 %")
    with_prior = fit(rx90, recs, method="consistent", base=wls.base, observation=wls.observation,
                     physical_prior=prior, covariance=covariance).result
    z = np.abs(with_prior.values - beta_truth) / wls.result.std
    assert z.max() <= 3.0, (with_prior.names[int(np.argmax(z))], z.max())   # measured 2.4-2.7
    chi = rx90.parameter_vector(with_prior.standard)
    assert unseen_distance(base.K, rx90.parameter_names, prior, chi) <= 0.05   # measured < 0.2 %
    # Without a prior the same directions are wherever the solver stopped (58-100 % away).
    chi0 = rx90.parameter_vector(without.standard)
    assert unseen_distance(base.K, rx90.parameter_names, prior, chi0) > 0.2
    assert "from the prior: truth +-30 %" in with_prior.split and "arbitrary" in without.split
    # Every centre of mass inside its link's bounding ellipsoid; masses above the floor.
    for j in range(1, 7):
        body = RigidBody.from_vector(np.array([with_prior.standard[f"{p}{j}"] for p in FIELDS]))
        assert prior.ellipsoid(str(j)).contains(body.com_inertia()[0])
        assert body.m >= prior.mass_floor * prior.values[f"M{j}"] * (1 - 1e-6)
    assert "yes" in bodies_table(6, with_prior.standard, prior)


def test_the_ellipsoid_condition_is_the_mass_weighted_quadric():
    """tr(J P) = sum of m_k (1 - (x_k - c)^T A (x_k - c)) over point masses (Wensing et al. 2017)."""
    from identify.estimation.consistency.lmi import pseudo_inertia

    rng = np.random.default_rng(1)
    e = Ellipsoid(rng.normal(0, 0.1, 3), np.diag(rng.uniform(1, 20, 3)))
    points, masses = rng.normal(0, 0.2, (5, 3)), rng.uniform(0.1, 2, 5)
    J = sum(m * np.outer([*x, 1.0], [*x, 1.0]) for x, m in zip(points, masses))
    body = sum((RigidBody.from_com(m, x, np.eye(3), np.zeros((3, 3))) for x, m in zip(points, masses)),
               RigidBody.zero())
    np.testing.assert_allclose(pseudo_inertia(body.vector()), J, atol=1e-12)
    expected = sum(m * (1 - (x - e.centre) @ e.A @ (x - e.centre)) for x, m in zip(points, masses))
    assert np.trace(J @ e.quadric()) == pytest.approx(expected, rel=1e-12)


def test_a_wrong_prior_is_flagged_and_the_right_one_is_not(rx90, twin_fit):
    """bodies_far_from_prior / consistent_cost_high (identify.fitting.plausibility.prior_flags), as the
    identify command computes them (its _fit_flags): the twin against its own parameters (the
    right robot file) gives neither (cost +0.04 %); against a prior whose bodies are 5x heavier
    (a robot file of another, heavier arm) links are flagged, each with both masses and the ratio.
    (The RX90 file's [nominal] table is not the twin's truth: against it the fit costs +330 % and
    both flags are raised, docs/plausibility.md.)"""
    from identify.app.commands.identify_cmd import _fit_flags
    from identify.fitting.plausibility import CONSISTENT_COST_PCT, PRIOR_MASS_RATIO

    recs, wls, _, covariance = twin_fit
    truth = rx90sym.default_parameters(rx90)
    # Mass, first moments and inertias x5: the same centres of mass and shapes, 5x heavier bodies.
    heavy = {k: 5 * v if k.startswith(("M", "XX", "XY", "XZ", "YY", "YZ", "ZZ")) else v for k, v in truth.items()}
    codes = {}
    for name, values in (("right", truth), ("heavy", heavy)):
        prior = PhysicalPrior(values, name)
        f = fit(rx90, recs, method="consistent", base=wls.base, observation=wls.observation,
                physical_prior=prior, covariance=covariance)
        flags = _fit_flags(f, "consistent", prior)
        codes[name] = [fl.code for fl in flags]
        ratios = {j: f.result.standard[f"M{j}"] / values[f"M{j}"] for j in range(1, 7)}
        print(name, f"cost +{f.result.cost_increase_pct:.3f} %", np.round(list(ratios.values()), 3), codes[name])
        if name == "right":
            assert f.result.cost_increase_pct < CONSISTENT_COST_PCT / 2
            assert all(1 / PRIOR_MASS_RATIO <= r <= PRIOR_MASS_RATIO for r in ratios.values())
        else:
            far = [fl for fl in flags if fl.code == "bodies_far_from_prior"]
            assert far and all(fl.severity == "warning" and "x its prior mass" in fl.message for fl in far)
            outside = {f"M{j}" for j, r in ratios.items() if not 1 / PRIOR_MASS_RATIO <= r <= PRIOR_MASS_RATIO}
            assert {fl.parameter for fl in far} == outside   # measured: M3 (0.26) and M5 (0.18)
    assert not {"bodies_far_from_prior", "consistent_cost_high"} & set(codes["right"])


def test_the_cost_flag_judges_the_increase_over_wls():
    """consistent_cost_high on the cost increase alone (the measured cases of docs/plausibility.md:
    good real fits +1.4 % and +1.8 %, the UR10e identified as a TX40 +20 %)."""
    from identify.fitting.plausibility import CONSISTENT_COST_PCT, prior_flags

    assert prior_flags({}, {}, 1.82) == [] and prior_flags({}, {}, float("nan")) == []
    (flag,) = prior_flags({"M1": 1.0}, {"M1": 1.2}, 20.0, "tx40")
    assert flag.code == "consistent_cost_high" and flag.severity == "warning" and "tx40" in flag.message
    assert f"{CONSISTENT_COST_PCT:g} %" in flag.message
