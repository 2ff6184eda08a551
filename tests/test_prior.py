"""The identified model on the RX90 twin: the description's bodies as a prior weighed against the data
(identify.fitting.consistent_fit), its weight λ chosen by blocked cross-validation."""
from __future__ import annotations

import math

import numpy as np
import pytest

import rx90sym
from identify import Processing, fit
from identify.estimation.consistency.body_prior import body_prior
from rx90sym.rigid_body import RigidBody

from motions import multisine

FIELDS = ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")


def perturbed(truth: dict, rng: np.random.Generator, by: float) -> dict:
    """Each link's mass, CoG coordinates and inertia at the CoG off by +-``by`` (a physical body again:
    the inertia is scaled as a whole)."""
    out = dict(truth)
    for j in range(1, 7):
        body = RigidBody.from_vector(np.array([truth[f"{p}{j}"] for p in FIELDS]))
        c, I = body.com_inertia()
        f = lambda size=None: 1 + rng.choice([-by, by], size)  # noqa: E731
        moved = RigidBody.from_com(body.m * f(), c * f(3), np.eye(3), I * f())
        out.update(zip([f"{p}{j}" for p in FIELDS], moved.vector()))
    return out


@pytest.fixture(scope="module")
def twin(rx90):
    """A 12 s motion of the twin with quantisation and white torque noise (no rest mask)."""
    rec = rx90sym.twin.simulate(rx90, multisine(rx90, 0), duration=12.0, noise="quantised", seed=0)
    return rec, rx90sym.default_parameters(rx90)


PROCESSING = Processing(min_velocity=None, estimate_delay=False, cross_validate=False, cutoff=20.0)


def test_an_exact_description_is_kept_at_the_top_of_the_grid(rx90, twin):
    """λ = inf: every base parameter is the data's where they determine it (within 2σ of the least squares),
    the description's where the data say nothing (share 0); the drives are the data's."""
    rec, truth = twin
    f = fit(rx90, [rec], PROCESSING, physical_prior=truth)
    model = f.identified
    assert model.prior["choice"]["chosen_label"] == "inf", model.prior["choice"]["table"]
    bp = rx90sym.base_parameters(rx90)
    described = dict(zip(bp.names, bp.beta(rx90.parameter_vector(truth))))
    share = dict(zip(model.names, model.data_share))
    determined = set(model.prior["determined"])
    for name, value, least, std in zip(model.names, model.values, model.least_squares, model.std):
        if name in determined:
            assert abs(value - least) <= 2 * std, name
        elif share[name] < 1e-6:
            assert value == pytest.approx(described[name], rel=1e-6, abs=1e-8), name
    assert share["FV1"] > 0.999 and min(share.values()) < 1e-6
    assert model.moved() == [] and "held more than 2σ" not in model.table()  # the drives and all it determines: the data's


@pytest.mark.parametrize("seed", [0, 1])
def test_a_description_half_wrong_keeps_what_the_data_determine(rx90, twin, seed):
    """Every base parameter the data determine (relative σ of the least squares on the model's columns
    under 10 %) within 2 σ of that estimate, with a description whose bodies are all 50 % off."""
    rec, truth = twin
    f = fit(rx90, [rec], PROCESSING, physical_prior=perturbed(truth, np.random.default_rng(seed), 0.5))
    model = f.identified
    z = {n: abs(v - ls) / s for n, v, ls, s, r in zip(model.names, model.values, model.least_squares, model.std,
                                                     model.rel_std_pct) if r < 10}
    assert len(z) > 30
    worst = max(z, key=z.get)
    assert z[worst] <= 2.0, (worst, z[worst], model.prior["choice"]["table"])
    assert model.prior_weight < math.inf


def test_the_weight_moves_the_model_from_the_data_to_the_description(rx90, twin):
    """λ = 0 is the data alone (the prior only breaks ties); larger weights take the model toward the
    description off the directions the data determine (its prior term falls to 0 at λ = inf) at a growing
    weighted residual."""
    rec, truth = twin
    prior = perturbed(truth, np.random.default_rng(3), 0.5)
    costs, terms = [], []
    for weight in (0.0, 1e2, 1e5, math.inf):
        model = fit(rx90, [rec], PROCESSING, physical_prior=prior, prior_weight=weight).identified
        assert model.prior_weight == weight
        terms.append(model.prior["prior_term"])
        costs.append(model.cost)
    assert costs == sorted(costs) and terms == sorted(terms, reverse=True), (costs, terms)
    assert terms[-1] < 1e-9 * terms[0]


def test_a_wrong_prior_is_flagged_and_the_right_one_is_not(rx90, twin):
    """bodies_far_from_prior (identify.fitting.plausibility.prior_flags) on the identified model: against
    the twin's own parameters no flag; against 5x heavier bodies with the weight chosen by the data, the
    links whose identified mass the data pull away from the prior's are named with both masses."""
    from identify.fitting.plausibility import PRIOR_MASS_RATIO, prior_flags

    rec, truth = twin
    heavy = {k: 5 * v if k.startswith(("M", "XX", "XY", "XZ", "YY", "YZ", "ZZ")) else v for k, v in truth.items()}
    for name, values in (("right", truth), ("heavy", heavy)):
        model = fit(rx90, [rec], PROCESSING, physical_prior=values).identified
        flags = prior_flags(model.standard, values, "rx90")
        ratios = {j: model.standard[f"M{j}"] / values[f"M{j}"] for j in range(1, 7)}
        outside = {f"M{j}" for j, r in ratios.items() if not 1 / PRIOR_MASS_RATIO <= r <= PRIOR_MASS_RATIO}
        assert {fl.parameter for fl in flags} == outside
        if name == "right":
            assert not flags
        else:
            assert flags and all("x its prior mass" in fl.message for fl in flags), ratios


@pytest.mark.parametrize("divergence", ["gaussian", "entropic"])
def test_the_divergence_is_zero_at_the_prior_and_its_hessian_its_curvature(rx90, twin, divergence):
    """D(θ0 | θ0) = 0, D > 0 elsewhere, and ½ Δᵀ H Δ is D's second-order term (central differences)."""
    _, truth = twin
    prior = body_prior(truth, 6, "truth", divergence)
    names = rx90.parameter_names
    theta0 = dict(truth)
    assert prior.value(theta0) == pytest.approx(0.0, abs=1e-12)
    H = prior.hessian(names)
    rng = np.random.default_rng(0)
    direction = np.array([rng.normal() * abs(truth[n]) * 0.01 if n in prior.values else 0.0 for n in names])
    for h in (1e-2, 1e-3):
        up = {n: truth[n] + h * d for n, d in zip(names, direction)}
        down = {n: truth[n] - h * d for n, d in zip(names, direction)}
        second = (prior.value(up) + prior.value(down)) / h ** 2   # 2 D(±hΔ)/h² -> Δᵀ H Δ
        assert second == pytest.approx(direction @ H @ direction, rel=1e-3 if h == 1e-3 else 3e-2)
    assert prior.value({n: truth[n] + direction[k] for k, n in enumerate(names)}) > 0


def test_the_held_out_check_refuses_only_a_model_worse_than_the_description():
    """identify.fitting.plausibility.heldout_flags on the cross-validation's per-block errors: a model worse
    than the yardstick over all joints in every block is refused; one worse on one joint only is a warning
    naming that joint with both figures to two decimals; a model no worse says nothing unless it explains
    under half of a joint's torque."""
    from identify.fitting.plausibility import heldout_flags

    reference = np.array([[10.0, 20.0, 30.0]] * 5) + np.arange(5)[:, None] * 0.3
    slightly = reference * 1.1  # clearly worse, yet within REFUSE_RATIO: a warning per joint, no refusal
    assert [(f.code, f.severity) for f in heldout_flags(slightly.mean(0), slightly, reference.mean(0), reference,
                                                        "x")] == [("model_worse_on_joint", "warning")] * 3
    worse = reference * 1.3
    (refusal,) = heldout_flags(worse.mean(0), worse, reference.mean(0), reference, "the model the user had")
    assert refusal.severity == "error" and refusal.code == "model_unexplained"
    assert "26.78 % against 20.60 %" in refusal.message and "the model the user had" in refusal.message
    one = reference.copy()
    one[:, 1] *= 1.05
    one[:, 0] *= 0.9
    one[:, 2] *= 0.95
    flags = heldout_flags(one.mean(0), one, reference.mean(0), reference, "the plain OLS")
    assert [(f.code, f.severity, f.joint) for f in flags] == [("model_worse_on_joint", "warning", 2)]
    assert "21.63 % against 20.60 %" in flags[0].message
    assert heldout_flags(reference.mean(0) * 0.9, reference * 0.9, reference.mean(0), reference, "x") == []
    poor = reference.copy()
    poor[:, 2] = 50.4  # above RESIDUAL_SHARE (50 %) of the torque, yet no worse than the yardstick's 50.6
    flags = heldout_flags(poor.mean(0), poor, np.r_[reference.mean(0)[:2], 50.6], np.c_[reference[:, :2], [50.6] * 5], "x")
    assert [(f.code, f.severity) for f in flags] == [("torque_poorly_explained", "warning")] and "50.40 %" in flags[0].message
    # Worse in every block's relative error, yet better on the pooled figures it would print (a block of large
    # torque weighs more pooled, as on the Gen3's joint 1): no warning whose figures say the opposite.
    mixed = reference.copy()
    mixed[:, 0] += 0.5
    assert heldout_flags(np.r_[9.0, reference.mean(0)[1:]], mixed, reference.mean(0), reference, "x") == []
    assert [f.joint for f in heldout_flags(np.r_[11.0, reference.mean(0)[1:]], mixed, reference.mean(0), reference,
                                           "x")] == [1]


def test_a_smaller_weight_is_chosen_only_when_it_beats_the_larger_clearly():
    """identify.selection.prior_weight: a smaller λ's held-back error must be below the larger one's beyond
    the blocks' spread, on every block but one at most, and by WEIGHT_MARGIN (20 %) of it."""
    from identify.selection.prior_weight import WEIGHT_MARGIN, _clearly_lower
    from identify.selection.candidates import Candidate

    rng = np.random.default_rng(0)
    larger = 10.0 + rng.uniform(0, 1, (5, 3))

    def candidate(per_block: np.ndarray) -> Candidate:
        return Candidate(math.nan, None, score=float(per_block.mean()), per_block=tuple(map(tuple, per_block)))

    ref = candidate(larger)
    assert WEIGHT_MARGIN == 0.2
    assert not _clearly_lower(candidate(larger * 0.85), ref)   # lower on every block, by 15 %
    assert _clearly_lower(candidate(larger * 0.7), ref)        # by 30 %
    mixed = larger * 0.5
    mixed[:2] = larger[:2] * 1.01                               # 30 % lower overall, higher on two blocks
    assert candidate(mixed).score < 0.75 * ref.score and not _clearly_lower(candidate(mixed), ref)
    mixed[1] = larger[1] * 0.5                                  # higher on one block only
    assert _clearly_lower(candidate(mixed), ref)
