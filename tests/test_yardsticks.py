"""The two yardsticks of every validation (identify.fitting.yardsticks): the model the user had against an
independent computation with Pinocchio's RNEA on the URDF itself, its sense on a twin whose description is
exact, both in the validation, the JSON and the fit file (schema 5; schema 4 still read), and their held-out
errors per time block against a direct per-fold computation."""
from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np
import pinocchio as pin
import pytest

import identify
import rx90sym
from identify.app.report.tables import validation_table
from conftest import plain_signals_by_hand, robot_file_without
from identify import Processing, fit, load_fit, split
from identify.selection.raw_torque_scores import RawSpan
from identify.fitting.baseline import baseline_regressor, memory_windows, window_signals
from identify.fitting.yardsticks import fit_yardsticks, yardstick_folds
from identify.io.blocks import MemorySource
from identify.selection.folds import block_scores, time_folds
from identify.observation.scan import scan
from motions import multisine
from twin_logs import URDF_DIR, UR5_DRIVES, chirp, point_to_point

UR5 = URDF_DIR / "ur5.urdf"


@pytest.fixture(scope="module")
def ur5():
    """The UR5 of its URDF (exact angles), its URDF inertials and friction as the twin's truth, no rotor
    inertia: the description holds every rigid body exactly."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the URDF's missing acceleration limits
        robot = rx90sym.load_robot(str(UR5), tip="tool0")
    truth = dict(rx90sym.twin.default_parameters(robot))
    for key in ("FV", "FS"):
        truth.update({f"{key}{j + 1}": v for j, v in enumerate(UR5_DRIVES[key])})
    return robot, truth


def _simulate(robot, truth, motion, duration, seed):
    return rx90sym.twin.simulate(robot, motion, params=truth, noise="quantised", seed=seed, rate=100.0,
                                 duration=duration)


def _direct_user_model(fit_rec, test_rec):
    """The issue notes' definition written out with Pinocchio's rnea on a model read from the URDF itself:
    (prediction of the test recording's samples 0.5 s from its ends, those samples, friction per joint)."""
    model = pin.buildModelFromUrdf(str(UR5))
    data = model.createData()
    assert model.nq == 6

    def rows(rec):
        q, dq, ddq, keep = plain_signals_by_hand(rec)
        rnea = np.array([pin.rnea(model, data, q[i], dq[i], ddq[i]) for i in keep])
        return dq[keep], rnea, keep

    dq, rnea, keep = rows(fit_rec)
    dq_t, rnea_t, keep_t = rows(test_rec)
    friction, pred = [], np.zeros_like(rnea_t)
    for j in range(6):
        A = np.column_stack([dq[:, j], np.sign(dq[:, j]), np.ones(len(keep))])
        x, *_ = np.linalg.lstsq(A, np.asarray(fit_rec.tau)[keep, j] - rnea[:, j], rcond=1e-10)
        friction.append(x)
        pred[:, j] = rnea_t[:, j] + np.column_stack([dq_t[:, j], np.sign(dq_t[:, j]), np.ones(len(keep_t))]) @ x
    return pred, keep_t, np.array(friction)


def test_the_user_model_equals_pinocchios_rnea_on_the_urdf(ur5):
    robot, truth = ur5
    fit_rec = _simulate(robot, truth, point_to_point(robot, 1, 6.0), 6.0, 0)
    test_rec = _simulate(robot, truth, chirp(robot, 1, 6.0), 6.0, 1)
    user = fit_yardsticks(robot, [fit_rec], block=250).user  # filtered in windows: the same to ~1e-12
    ref, kept, friction = _direct_user_model(fit_rec, test_rec)
    p = user.predict(robot, test_rec)
    np.testing.assert_array_equal(np.flatnonzero(p.scored), kept)
    assert np.max(np.abs(p.predicted[p.scored] - ref)) < 1e-9 * max(1.0, np.abs(ref).max())
    values = dict(zip(user.names, user.values))
    ours = np.array([[values[f"{k}{j + 1}"] for k in ("FV", "FS", "OFF")] for j in range(6)])
    assert np.max(np.abs(ours - friction)) < 1e-9 * max(1.0, np.abs(friction).max())
    assert user.rank == 18 and "ur5.urdf" in user.source


def test_an_exact_description_beats_the_plain_ols_on_a_short_log(ur5):
    """5 s of point-to-point moves fitted, a 10 s chirp predicted: with the bodies known, 18 friction and
    offset terms generalise where the plain OLS's 78 overfit the few moves. Measured (seeds 0-7): the user
    model's RMS 0.003-0.70x the plain OLS's on every joint, median 0.05x."""
    robot, truth = ur5
    ratios = []
    for seed in range(5):
        fit_rec = _simulate(robot, truth, point_to_point(robot, seed, 5.0), 5.0, 2 * seed)
        test_rec = _simulate(robot, truth, chirp(robot, seed, 10.0), 10.0, 2 * seed + 1)
        sticks = fit_yardsticks(robot, [fit_rec])
        rms = []
        for m in (sticks.plain, sticks.user):
            p = m.predict(robot, test_rec)
            rms.append(np.sqrt(np.mean((p.predicted - p.measured)[p.scored] ** 2, axis=0)))
        ratios.append(rms[1] / rms[0])
    assert np.all(np.array(ratios) < 0.85), np.round(ratios, 3)
    assert np.median(ratios) < 0.3, np.round(ratios, 3)


@pytest.fixture(scope="module")
def tx40_fit(tx40):
    rec = rx90sym.twin.simulate(tx40, multisine(tx40, 3, duration=8.0), duration=8.0, noise="quantised", seed=3,
                                rate=200.0)
    fit_part, test = split(rec, 0.6)
    return fit(tx40, [fit_part], Processing(cutoff=12.0, estimate_delay=False)), fit_part, test


def test_both_yardsticks_in_the_validation_the_json_and_the_fit_file(tx40, tx40_fit, tmp_path):
    f, fit_part, test = tx40_fit
    v = f.validate(test)
    # The user model's figure: its own prediction scored on the validation's samples.
    p = fit_yardsticks(tx40, [fit_part]).user.predict(tx40, test)
    at = np.searchsorted(p.t, v.t)
    assert np.all(p.scored[at])
    rms = np.sqrt(np.mean((p.measured[at] - p.predicted[at]) ** 2, axis=0))
    np.testing.assert_allclose(v.user_rms_error, rms, rtol=1e-9)
    ratio, better = v.yardstick_ratio()
    best = np.minimum(v.baseline_rms_error, v.user_rms_error)
    np.testing.assert_allclose(ratio, v.rms_error / best, rtol=1e-12)
    d = v.to_dict()
    assert d["beats_both"] == [bool(r <= 1) for r in ratio] and d["better_yardstick"] == better
    assert d["user_model_rms_error_moving"] is not None and d["yardstick_ratio_moving"] is not None
    lines = v.table().splitlines()
    assert "user model rms [N m]" in lines[1] and any(line.startswith("beats both yardsticks") for line in lines)
    # The report's validation table, from the JSON: both yardsticks' columns, the ratio, the verdicts.
    table = validation_table(d)
    heads = [c.header() for c in table.columns]
    assert "user model RMS all [N·m]" in heads and "plain OLS RMS moving [N·m]" in heads and "beats both" in heads
    assert [row[heads.index("beats both")].value for row in table.rows] == ["yes" if b else "no" for b in d["beats_both"]]
    assert "Beats both on all samples on joints" in table.note and "Beats both while moving on joints" in table.note
    # The fit file keeps both (schema 5): read back, the same figures.
    f.save(tmp_path / "fit.json")
    data = json.loads((tmp_path / "fit.json").read_text())
    assert data["schema_version"] == 5 and data["user_model"]["computed"] and "tx40.toml" in data["user_model"]["bodies_from"]
    back = load_fit(tmp_path / "fit.json", tx40)
    w = back.validate(test)
    np.testing.assert_allclose(w.user_rms_error, v.user_rms_error, rtol=1e-12)
    np.testing.assert_allclose(w.baseline_rms_error, v.baseline_rms_error, rtol=1e-12)
    # A schema-4 file (no user_model) still reads; its validation says why the model the user had is missing.
    del data["user_model"]
    data["schema_version"] = 4
    (tmp_path / "old.json").write_text(json.dumps(data))
    old = load_fit(tmp_path / "old.json", tx40).validate(test)
    assert old.user_rms_error is None and old.baseline_rms_error is not None
    assert "schema version 5" in old.user_model_note and old.to_dict()["user_model_note"] == old.user_model_note
    assert any("the model the user had: not computed" in line for line in old.table().splitlines())


def test_a_description_without_inertials_has_no_user_model_and_says_so(tmp_path):
    robot = rx90sym.load_robot(str(robot_file_without(tmp_path / "tx40.toml", "tx40", "nominal")))
    rec = rx90sym.twin.simulate(robot, multisine(robot, 4, duration=5.0), params=rx90sym.twin.default_parameters(
        rx90sym.load_robot("tx40")), duration=5.0, noise="quantised", seed=4, rate=200.0)
    fit_part, test = split(rec, 0.6)
    f = fit(robot, [fit_part], Processing(cutoff=12.0, estimate_delay=False))
    assert f.user_model is None and "no inertial parameters" in f.user_model_note
    v = f.validate(test)
    assert v.baseline_rms_error is not None and v.user_rms_error is None
    assert v.to_dict()["user_model_note"] == f.user_model_note
    assert "the model the user had: not computed (the description" in v.table()
    f.save(tmp_path / "fit.json")
    assert json.loads((tmp_path / "fit.json").read_text())["user_model"] == {
        "computed": False, "definition": identify.fitting.user_model.USER_MODEL_DEFINITION,
        "reason": f.user_model_note}
    assert load_fit(tmp_path / "fit.json").user_model_note == f.user_model_note


def _direct_folds(robot, rec, span):
    """Per held-out block, both yardsticks fitted by lstsq on the other blocks' samples of the whole
    recording (its signals whole, no windows), scored on the block's samples within the bounds."""
    segs = [window_signals(robot, s, w, r) for s, w, r in memory_windows([rec])]
    starts = np.r_[0, np.flatnonzero(np.diff(rec.segment)) + 1]
    theta = np.array([rx90sym.nominal_parameters(robot)[f"{p}{j + 1}"] for j in range(robot.n)
                      for p in ("M", "MX", "MY", "MZ", "XX", "XY", "YY", "XZ", "YZ", "ZZ")])
    W, y, tau, ids, scored = [], [], [], [], []
    for s, start in zip(segs, starts):
        k = np.flatnonzero(s.kept)
        W.append(baseline_regressor(robot, s.q[k], s.dq[k], s.ddq[k]))
        y.append(s.tau[k] + s.spring[k])
        tau.append(s.tau[k])
        ids.append(np.clip(time_folds(s.t[k], span.start, span.span, span.blocks), 0, span.blocks - 1))
        lo, hi = span.bounds.get((0, int(start)), (np.inf, -np.inf))
        scored.append((s.t[k] >= lo) & (s.t[k] <= hi))
    W, y, tau, ids, scored = (np.concatenate(a) for a in (W, y, tau, ids, scored))
    n, rigid = robot.n, theta.size
    err = {k: np.zeros((span.blocks, n)) for k in ("plain", "user")}
    ref = np.zeros((span.blocks, n))
    for b in range(span.blocks):
        other, held = ids != b, (ids == b) & scored
        plain, *_ = np.linalg.lstsq(W[other].reshape(-1, W.shape[2]), y[other].reshape(-1), rcond=1e-10)
        user = np.r_[theta, np.zeros(3 * n)]
        for j in range(n):
            cols = rigid + 3 * j + np.arange(3)
            user[cols], *_ = np.linalg.lstsq(W[other][:, j, cols], y[other, j] - W[other][:, j, :rigid] @ theta,
                                             rcond=1e-10)
        for kind, values in (("plain", plain), ("user", user)):
            err[kind][b] = np.sum((y[held] - W[held] @ values) ** 2, axis=0)
        ref[b] = np.sum(tau[held] ** 2, axis=0)
    return err, ref


def test_the_held_out_yardsticks_equal_a_direct_per_fold_computation(rx90):
    """The RX90 (its spring added to the torques fitted, not to the reference), two segments read in windows
    of 300 samples, three time blocks, the bounds of each segment narrower than its samples: the
    per-(block, joint) errors and references equal a direct computation, and the scores are block_scores'
    of them."""
    assert rx90.spring is not None
    rec = rx90sym.twin.simulate(rx90, multisine(rx90, 6, duration=8.0), duration=8.0, noise="quantised", seed=6,
                                rate=200.0)
    segment = np.repeat([0, 1], [900, rec.n_samples - 900])
    rec = dataclasses.replace(rec, segment=segment)
    src = MemorySource(rec, rx90)
    sc = scan(src, 300, None)
    span = RawSpan({(0, 0): (1.0, 3.8), (0, 900): (5.0, 7.3)}, 1.0, 6.3, 3)
    folds = yardstick_folds(rx90, [src], [sc], span, True, 300)
    err, ref = _direct_folds(rx90, rec, span)
    assert np.all(ref > 0) and np.all(folds.samples > 100)
    np.testing.assert_allclose(folds.ref2, ref, rtol=1e-9)
    for kind in ("plain", "user"):
        np.testing.assert_allclose(folds.err2[kind], err[kind], rtol=1e-8)
        assert folds.scores(kind) == block_scores(folds.err2[kind], folds.ref2)
    assert folds.scores("user")[0] != folds.scores("plain")[0]
