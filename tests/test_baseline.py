"""The plain OLS baseline (identify.fitting.baseline) against an independent implementation with
Pinocchio's regressor, on data of known truth, and in the validation (raw torques, same samples)."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import rx90sym
from conftest import plain_signals_by_hand, random_body
from identify import Processing, fit, load_fit, split
from identify.fitting.baseline_factors import fit_baseline
from motions import multisine
from rx90sym.pinocchio_bridge import pinocchio_model
from rx90sym.recording import Recording


def _independent(robot, fit_rec, test_rec):
    """The issue notes' definition written out with Pinocchio's regressor: (prediction of the test
    recording's samples 0.5 s from its ends, those samples)."""
    model = pinocchio_model(robot)
    data = model.createData()

    def rows(rec):
        q, dq, ddq, keep = plain_signals_by_hand(rec)
        n = robot.n
        W = []
        for i in keep:
            Y = pin.computeJointTorqueRegressor(model, data, q[i], dq[i], ddq[i])
            F = np.zeros((n, 3 * n))
            for j in range(n):
                F[j, 3 * j:3 * j + 3] = dq[i, j], np.sign(dq[i, j]), 1.0
            W.append(np.hstack([Y, F]))
        return np.vstack(W), keep

    W, keep = rows(fit_rec)
    beta, *_ = np.linalg.lstsq(W, np.asarray(fit_rec.tau)[keep].reshape(-1), rcond=1e-10)
    Wt, kt = rows(test_rec)
    return (Wt @ beta).reshape(kt.size, robot.n), kt


def test_the_baseline_equals_an_independent_one_with_pinocchios_regressor(tx40):
    rec = rx90sym.twin.simulate(tx40, multisine(tx40, 5, duration=6.0), duration=6.0, noise="quantised", seed=5,
                                rate=200.0)
    fit_part, test = split(rec, 0.6)
    ours = fit_baseline(tx40, [fit_part]).predict(tx40, test)
    ref, kept = _independent(tx40, fit_part, test)
    np.testing.assert_array_equal(np.flatnonzero(ours.scored), kept)
    scale = max(1.0, np.abs(ref).max())
    assert np.max(np.abs(ours.predicted[ours.scored] - ref)) < 1e-9 * scale


def test_the_baseline_recovers_a_known_model(tx40):
    """Torques made by the baseline's own model (rigid bodies through Pinocchio's RNEA, viscous,
    Coulomb and an offset per joint) from the exact motion, no noise: the friction and offsets are
    found and the held-out torques predicted within the error of a 10 Hz filter's derivatives."""
    rng = np.random.default_rng(7)
    n = tx40.n
    chi = np.zeros(len(tx40.parameter_names))
    for j in range(n):
        chi[13 * j:13 * j + 10] = random_body(rng)
    model, motion = pinocchio_model(tx40, chi), multisine(tx40, 7, duration=12.0)
    data = model.createData()
    t = np.arange(0, 12.0, 1 / 250.0)
    q, dq, ddq = motion(t)
    fv, fs, off = rng.uniform(0.5, 3, n), rng.uniform(0.5, 3, n), rng.uniform(-2, 2, n)
    tau = np.array([pin.rnea(model, data, *s) for s in zip(q, dq, ddq)]) + fv * dq + fs * np.sign(dq) + off
    rec = Recording(t=t, q=q, tau=tau, robot=tx40.name)
    fit_part, test = split(rec, 2 / 3)
    b = fit_baseline(tx40, [fit_part])
    values = dict(zip(b.names, b.values))
    for j in range(n):  # measured (seed 7): within 0.6 % (FV), 0.4 % (FS) and 0.02 N m (OFF)
        assert values[f"FV{j + 1}"] == pytest.approx(fv[j], rel=0.03)
        assert values[f"FS{j + 1}"] == pytest.approx(fs[j], rel=0.03)
        assert values[f"OFF{j + 1}"] == pytest.approx(off[j], abs=0.1)
    p = b.predict(tx40, test)
    err = np.sqrt(np.mean((p.predicted - p.measured)[p.scored] ** 2, axis=0))
    assert np.all(err < 0.01 * np.sqrt(np.mean(tau ** 2, axis=0))), err  # measured: < 0.2 %


def test_the_validation_scores_raw_torques_beside_the_baseline_on_the_same_samples(tx40, tmp_path):
    rec = rx90sym.twin.simulate(tx40, multisine(tx40, 3, duration=8.0), duration=8.0, noise="quantised", seed=3,
                                rate=200.0)
    fit_part, test = split(rec, 0.6)
    fits = [fit(tx40, [fit_part], Processing(cutoff=fc, decimate_to=dec, estimate_delay=False))
            for fc, dec in ((6.5, 20.0), (12.0, None))]
    vals = [f.validate(test) for f in fits]
    # the same raw samples (cut-offs from 6 Hz on predict 0.5 s from the ends): the recording's own time
    # stamps, its torques unfiltered
    np.testing.assert_array_equal(vals[0].t, vals[1].t)
    idx = np.searchsorted(test.t, vals[0].t)
    np.testing.assert_array_equal(test.t[idx], vals[0].t)
    np.testing.assert_array_equal(vals[0].measured, np.asarray(test.tau)[idx])
    # the baseline figure, from the independent implementation on the same samples
    ref, kept = _independent(tx40, fit_part, test)
    inside = np.isin(kept, idx)
    ref_rms = np.sqrt(np.mean((np.asarray(test.tau)[kept][inside] - ref[inside]) ** 2, axis=0))
    np.testing.assert_allclose(vals[0].baseline_rms_error, ref_rms, rtol=1e-8)
    d = vals[0].to_dict()
    assert d["beats_baseline"] == [bool(a <= b) for a, b in zip(d["rms_error"], d["baseline_rms_error"])]
    assert "beats both yardsticks" in vals[0].table()
    # the ratio line: each joint's RMS over the smaller of the two yardsticks' on the same samples
    line = next(x for x in vals[0].table().splitlines() if x.startswith("RMS / the better yardstick's"))
    v = vals[0]
    for moving, k in ((False, 0), (True, 1)):
        own = v.rms_error_moving if moving else v.rms_error
        better = np.minimum(*(v.yardsticks(moving)[name] for name in v.yardsticks(moving)))
        printed = [float(cell.split()[1].split("/")[k]) for cell in line.split(": ", 1)[1].split("  ")]
        np.testing.assert_allclose(printed, own / better, atol=0.005)
    # the fit file keeps the baseline: predict shows it again; an older file (without it) reads None
    fits[0].save(tmp_path / "fit.json")
    back = load_fit(tmp_path / "fit.json", tx40)
    np.testing.assert_allclose(back.validate(test).baseline_rms_error, vals[0].baseline_rms_error, rtol=1e-12)
    import json
    data = json.loads((tmp_path / "fit.json").read_text())
    del data["baseline"]
    (tmp_path / "old.json").write_text(json.dumps(data))
    old = load_fit(tmp_path / "old.json", tx40)
    assert old.baseline is None and old.validate(test).baseline_rms_error is None
