"""What a fit block by block carries besides its estimates, against the whole-signal fit of the same log:
the identified model with the default prior (its weight chosen by cross-validation), the plain OLS baseline
(filtered in windows with margins, and its prediction) and the recorded-torque checks, for blocks smaller
than the log (several blocks) and a block holding the whole log (a CSV path: the block path in one block)."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import identify
import rx90sym
from identify.fitting.baseline_factors import fit_baseline, fit_baseline_windows
from identify.fitting.baseline_blocks import source_windows
from identify.fitting.plausibility import GravityAtRest
from identify.fitting.torque_checks import (CODES, _source_blocks, recorded_torque_flags,
                                           log_torque_flags)
from identify.io.blocks import MemorySource
from identify.observation.processing import Processing
from identify.observation.scan import scan
from motions import multisine

#: The processing given (the choices block by block are the cross-validation's and friction's own tests).
GIVEN = Processing(cross_validate=False, friction="coulomb")


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    """Largest difference relative to the largest magnitude of ``b``."""
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(np.asarray(b))))


@pytest.fixture(scope="module")
def log(twin_empty, rx90, tmp_path_factory):
    """The 20 s twin run (5,000 samples) with a slow torque disturbance the model does not hold (its residuals
    coloured: the segment bootstrap's σ 3.5 x eq. 13's), in memory and as a CSV file."""
    rec = twin_empty[0]
    slow = 0.05 * np.cumsum(np.random.default_rng(0).normal(size=rec.tau.shape), axis=0)  # N m, a random walk
    rec = dataclasses.replace(rec, tau=rec.tau + slow)
    path = tmp_path_factory.mktemp("parity") / "rec.csv"
    identify.write_recording(path, rec, rx90)
    return rec, str(path)


@pytest.fixture(scope="module")
def consistent(rx90, log):
    """The consistent fit with the default prior (the description, its weight chosen by cross-validation):
    whole, in three blocks, and the CSV file in one block (the block path, its bootstrap with another seed)."""
    rec, path = log
    n = rec.n_samples
    return {"whole": identify.fit(rx90, [rec], GIVEN, "consistent"),
            "blocks": identify.fit(rx90, [rec], GIVEN, "consistent", block=n // 3),
            "one block": identify.fit(rx90, [path], GIVEN, "consistent", block=n + 1, bootstrap_seed=3)}


def test_the_consistent_fit_takes_the_default_prior_block_by_block(consistent, log):
    """The robot's description as the prior, its weight chosen on the same folds: the weight, the cross-validation's
    scores and the standard parameters equal the whole fit's (measured ~1e-12 relative; the solver's tolerance
    allowed); the data alone (no prior) give other parameters."""
    whole = consistent["whole"]
    prior = whole.result.prior
    assert prior is not None and prior["choice"] is not None
    names = list(whole.result.standard)
    ref = np.array([whole.result.standard[k] for k in names])
    for key in ("blocks", "one block"):
        got = consistent[key]
        assert got.block is not None and got.result.prior["weight_label"] == prior["weight_label"], key
        scores = [v for v in got.result.prior["choice"]["scores_pct"] if v is not None]
        assert _rel(scores, [v for v in prior["choice"]["scores_pct"] if v is not None]) < 1e-7, key
        assert _rel([got.result.standard[k] for k in names], ref) < 1e-7, key
    assert _rel(consistent["blocks"].bootstrap.std, whole.bootstrap.std) < 1e-8
    assert consistent["one block"].bootstrap.seed == 3 and _rel(consistent["one block"].bootstrap.std,
                                                                 whole.bootstrap.std) > 1e-3
    other = identify.fit(whole.robot, [log[0]], GIVEN, "consistent", physical_prior="none")
    assert _rel([other.result.standard[k] for k in names], ref) > 1e-3


def test_the_baseline_block_by_block_is_the_whole_logs(rx90, log, consistent, twin_empty):
    """The fit file's plain baseline: parameters, samples, rank and residuals equal to 1e-9 (measured
    8.6e-13 on the parameters); its prediction of another run, scored beside the fit's, too."""
    whole = consistent["whole"].baseline
    for key in ("blocks", "one block"):
        got = consistent[key].baseline
        assert got is not None and (got.samples, got.rank, got.names) == (whole.samples, whole.rank, whole.names)
        assert _rel(got.values, whole.values) < 1e-9, key
        assert _rel(got.residual_rms, whole.residual_rms) < 1e-9, key
        assert got.to_json()["definition"] == whole.to_json()["definition"]
    other = twin_empty[1]
    a, b = consistent["blocks"].validate(other), consistent["whole"].validate(other)
    assert a.baseline_rms_error is not None and a.baseline_predicted is not None
    common, ia, ib = np.intersect1d(a.t, b.t, return_indices=True)
    assert common.size > 0.95 * b.t.size
    assert _rel(a.baseline_predicted[ia], b.baseline_predicted[ib]) < 1e-9
    assert _rel(a.baseline_rms_error, b.baseline_rms_error) < 1e-8  # measured 5.9e-12: the same samples scored
    # The filtered figures (the fit's rows at its own rate, a pass of their own block by block) are the whole log's.
    for name in ("rms_error_filtered", "rms_error_filtered_moving"):
        assert getattr(a, name) is not None and _rel(getattr(a, name), getattr(b, name)) < 1e-8, name
    # identify.predict at the fit's own rate in blocks of 1000 and in one block: those figures from its one pass,
    # the baseline beside them.
    f = consistent["whole"]
    base = f.columns_of(f.result)  # the identified model's columns: the fit's, with the offsets it adds
    streamed = identify.predict(rx90, f.result, other, base=base, block=1000, baseline=f.baseline, **f.filtering())
    memory = identify.predict(rx90, f.result, other, base=base, baseline=f.baseline, block=10 ** 7, **f.filtering())
    for name in ("rms_error", "rms_error_filtered", "rms_error_filtered_moving", "baseline_rms_error"):
        assert _rel(getattr(streamed, name), getattr(memory, name)) < 1e-8, name


def test_the_baseline_in_windows_equals_the_whole_segments_with_gaps_and_lost_samples(rx90, twin_empty):
    """Three segments with bridged samples: the baseline filtered in windows of 400..N samples (in memory
    and read from a block source) is the one of whole segments, to 1e-9; without the margins it is not."""
    rec = twin_empty[1]
    n = rec.n_samples
    segment = np.repeat([0, 1, 2], [n // 2, n // 4, n - n // 2 - n // 4])
    measured = np.ones(n, bool)
    measured[::97] = False
    rec = dataclasses.replace(rec, segment=segment, measured=measured)
    ref = fit_baseline(rx90, [rec])
    src = MemorySource(rec, rx90)
    sc = scan(src, 1000, None)
    for block in (400, 1000, n):
        for got in (fit_baseline(rx90, [rec], block=block),
                    fit_baseline_windows(rx90, source_windows([src], [sc], block))):
            assert got.samples == ref.samples and got.rank == ref.rank
            assert _rel(got.values, ref.values) < 1e-9, block
    pred, ref_pred = ref.predict(rx90, rec, block=400), ref.predict(rx90, rec)
    np.testing.assert_array_equal(pred.scored, ref_pred.scored)
    assert _rel(pred.predicted[pred.scored], ref_pred.predicted[ref_pred.scored]) < 1e-9
    # Windows without the filter's margin (2 samples for the gradients only) move the estimates far more.
    import identify.fitting.baseline as baseline_module

    narrow = baseline_module.BaselineSegment.windows
    try:
        baseline_module.BaselineSegment.windows = lambda self, block=None: baseline_module.motion_windows(
            self.samples, 0, 1, self.samples if block is None else block, 0, 0)
        bad = fit_baseline(rx90, [rec], block=400)
    finally:
        baseline_module.BaselineSegment.windows = narrow
    assert _rel(bad.values, ref.values) > 1e-6


def _still_then_moving(robot: rx90sym.Robot) -> identify.Recording:
    """12 s of the twin at 250 Hz: 2 s held at a pose where gravity loads joints 2 and 3, then a motion."""
    t = np.arange(3000) / 250.0
    traj = multisine(robot, 3, duration=10.0)
    pose = np.array([0.3, 0.3, 2.0, 0.2, 0.8, 0.1]) - traj(0.0)[0][0]
    q, dq, ddq = traj(np.maximum(t - 2.0, 0.0))
    held = t < 2.0
    dq[held], ddq[held] = 0.0, 0.0
    return rx90sym.twin.simulate(robot, (t, q + pose, dq, ddq), noise="quantised", seed=0)


def test_the_recorded_torque_checks_block_by_block(rx90):
    """The sums behind static_gravity (samples at rest by numpy.gradient of q across block edges) and the
    torque peaks behind torque_scale are the whole log's; identify.fit flags a torque of the wrong sign and one
    of the wrong scale alike on both paths."""
    rec = _still_then_moving(rx90)
    nominal = rx90sym.nominal_parameters(rx90)
    whole = GravityAtRest(rx90, nominal)
    whole.add(rec.q, rec.tau, np.gradient(rec.q, rec.t, axis=0))
    assert 480 < whole.count < 700  # the 2 s held, and the few samples where every joint turns at once
    src = MemorySource(rec, rx90)
    sc = scan(src, 1000, None)
    for block in (97, 333, 1000):
        part = GravityAtRest(rx90, nominal)
        for q, tau, dq in _source_blocks([src], [sc], block):
            part.add(q, tau, dq)
        assert part.count == whole.count
        np.testing.assert_allclose(part.tau_g, whole.tau_g, rtol=1e-12)
        np.testing.assert_allclose(part.g_g, whole.g_g, rtol=1e-12)
    tau = rec.tau.copy()
    tau[:, 1] *= -1
    flipped = dataclasses.replace(rec, tau=tau)
    scaled = dataclasses.replace(rec, tau=rec.tau * 100)
    for bad, code in ((flipped, "static_gravity"), (scaled, "torque_scale")):  # x 100: gravity's scale too
        ref = [(f.code, f.joint, f.message) for f in recorded_torque_flags(rx90, [bad])]
        assert code in [c for c, _, _ in ref]
        got = log_torque_flags(rx90, [MemorySource(bad, rx90)], [sc], 333)
        assert [(f.code, f.joint, f.message) for f in got] == ref
        for block in (None, 1000):
            fit = identify.fit(rx90, [bad], GIVEN, block=block)
            assert [(f.code, f.joint, f.message) for f in fit.flags if f.code in CODES] == ref, block
    assert recorded_torque_flags(rx90, [rec]) == [] and log_torque_flags(rx90, [src], [sc], 333) == []


def test_rx90_identify_checks_the_recorded_torques_of_a_long_log(rx90, tmp_path, capsys):
    """A log longer than --block with torques in the wrong unit: the check block by block stops the run
    (exit 2, nothing written), as for a log read whole."""
    from identify.app.cli import main

    rec = _still_then_moving(rx90)
    path, out = tmp_path / "bad.csv", tmp_path / "fit.json"
    identify.write_recording(path, dataclasses.replace(rec, tau=rec.tau * 100), rx90)
    for block in ("1000", "100000"):  # block by block, and read whole
        code = main(["identify", str(path), "--block", block, "--no-cross-validate", "--json", str(out)])
        err = capsys.readouterr().err
        assert code == 2 and "far above robot rx90's torque limits" in err and not out.exists(), block
        assert "not checked" not in err


def test_rx90_predict_on_a_long_log_is_the_fits_prediction(rx90, consistent, twin_empty, tmp_path):
    """rx90 predict on a log longer than --block (read block by block) gives Fit.predict's figures on the log
    held whole, the plain baseline's among them."""
    import json

    from identify.app.cli import main

    f = consistent["whole"]
    other = twin_empty[1]
    fit_file, path, out = tmp_path / "fit.json", tmp_path / "other.csv", tmp_path / "pred.json"
    f.save(fit_file)
    identify.write_recording(path, other, rx90)
    assert main(["predict", str(path), "--identification", str(fit_file), "--block", "1000", "--json", str(out)]) == 0
    got, ref = json.loads(out.read_text()), f.predict(other)
    for name in ("rms_error", "rms_error_filtered", "rms_error_filtered_moving", "baseline_rms_error"):
        assert _rel(np.array(got[name]), getattr(ref, name)) < 1e-8, name


def test_the_consistent_fit_of_presliding_rest_is_the_same_on_both_paths(rx90, log):
    """The identified model holds the presliding magnitudes FPj beside the standard parameters (applied from
    the fit by a simulator): read from the file as held in memory."""
    rec, path = log
    fits = [identify.fit(rx90, recordings, Processing(cross_validate=False, rest="presliding"), "consistent",
                         block=block) for recordings, block in (([rec], None), ([path], rec.n_samples + 1))]
    assert any(k.startswith("FP") for k in fits[0].result.extras)
    assert _rel(fits[1].result.values, fits[0].result.values) < 1e-7
