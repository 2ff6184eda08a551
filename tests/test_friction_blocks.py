"""Friction forms on the block path (issue 32, item 3): a smooth form's velocity scales and the friction
form chosen per joint do not depend on the block size. A log of N samples fitted in blocks smaller than
N (several blocks) and in one block (the whole-signal fit) gives the same scales and estimates to 1e-8
relative, and the scales are the twin's (an independent truth: the torques were simulated with them)."""
from __future__ import annotations

import numpy as np
import pytest

import identify
from identify.friction.choice import choose_friction

from test_friction_choice import fold_rows, mixed_twin
from test_friction_forms import TRUE_SCALE, friction_twin


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    """Largest relative difference, parameters near zero measured against 1e-6 of the largest."""
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-6 * np.max(np.abs(b)))))


@pytest.mark.parametrize("form", ["tanh", "stribeck"])
def test_a_smooth_form_fitted_in_blocks_equals_the_whole_signal_fit(rx90, rx90_base, form):
    """Measured (RX90 twin, 20 s at 100 Hz): 1.7e-11 (tanh) and 9.7e-11 (Stribeck) relative for
    blocks of 1000 and N - 1, the same scales; scales within 15 % of the truth."""
    rec = friction_twin(rx90, form, 0, 20.0, 100.0)
    n = rec.n_samples
    processing = identify.Processing(friction=form, min_velocity=None, estimate_delay=False, cutoff=10.0,
                                     decimate_to=None)
    whole = identify.fit(rx90, [rec], processing, base=rx90_base, block=n)
    assert whole.passes.blocks == 1   # a log within one block is one block
    scales = np.array(whole.model.friction["velocity_scale"])
    np.testing.assert_allclose(scales, TRUE_SCALE, rtol=0.15)
    for block in (1000, n - 1):
        got = identify.fit(rx90, [rec], processing, base=rx90_base, block=block)
        assert got.block == block and got.passes is not None and (block > 1000 or got.passes.blocks >= 2)
        assert got.model.friction["velocity_scale"] == whole.model.friction["velocity_scale"]
        assert got.result.names == whole.result.names
        assert _relative(got.result.values, whole.result.values) < 1e-8


def test_the_friction_form_chosen_block_by_block_is_the_one_block_choice(rx90, rx90_base):
    """A twin with tanh on joints 1, 3, 6 (10 s at 100 Hz): read in 3 blocks and in 4 (the last one short),
    the same forms per joint and held-back scores equal to those of the log read as one block to 1e-8
    (measured 1e-12)."""
    rec = mixed_twin(rx90, ("tanh", "coulomb", "tanh", "coulomb", "coulomb", "tanh"), 1)
    rows = rx90.n * rec.n_samples
    whole = choose_friction(rx90, fold_rows(rx90, [rec], block=2 * rec.n_samples), rx90_base, rows)
    assert whole.chosen[0] == whole.chosen[2] == "tanh", whole.table()   # the truth, where it is clear
    assert sum(len(p.windows) for p in fold_rows(rx90, [rec], block=2 * rec.n_samples).plans[0]) == 1
    for block in (400, 300):
        split = fold_rows(rx90, [rec], block=block)
        assert sum(len(p.windows) for p in split.plans[0]) >= 3
        got = choose_friction(rx90, split, rx90_base, rows)
        assert got.chosen == whole.chosen, got.table()
        for a, b in zip(got.candidates + (got.combined,), whole.candidates + (whole.combined,)):
            assert a.label == b.label
            np.testing.assert_allclose(a.per_block, b.per_block, rtol=1e-8)


@pytest.mark.slow
def test_a_cross_validated_fit_chooses_the_same_form_whatever_the_block(rx90):
    """identify.fit with the defaults (processing and friction form chosen block by block) on a 30 s
    tanh twin in blocks of 1000 and 2999: the same choice, every form's held-back scores to 1e-8 (the
    processing the raw-torque scoring chooses, 10 Hz at 25 Hz, keeps coulomb: tanh's 3.14 % against
    3.07 %), the estimates to 1e-8 (measured 6e-10)."""
    rec = friction_twin(rx90, "tanh", 0, 30.0, 100.0)
    fits = [identify.fit(rx90, [rec], identify.Processing(), block=b) for b in (1000, rec.n_samples - 1)]
    a, b = (f.choice["friction"] for f in fits)
    assert a["chosen"] == b["chosen"] and [c["form"] for c in a["candidates"]] == [c["form"] for c in b["candidates"]]
    assert len(a["candidates"]) >= 2   # coulomb and a smooth form scored
    for ca, cb in zip(a["candidates"], b["candidates"]):
        np.testing.assert_allclose(ca["per_joint_pct"], cb["per_joint_pct"], rtol=1e-8)
    assert fits[0].model.friction == fits[1].model.friction
    assert _relative(fits[0].result.values, fits[1].result.values) < 1e-8


def test_presliding_travels_and_a_smooth_form_in_blocks_equal_the_whole_signal_fit(rx90, rx90_base):
    """Rest policy "presliding" with the tanh form on a stop-and-go twin with Dahl friction (15 s at
    200 Hz): the travels and scales found block by block (blocks of 1000) are the whole-signal fit's,
    the estimates within 1e-8 (measured 5e-11); the travels are those a 5 mrad Dahl state prefers
    (5 or 10 mrad, the candidates around it)."""
    import rx90sym
    from rx90sym.recording import Recording

    from test_presliding import presliding_torques, stop_and_go

    chi = rx90.parameter_vector(rx90sym.twin.default_parameters(rx90))
    t, q, qd, qdd = stop_and_go(rx90, 0, duration=15.0)
    rec = Recording(t=t, q=q, tau=presliding_torques(rx90, chi, q, qd, qdd, 0), dq=qd, robot=rx90.name)
    processing = identify.Processing(rest="presliding", friction="tanh", estimate_delay=False, cutoff=10.0)
    whole = identify.fit(rx90, [rec], processing, base=rx90_base, block=rec.n_samples)
    got = identify.fit(rx90, [rec], processing, base=rx90_base, block=1000)
    assert whole.passes.blocks == 1 and got.passes.blocks >= 2
    for key in ("presliding_travel", "velocity_scale"):
        assert got.model.friction[key] == whole.model.friction[key], key
    assert set(whole.model.friction["presliding_travel"]) <= {0.005, 0.01}
    assert got.result.names == whole.result.names
    assert _relative(got.result.values, whole.result.values) < 1e-8
