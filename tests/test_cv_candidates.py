"""The cross-validated choice's newer candidates (torque offsets per joint, no decimation), scored
against the raw measured torques, on a twin whose torques carry known offsets."""
from __future__ import annotations

import numpy as np
import pytest

import rx90sym
from identify import Processing, fit, load_fit, split
from identify.selection.processing_choice import choose_processing
from identify.selection.cross_validation import NO_DECIMATION
from identify.observation.offsets import offset_joints
from motions import multisine

#: True torque offsets [N m] of the twin: large on joints 1, 3, 5, none on 2, 4, 6.
OFFSETS = np.array([1.5, 0.0, 1.0, 0.0, 0.8, 0.0])


@pytest.fixture(scope="module")
def offset_twin(tx40):
    """(recording with torque offsets, fit part, held-out part): 12 s of the TX40 twin at 250 Hz."""
    truth = tx40.with_options(offsets=True)
    params = rx90sym.twin.default_parameters(truth)
    params.update({f"OFF{j + 1}": float(v) for j, v in enumerate(OFFSETS)})
    rec = rx90sym.twin.simulate(truth, multisine(truth, 11, duration=12.0), params=params, duration=12.0,
                                noise="quantised", seed=11)
    rec = rx90sym.recording.Recording(t=rec.t, q=rec.q, tau=rec.tau, robot=tx40.name)
    return (rec, *split(rec, 2 / 3))


def test_the_choice_gives_offsets_to_the_joints_that_have_them(tx40, offset_twin):
    _, fit_part, held = offset_twin
    base = rx90sym.base_parameters(tx40)
    choice = choose_processing(tx40, [fit_part], base=base, offsets=offset_joints(tx40, base))
    chosen = {j + 1 for j in choice.offsets}
    assert {1, 3, 5} <= chosen, choice.reason()
    assert "torque offsets on joints" in choice.reason() and "with offsets" in choice.table()
    assert any(c.label.startswith(NO_DECIMATION) for c in choice.candidates), choice.table()
    assert choice.to_dict()["scored_against"] == "raw measured torques"
    # The fit takes them (its own file says where), and predicts the held-out part better than without.
    f = fit(tx40, [fit_part], Processing(estimate_delay=False))
    assert set(f.model.offset_joints) >= {1, 3, 5}
    plain = fit(tx40, [fit_part], Processing(estimate_delay=False, cutoff=f.cutoff, decimate_to=f.decimate_to,
                                             rest=f.rest))
    # The least-squares estimates' predictions (the identified model adds an offset on every joint either way).
    with_off, without = f.predict(held, f.result), plain.predict(held, plain.result)
    for j in (0, 2, 4):  # measured (seed 11): 0.19 / 0.16 / 0.12 N m against 1.5 / 1.0 / 0.8
        assert with_off.rms_error[j] < 0.5 * without.rms_error[j]


def test_offsets_round_trip_and_never_beside_asymmetric_coulomb(tx40, offset_twin, tmp_path):
    _, fit_part, held = offset_twin
    f = fit(tx40, [fit_part], Processing(estimate_delay=False))
    f.save(tmp_path / "fit.json")
    back = load_fit(tmp_path / "fit.json", tx40)
    assert back.model.offset_joints == f.model.offset_joints
    np.testing.assert_allclose(back.predict(held).predicted, f.predict(held).predicted, rtol=0, atol=1e-9)
    asym = tx40.with_options(asymmetric_coulomb=(0, 2))
    eligible = offset_joints(asym, rx90sym.base_parameters(asym))
    assert 0 not in eligible and 2 not in eligible and 1 in eligible
    assert offset_joints(tx40.with_options(offsets=True), rx90sym.base_parameters(tx40)) == ()


def test_a_fit_in_blocks_takes_the_offsets_the_whole_fit_takes(tx40, offset_twin):
    """The fit part (2000 samples) read in blocks of 1000: the block-by-block choice keeps the offsets
    the choice in one block keeps, the fit carries their columns and records them, and its estimates
    are the one-block fit's.
    Measured: the same offsets, estimates within 1.4e-10 relative."""
    _, fit_part, held = offset_twin
    p = Processing(estimate_delay=False, friction="coulomb")
    whole = fit(tx40, [fit_part], p)
    blocks = fit(tx40, [fit_part], p, block=1000)
    assert blocks.passes.blocks >= 2 and whole.passes.blocks == 1  # one pipeline, two block sizes
    assert set(whole.model.offset_joints) >= {1, 3, 5} and blocks.model.offset_joints == whole.model.offset_joints
    assert blocks.result.names == whole.result.names and any(n.startswith("OFF") for n in blocks.result.names)
    np.testing.assert_allclose(blocks.result.values, whole.result.values, rtol=1e-8,
                               atol=1e-8 * np.max(np.abs(whole.result.values)))
    np.testing.assert_allclose(blocks.predict(held).predicted, whole.predict(held).predicted, rtol=0, atol=1e-7)
