"""Logs of any length: block-wise filtering, incremental QR, streamed fit, log conversion and Dask
against the whole-signal functions (the reference: every figure so far comes from them)."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

import identify
import rx90sym
from identify.estimation.bootstrap import SegmentBootstrap, segment_bootstrap_std
from identify.estimation.compression import compress
from identify.estimation.incremental_qr import JointFactors
from identify.io.blocks import CsvSource
from identify.io.log_blocks import convert_log
from identify.observation.processing import Processing
from identify.signal.blocks import WelchAccumulator, decimation_margin, lowpass_margin, motion_windows
from identify.signal.filtering import decimate, lowpass
from identify.fitting.passes import BootstrapSpec, run_passes
from identify.fitting.validation import predict

RX90 = str(Path(sys.executable).parent / "rx90")


def test_blocks_equal_the_whole_signal_filters():
    """Low-pass then decimation on overlapping blocks, cut to their cores, equal the whole-signal result
    to the stated tolerance (1e-12 of the impulse response) at 1 kHz with a 3 Hz cut-off."""
    rng = np.random.default_rng(0)
    rate, fc, k, n, edge = 1000.0, 3.0, 20, 40_000, 1000
    x = np.cumsum(rng.normal(size=(n, 2)), axis=0)
    whole = decimate(lowpass(x, rate, fc)[edge:n - edge], k)
    lp, dm = lowpass_margin(rate, fc), decimation_margin(k)
    windows = motion_windows(n, edge, k, 6000, lp, dm)
    assert len(windows) > 4 and windows[0].raw[0] == 0 and windows[-1].raw[1] == n
    got = np.full_like(whole, np.nan)
    for w in windows:
        (r0, r1), (d0, d1), (c0, c1) = w.raw, w.span, w.core
        part = decimate(lowpass(x[r0:r1], rate, fc)[d0 - r0:d1 - r0], k)
        j0 = (d0 - edge) // k
        got[c0:c1] = part[c0 - j0:c1 - j0]
    scale = np.abs(whole).max()
    assert np.nanmax(np.abs(got - whole)) < 1e-10 * scale
    # Without the margins the error is of the signal's size: the margins are what makes it exact.
    short = decimate(lowpass(x[20_000:26_000], rate, fc), k)
    assert np.abs(short[5] - whole[(20_000 + 100 - edge) // k]).max() > 1e-4 * scale


def test_streamed_welch_equals_scipy():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(9_173, 3))
    acc = WelchAccumulator(250.0, 1000, 3)
    for a in range(0, x.shape[0], 1234):
        acc.feed(x[a:a + 1234])
    f, p = acc.result()
    for j in range(3):
        f0, p0 = signal.welch(x[:, j], fs=250.0, window="hann", nperseg=1000, detrend="constant")
        np.testing.assert_allclose(p[:, j], p0, rtol=1e-12)
        np.testing.assert_array_equal(f, f0)


def test_incremental_qr_and_bootstrap_equal_the_whole_matrix():
    rng = np.random.default_rng(2)
    S, n, c = 900, 3, 6
    W = rng.normal(size=(S * n, c))
    Y = W @ rng.normal(size=c) + rng.normal(size=S * n)
    joint, samples = np.repeat(np.arange(n), S), np.tile(np.arange(S), n)
    factors = JointFactors(n, c)
    boot = SegmentBootstrap(S, 25, n, c, draws=40, seed=5)
    for a in range(0, S, 170):  # blocks that split bootstrap segments
        for j in range(n):
            rows = slice(j * S + a, j * S + min(S, a + 170))
            factors.add(j, np.column_stack([W[rows], Y[rows]]))
            boot.add(j, samples[rows], W[rows], Y[rows])
    for j in range(n):
        whole = compress(W[joint == j], Y[joint == j])
        x = rng.normal(size=c)
        assert factors.system(j).rss(x) == pytest.approx(whole.rss(x), rel=1e-12)
    res = identify.weighted_least_squares(W, Y, joint, [f"p{i}" for i in range(c)])
    streamed = identify.estimation.least_squares.solve_joint_systems(factors.systems(), res.names)
    np.testing.assert_allclose(streamed.values, res.values, rtol=1e-12)
    np.testing.assert_allclose(boot.std(res.weights),
                               segment_bootstrap_std(W, Y, joint, samples, res.weights, 25, 40, 5), rtol=1e-10)


@pytest.fixture(scope="module")
def whole_fit(rx90, rx90_base, twin_empty):
    # The position-spectrum cut-off (no cross-validation): the block-wise fits compared with it fix it too.
    return identify.fit(rx90, twin_empty[:1], WHOLE, base=rx90_base)


#: The processing of a block-wise fit, for the whole-signal fits it is compared with.
WHOLE = Processing(cross_validate=False)


def _close(a: np.ndarray, b: np.ndarray, rtol: float) -> None:
    """Equal to ``rtol`` relative, parameters near zero compared with the largest one."""
    np.testing.assert_allclose(a, b, rtol=rtol, atol=rtol * 1e-2 * np.abs(b).max())


def test_streamed_fit_equals_the_whole_fit(rx90, rx90_base, twin_empty, whole_fit):
    """A 20 s twin recording in blocks of 1,000 samples: estimates, σ, bootstrap σ, delay estimate
    and validation equal the whole-signal path's."""
    obs = whole_fit.observation
    boot = segment_bootstrap_std(obs.W, obs.Y, obs.joint, obs.samples, whole_fit.result.weights, 25, 50, 0)
    fit = run_passes(rx90, twin_empty[:1], Processing(cross_validate=False), columns=rx90_base, block=1000,
                     bootstrap=BootstrapSpec(0.5, 50, 0))
    assert fit.blocks >= 4 and fit.cutoff == whole_fit.cutoff and fit.result.rows == whole_fit.result.rows
    _close(fit.result.values, whole_fit.result.values, 1e-8)
    _close(fit.result.std, whole_fit.result.std, 1e-8)
    assert fit.result.sigma_rho == pytest.approx(whole_fit.result.sigma_rho, rel=1e-10)
    _close(fit.bootstrap_std, boot, 1e-8)
    assert fit.delay_estimate.delay == pytest.approx(whole_fit.delay_estimate.delay, abs=1e-9)
    val = identify.predict(rx90, whole_fit.result, twin_empty[1], base=rx90_base, **whole_fit.filtering())
    streamed = predict(rx90, whole_fit.result, twin_empty[1], base=rx90_base, block=1000, **whole_fit.filtering())
    np.testing.assert_allclose(streamed.rms_error, val.rms_error, rtol=1e-8)
    np.testing.assert_allclose(streamed.relative_error_pct_moving, val.relative_error_pct_moving, rtol=1e-8)


@pytest.mark.slow
def test_streamed_fit_of_several_recordings_with_rest_dropped(rx90, rx90_base, twin_empty):
    """80 s in four recordings, rest rows dropped and the cut-off chosen: equal to the whole path."""
    # The processing fixed on both paths (the choice block by block: tests/test_cv_blocks.py).
    whole = identify.fit(rx90, twin_empty, Processing(rest="drop", delay="auto", cross_validate=False), base=rx90_base)
    fit = run_passes(rx90, twin_empty, Processing(rest="drop", delay="auto", cross_validate=False), columns=rx90_base,
                     block=2000)
    assert fit.cutoff == whole.cutoff and fit.result.rows == whole.result.rows
    assert fit.delay == pytest.approx(whole.delay, abs=1e-9)
    _close(fit.result.values, whole.result.values, 1e-8)


def test_dask_blocks_equal_serial(rx90, rx90_base, twin_empty, whole_fit, tmp_path):
    """identify.fit with blocks as Dask tasks (two local workers) gives the serial block-wise fit (same
    operations, same order), which equals the whole fit; the fit file saves and loads."""
    from dask.distributed import Client, LocalCluster

    serial = identify.fit(rx90, twin_empty[:1], WHOLE, base=rx90_base, block=1000)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        spread = identify.fit(rx90, twin_empty[:1], WHOLE, base=rx90_base, block=1000, client=client)
    np.testing.assert_allclose(spread.result.values, serial.result.values, rtol=1e-10)
    np.testing.assert_allclose(spread.bootstrap.std, serial.bootstrap.std, rtol=1e-10)
    for stick in ("baseline", "user_model"):  # the yardsticks' windows on the workers too
        np.testing.assert_allclose(getattr(spread, stick).values, getattr(serial, stick).values, rtol=1e-10)
    assert spread.passes.blocks == serial.passes.blocks >= 4 and serial.observation is not None  # rows kept (few)
    _close(serial.result.values, whole_fit.result.values, 1e-8)
    assert serial.bootstrapped(0) is serial
    loaded = identify.load_fit(serial.save(tmp_path / "fit.json"))
    np.testing.assert_array_equal(loaded.result.values, serial.result.values)
    assert loaded.cutoff == whole_fit.cutoff


def test_csv_blocks_read_the_file_and_name_bad_rows(rx90, twin_empty, tmp_path):
    rec = twin_empty[0]
    path = tmp_path / "rec.csv"
    identify.write_recording(path, rec, rx90)
    src = CsvSource(path, rx90, batch_bytes=1 << 16)
    scanned = list(src.scan(1500))
    assert src.n_samples == rec.n_samples and len(scanned) == -(-rec.n_samples // 1500)
    part = next(src.windows([(1234, 4321)]))
    np.testing.assert_allclose(part.q, rec.q[1234:4321], atol=1e-15)
    np.testing.assert_array_equal(part.tau, rec.tau[1234:4321])
    lines = path.read_text().splitlines()
    cells = lines[3 + 3000].split(",")  # two comment lines and the header, then data row 1
    cells[2] = "nan"
    lines[3 + 3000] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(identify.RecordingError, match=r"rec\.csv.*q2.*row 3001"):
        list(CsvSource(path, rx90).scan(1000))


def test_convert_log_in_blocks_equals_the_whole_reader(rx90, twin_empty, tmp_path):
    rec = twin_empty[0]
    log = tmp_path / "log.csv"
    q = np.asarray(rx90.to_controller(rec.q))
    table = np.column_stack([rec.t, q, rec.tau])
    np.savetxt(log, table, delimiter=",", fmt="%.17g",
               header=",".join(["t"] + [f"q{j}" for j in range(1, 7)] + [f"tau{j}" for j in range(1, 7)]),
               comments="")
    for resample in (None, 200.0):
        out = tmp_path / "streamed.csv"
        report = convert_log(log, rx90, "t,q1..q6,tau1..tau6", out, header=True, resample=resample, block=777)
        whole = identify.read_log(log, rx90, "t,q1..q6,tau1..tau6", header=True, resample=resample)
        got = identify.read_recording(out, rx90)
        assert report["samples"] == whole.n_samples and report["rows"] == rec.n_samples
        np.testing.assert_allclose(got.q, whole.q, rtol=0, atol=1e-14)
        np.testing.assert_array_equal(got.tau, whole.tau)
        np.testing.assert_array_equal(got.t, whole.t)
    text = log.read_text().splitlines()
    text[2000] = text[2000].replace(",", ",x", 1)
    log.write_text("\n".join(text) + "\n")
    with pytest.raises(identify.RecordingError, match=r"line 2001"):
        convert_log(log, rx90, "t,q1..q6,tau1..tau6", tmp_path / "bad.csv", header=True, block=777)
    assert not (tmp_path / "bad.csv").exists()


@pytest.mark.slow
def test_cli_identify_streams_a_log_longer_than_the_block(rx90, twin_empty, whole_fit, tmp_path):
    path = tmp_path / "rec.csv"
    identify.write_recording(path, twin_empty[0], rx90)
    done = subprocess.run([RX90, "identify", str(path), "--block", "1000", "--no-cross-validate", "--json",
                           str(tmp_path / "id.json")],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert "block by block" in done.stderr
    out = json.loads((tmp_path / "id.json").read_text())
    values = np.array([p["value"] for p in out["parameters"]])
    _close(values, whole_fit.result.values, 1e-8)
    bad = subprocess.run([RX90, "identify", str(path), "--block", "10"], capture_output=True, text=True)
    assert bad.returncode == 2 and "--block must be at least 1000" in bad.stderr


def test_fleet_fits_every_robot_on_its_own_logs(rx90, rx90_base, twin_empty, whole_fit):
    """Two robots in one call (two RX90 cells, each with its own log): one fit each, equal to that
    robot's whole-signal fit, and one table line each."""
    from identify.fitting.fleet import fit_fleet

    fleet = fit_fleet({"cell-1": (rx90, twin_empty[:1]), "cell-2": (rx90, twin_empty[1:2])}, WHOLE, base=rx90_base,
                      block=2000)
    assert list(fleet.fits) == ["cell-1", "cell-2"]
    _close(fleet.fits["cell-1"].result.values, whole_fit.result.values, 1e-8)
    other = identify.fit(rx90, twin_empty[1:2], WHOLE, base=rx90_base)
    _close(fleet.fits["cell-2"].result.values, other.result.values, 1e-8)
    assert not np.allclose(other.result.values, whole_fit.result.values, rtol=1e-6)
    lines = fleet.table().splitlines()
    assert len(lines) == 3 and lines[1].startswith("cell-1") and lines[2].startswith("cell-2")


def test_a_log_within_one_block_is_one_block(rx90, twin_empty):
    """One pipeline: identify.fit with the defaults (processing, offsets and friction form chosen on the
    torques, delay, bootstrap, both yardsticks) gives the same estimates to 1e-8 relative for a block of N / 3,
    N - 1, N, N + 1 and 100 N samples of an N-sample recording, and the same choices."""
    rec = twin_empty[0]
    n = rec.n_samples
    ref = identify.fit(rx90, [rec], block=n)
    assert ref.choice is not None and ref.baseline is not None and ref.observation is not None
    for block in (n // 3, n - 1, n + 1, 100 * n):
        got = identify.fit(rx90, [rec], block=block)
        assert got.passes.blocks >= (3 if block == n // 3 else 1)
        a, b = got.choice["chosen"], ref.choice["chosen"]
        assert got.result.names == ref.result.names
        assert (a["cutoff_hz"], a["decimate_to_hz"], a["rest"]) == (b["cutoff_hz"], b["decimate_to_hz"], b["rest"])
        assert a["score_pct"] == pytest.approx(b["score_pct"], rel=1e-8)
        assert got.model.friction == ref.model.friction and got.model.offset_joints == ref.model.offset_joints
        _close(got.result.values, ref.result.values, 1e-8)
        _close(got.bootstrap.std, ref.bootstrap.std, 1e-8)
        _close(got.baseline.values, ref.baseline.values, 1e-8)
        _close(got.user_model.values, ref.user_model.values, 1e-8)


def test_a_fit_in_blocks_keeps_the_rows_of_the_whole_observation(rx90, rx90_base, twin_empty, whole_fit):
    """The decimated rows of a fit made in blocks of 1,000 samples, kept beside its factors
    (identify.observation.row_store), are those of the whole-signal observation matrix, and the same
    whatever the block."""
    obs = whole_fit.observation
    for block in (1000, 10 ** 6):
        got = identify.fit(rx90, twin_empty[:1], WHOLE, base=rx90_base, block=block, bootstrap_seed=None)
        kept = got.observation
        assert kept is not None and kept.names == obs.names and kept.rows == obs.rows
        np.testing.assert_array_equal(kept.joint, obs.joint)
        np.testing.assert_array_equal(kept.samples, obs.samples)
        np.testing.assert_allclose(kept.t, obs.t, rtol=0, atol=1e-12)
        scale = np.abs(obs.W).max(axis=0) + 1e-300
        assert np.max(np.abs(kept.W - obs.W) / scale) < 1e-9
        assert np.max(np.abs(kept.Y - obs.Y)) < 1e-9 * np.abs(obs.Y).max()
        np.testing.assert_allclose(kept.moving_fraction, obs.moving_fraction, rtol=1e-12)


def test_a_bad_block_is_refused_alike_everywhere(rx90, twin_empty, whole_fit, tmp_path):
    """fit, predict and the log reader refuse a block that is no whole number or too small, saying so."""
    rec = twin_empty[1]
    for bad in (0, -5, 2.5, 1000.5, "60000", True):
        with pytest.raises(ValueError, match="block must be a whole number of samples >= 1000"):
            identify.fit(rx90, [rec], WHOLE, block=bad)
        with pytest.raises(ValueError, match="block must be a whole number of samples >= 1000"):
            whole_fit.predict(rec, block=bad)
    log = tmp_path / "log.csv"
    log.write_text("\n".join(",".join(f"{v:.6f}" for v in [t, *q, *tau]) for t, q, tau in
                             zip(rec.t[:50], rec.q[:50], rec.tau[:50])) + "\n")
    for bad in (0, -1, 2.5):
        with pytest.raises(ValueError, match="block must be a whole number of lines >= 1"):
            identify.read_log(log, rx90, "t,q1..q6,tau1..tau6", convention="model", block=bad)
    assert identify.read_log(log, rx90, "t,q1..q6,tau1..tau6", convention="model", block=7).n_samples == 50


def test_a_prediction_does_not_depend_on_the_block(tmp_path):
    """The TX40 record (5 kHz): a fit at 20 Hz predicts at 400 Hz, 12.5 samples a row, where a window's own
    median step used to round the factor the other way than its segment's (its rows then did not tile: 384
    samples unscored, 0.8 N·m off before the boundary); and the "crossing" rest runs cut by a window's edge.
    Predicted in blocks of 2000 and 5000 samples and in one: the same samples scored, the same torques."""
    from identify import Processing, read_motor_recording

    robot = rx90sym.load_robot("tx40")
    d = rx90sym.datasets.tx40()
    rec = read_motor_recording(d.positions, d.torques, robot, d.period)
    k = 30000
    rest = ("zero-coulomb",) * 4 + ("crossing", "crossing")
    f = identify.fit(robot, [rec.select(slice(0, k))], Processing(cutoff=20.0, decimate_to=50.0, rest=rest,
                                                                 estimate_delay=False), bootstrap_seed=None)
    path = tmp_path / "held.csv"
    identify.write_recording(path, rec.select(slice(k, None)), robot)
    whole = f.predict(path, block=10 ** 6)
    assert whole.t.size > 9000
    for block in (2000, 5000):
        got = f.predict(path, block=block)
        np.testing.assert_array_equal(got.t, whole.t)
        np.testing.assert_allclose(got.predicted, whole.predicted, rtol=0, atol=1e-6)
        np.testing.assert_allclose(got.rms_error, whole.rms_error, rtol=1e-9)
