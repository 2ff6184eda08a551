"""The friction form chosen by the blocked cross-validation (issue 21, item 4): a twin whose true
friction is FSj·tanh(q̇/vs) gets tanh, a twin whose friction is Coulomb + viscous keeps coulomb, and
the fit records the choice in its processing_choice."""
from __future__ import annotations

import numpy as np
import pytest

import rx90sym
from identify import Processing, fit
from identify.observation.friction_choice import choose_friction
from rx90sym.recording import Recording
from test_friction_forms import friction_twin

from motions import multisine

OPTIONS = dict(cutoff=10.0, decimate_to=None, min_velocity=0.02, rest="zero-coulomb", spring=True, delay=0.0)


def coulomb_twin(robot: rx90sym.Robot, seed: int, duration: float = 10.0, rate: float = 100.0) -> Recording:
    """friction_twin's multisine run with the model's own friction FSj·sign(q̇) + FVj·q̇, 1 % noise."""
    chi = robot.parameter_vector(rx90sym.twin.default_parameters(robot))
    t = np.arange(0, duration, 1 / rate)
    q, qd, qdd = multisine(robot, seed, duration=duration)(t)
    tau = robot.regressor_batch(q, qd, qdd) @ chi - robot.spring_torque_batch(q)[:, :, 0]
    tau += 0.01 * np.sqrt(np.mean(tau**2, axis=0)) * np.random.default_rng(100 + seed).normal(size=tau.shape)
    return Recording(t=t, q=q, tau=tau, dq=qd, robot=robot.name)


# Measured, seeds 0-2 (10 s at 100 Hz, zero-coulomb at 0.02 rad/s): tanh twin 1.31-1.35 % against
# coulomb's 2.39-2.60 %; Coulomb twin (seeds 0-4) coulomb 4.17-5.46 % against tanh 4.21-5.54 %.
@pytest.mark.parametrize("seed", range(3))
def test_a_tanh_twin_chooses_tanh_and_a_coulomb_twin_keeps_coulomb(rx90, rx90_base, seed):
    tanh = choose_friction(rx90, [friction_twin(rx90, "tanh", seed, 10.0, 100.0)], rx90_base, OPTIONS)
    assert tanh.chosen == "tanh", tanh.table()
    coulomb = choose_friction(rx90, [coulomb_twin(rx90, seed)], rx90_base, OPTIONS)
    assert coulomb.chosen == "coulomb", coulomb.table()


def test_the_fit_records_the_friction_choice_and_a_given_form_is_not_chosen(rx90, rx90_base):
    rec = friction_twin(rx90, "tanh", 0, 10.0, 100.0)
    f = fit(rx90, [rec], Processing(estimate_delay=False, min_velocity=0.02, decimate_to=None), base=rx90_base)
    record = f.choice["friction"]
    assert record["chosen"] == "tanh" and f.model.friction["form"] == "tanh", f.choice["table"]
    assert "friction form chosen" in f.choice["table"]
    given = fit(rx90, [rec], Processing(estimate_delay=False, friction="coulomb"), base=rx90_base)
    assert "friction" not in given.choice and given.model.friction is None
    with pytest.raises(ValueError, match="forms must include 'coulomb'"):
        choose_friction(rx90, [rec], rx90_base, OPTIONS, forms=("tanh",))
