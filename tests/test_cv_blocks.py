"""The processing chosen by blocked cross-validation on a log read block by block
(identify.selection.processing_choice.choose_processing) against the same choice on the recording read
as one block with every sample's time kept, against a direct computation of one candidate's raw-torque
score on the whole recording, and through ``rx90 identify``."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

import identify
import rx90sym
from identify.app.cli import main
from identify.io.blocks import block_source
from identify import read_log
from identify.estimation.compression import block_factors
from identify.estimation.least_squares import fold_wls
from identify.selection.candidates import Candidate
from identify.selection.folds import time_folds
from identify.observation.matrix import column_regressor, filtered_motions, stack_rows
from identify.observation.offsets import offset_joints
from identify.observation.processing import Processing
from identify.observation.block_rows import plan_windows
from identify.observation.scan import scan
from identify.selection.processing_choice import LOWEST_CUTOFF, choose_processing, scans_for_choice
from identify.signal.filtering import EDGE_PERIODS
from motions import multisine
from rx90sym.host_log import HostFaults, host_log, write_host_log

#: Raw samples per block of the choice: every segment of the log below (about 5 s at 250 Hz) spans two
#: blocks or more; the command line's smallest --block (1,000) for its run.
BLOCK, CLI_BLOCK = 500, 1000
#: Scores [%] of the two paths agree to this relative tolerance. The filters agree to ~1e-13 at the
#: blocks' overlaps (their margins) and the knees to 1e-13 (each segment's rate from its own steps);
#: the fold fits amplify that by the conditioning of the base parameters: measured 4e-12 relative on
#: the scores (per joint and per held-back block included; 3e-10 on a TX40 twin with offsets).
RTOL = 1e-6


@pytest.fixture(scope="module")
def lossy_rx90(rx90, tmp_path_factory):
    """(recording CSV, the recording in memory): 15 s of the RX90 twin logged by a host at 250 Hz
    (5 % stale rows, bursts of 3-8 lost packets every 1-2 s bridged, two gaps of 0.2 s: three
    segments), read with --resample."""
    run = rx90sym.twin.simulate(rx90, multisine(rx90, 3), duration=15.0, noise="realistic", seed=3)
    table, _, _ = host_log(run, HostFaults(gap_every_s=(1.0, 2.0), gap_periods=(3, 8), long_gaps=(5.0, 10.0)), 3)
    folder = tmp_path_factory.mktemp("streamcv")
    cols = write_host_log(folder / "host.csv", table)
    rec = read_log(folder / "host.csv", rx90, cols, resample=250.0, convention="model")
    assert rec.n_segments == 3 and np.sum(~rec.measured_mask) > 100 and rec.meta["log"]["stale_rows"] > 100
    path = folder / "rec.csv"
    identify.write_recording(path, rec, rx90)
    return path, rec


def whole(robot, rec, processing=None, **options):
    """The choice on ``rec`` read as one block, every sample's time kept by its scan."""
    src = block_source(rec, robot)
    scans = [scan(src, rec.n_samples, LOWEST_CUTOFF, math.inf)]
    return choose_processing(robot, [src], processing, block=rec.n_samples, scans=scans, **options)


@pytest.fixture(scope="module")
def one_block(rx90, rx90_base, lossy_rx90):
    return whole(rx90, lossy_rx90[1], base=rx90_base, offsets=offset_joints(rx90, rx90_base))


def _same_scores(a, b) -> None:
    assert a == pytest.approx(b, rel=RTOL, nan_ok=True)


def test_the_choice_block_by_block_equals_the_one_block_choice(rx90, rx90_base, lossy_rx90, one_block):
    """Same knee, candidates, per-joint rest policy, chosen candidate and scores (per joint and per
    held-back block) from the CSV read in blocks of 500 samples as from the recording read in one block."""
    path, _ = lossy_rx90
    src = block_source(str(path), rx90)
    segments = scan(src, BLOCK, None).segments
    plans, _ = plan_windows(scan(src, BLOCK, None), Processing(cutoff=4.0, decimate_to=50.0), BLOCK)
    assert len(segments) == 3 and all(len(p.windows) >= 2 for p in plans)  # blocks inside every segment
    got = choose_processing(rx90, [src], base=rx90_base, block=BLOCK, offsets=offset_joints(rx90, rx90_base))
    assert got.knee == pytest.approx(one_block.knee, rel=1e-9)
    assert got.offsets == one_block.offsets and got.reference_hz == one_block.reference_hz == "raw"
    _same_scores([v for row in got.offset_candidate.per_block for v in row],
                 [v for row in one_block.offset_candidate.per_block for v in row])
    assert [(c.decimate_to, c.rest, c.label) for c in got.candidates] == \
        [(c.decimate_to, c.rest, c.label) for c in one_block.candidates]
    for a, b in zip(got.candidates, one_block.candidates):
        assert a.cutoff == pytest.approx(b.cutoff, rel=1e-9)
        _same_scores(a.score, b.score)
        _same_scores(a.per_joint, b.per_joint)
        _same_scores([v for row in a.per_block for v in row], [v for row in b.per_block for v in row])
    assert got.chosen.rest == one_block.chosen.rest and got.chosen.label == one_block.chosen.label
    assert any(c.decimate_to is None for c in got.candidates if not math.isnan(c.score))  # "no decimation" too
    assert got.chosen.cutoff == pytest.approx(one_block.chosen.cutoff, rel=1e-9)
    assert [name for name, _ in got.rest_scores] == [name for name, _ in one_block.rest_scores]
    # The choice is not a formality on this log: the candidates' scores differ by far more than the
    # tolerance, and the default (20 Hz) is beaten.
    scores = [c.score for c in got.candidates if not math.isnan(c.score)]
    assert max(scores) > 2 * min(scores) and got.chosen.label != "(default)"


def _direct_score(robot, base, rec, cand, blocks, delay):
    """(score, per block and joint) of one candidate computed on the whole recording in the plainest
    way: its rows (filtered_motions), the fold fits on the other blocks' rows, each held-back
    prediction put onto the recording's own measured time stamps by numpy.interp, against the raw
    torques, on the samples 3 periods of the cut-off, two decimated periods and the delay from
    each segment's ends."""
    names, regressor = column_regressor(robot, base)
    processing = Processing(cutoff=cand.cutoff, decimate_to=cand.decimate_to, min_velocity=0.05, rest=cand.rest,
                            delay=delay)
    motions, _, used = filtered_motions(robot, [rec], processing, regressor, names)
    margin = EDGE_PERIODS / cand.cutoff + 2.0 / cand.decimate_to + abs(delay)
    targets = []
    for piece in used:
        t = np.asarray(piece.t)
        keep = (t >= t[0] + margin) & (t <= t[-1] - margin) & piece.measured_mask
        targets.append((t[keep], np.asarray(piece.torques)[keep]))
    start = min(t[0] for t, _ in targets)
    span = max(t[-1] for t, _ in targets) - start + 1e-9
    ids = [np.clip(time_folds(m.t + delay, start, span, blocks), 0, blocks - 1) for m in motions]
    W, Y, joint, samples = stack_rows([m.Phi for m in motions], [m.Y for m in motions],
                                      masks=[m.rows(False) for m in motions])
    factors = block_factors(W, Y, joint, np.concatenate(ids)[samples], range(blocks), robot.n)
    err2, ref2 = np.zeros((blocks, robot.n)), np.zeros((blocks, robot.n))
    for b in range(blocks):
        beta = fold_wls(factors, b, robot.n)
        for m, (t, tau) in zip(motions, targets):
            here = time_folds(t, start, span, blocks) == b
            pred = m.Phi @ beta - robot.spring_torque_batch(m.q)[:, :, 0]
            for j in range(robot.n):
                err2[b, j] += np.sum((tau[here, j] - np.interp(t[here], m.t + delay, pred[:, j])) ** 2)
                ref2[b, j] += np.sum(tau[here, j] ** 2)
    return float(np.mean(100 * np.sqrt(err2.sum(0) / ref2.sum(0)))), 100 * np.sqrt(err2 / ref2)


def test_a_candidate_scores_its_prediction_interpolated_onto_the_raw_torques(rx90, rx90_base, lossy_rx90):
    """One candidate read in blocks of 500 samples (every segment in two or more windows, bridged
    samples, a torque delay of 6 ms: 1.5 samples) scores what the whole recording gives when its
    held-back prediction is interpolated by numpy onto the raw measured torques."""
    _, rec = lossy_rx90
    cand = Candidate(12.0, 50.0, rest="zero-coulomb")
    got = choose_processing(rx90, [rec], Processing(rest="zero-coulomb", delay=0.006), rx90_base, block=BLOCK,
                            candidates=[cand]).chosen
    score, per_block = _direct_score(rx90, rx90_base, rec, cand, 5, 0.006)
    assert got.score == pytest.approx(score, rel=RTOL)
    np.testing.assert_allclose(np.asarray(got.per_block), per_block, rtol=RTOL)


def test_the_cli_cross_validates_a_long_log(rx90, lossy_rx90, one_block, tmp_path, capsys):
    """``rx90 identify`` on a log longer than --block: the candidate table printed, the fit made with
    the chosen processing, ``processing_choice`` in the fit file as for a log in memory."""
    path, _ = lossy_rx90
    out = tmp_path / "fit.json"
    assert main(["identify", str(path), "--robot", "rx90", "--block", str(CLI_BLOCK), "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "processing chosen by 5-block cross-validation" in printed and "<- chosen" in printed
    assert "friction form chosen per joint by 5-block cross-validation" in printed   # block by block too
    assert "not cross-validated" not in printed
    record = json.loads(out.read_text())
    choice, chosen = record["processing_choice"], one_block.chosen
    assert choice["chosen"]["cutoff_hz"] == pytest.approx(chosen.cutoff, rel=1e-9)
    assert choice["chosen"]["rest"] == chosen.rest and choice["chosen"]["decimate_to_hz"] == chosen.decimate_to
    _same_scores(choice["chosen"]["score_pct"], chosen.score)
    assert record["model"]["cutoff_hz"] == pytest.approx(chosen.cutoff, rel=1e-9)
    assert record["model"]["rest"] == chosen.rest and record["model"]["decimate_to_hz"] == chosen.decimate_to
    loaded = identify.load_fit(out)
    assert loaded.cutoff == pytest.approx(chosen.cutoff, rel=1e-9) and loaded.choice["reason"] == choice["reason"]


def test_the_choice_on_dask_equals_the_serial_one(rx90, rx90_base):
    """Every block of every candidate a task on two local workers, the factors folded in block order
    on the client: the serial choice (same scores to the last digit, measured)."""
    from dask.distributed import Client, LocalCluster

    run = rx90sym.twin.simulate(rx90, multisine(rx90, 4), duration=6.0, noise="realistic", seed=4)
    src = block_source(run, rx90)  # 6 s at 250 Hz: three blocks of 500 samples
    serial = choose_processing(rx90, [src], base=rx90_base, block=BLOCK)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        spread = choose_processing(rx90, [src], base=rx90_base, block=BLOCK, client=client)
    assert [(c.cutoff, c.rest, c.score, c.per_block) for c in spread.candidates] == \
        [(c.cutoff, c.rest, c.score, c.per_block) for c in serial.candidates]
    # the knee (about 2 Hz) below the grid's 10 Hz floor: two rest policies at 10 Hz and the default
    assert spread.chosen.cutoff == serial.chosen.cutoff and len(serial.candidates) >= 3


def test_a_long_segment_gets_the_choice_of_every_time_from_its_first_and_last_seconds(rx90, rx90_base):
    """10 s in one segment read in blocks of 500 samples: the scan keeps only its first and last 3 s
    of times, where the raw samples scored start and end; the choice (torque offsets and a 4 ms
    delay included) is the one of the recording read in one block with every time kept."""
    run = rx90sym.twin.simulate(rx90, multisine(rx90, 5), duration=10.0, noise="realistic", seed=5)
    processing, options = Processing(delay=0.004), dict(base=rx90_base, offsets=offset_joints(rx90, rx90_base))
    src = block_source(run, rx90)
    got = choose_processing(rx90, [src], processing, block=BLOCK, **options)
    assert all(g.head.size + g.tail.size < g.samples for s in scans_for_choice([src], BLOCK) for g in s.segments)
    one = whole(rx90, run, processing, **options)
    assert (got.chosen.cutoff, got.chosen.decimate_to, got.chosen.rest, got.offsets) == \
        (one.chosen.cutoff, one.chosen.decimate_to, one.chosen.rest, one.offsets)
    for a, b in zip(got.candidates + (got.offset_candidate,), one.candidates + (one.offset_candidate,)):
        _same_scores([a.score, *[v for row in a.per_block for v in row]],
                     [b.score, *[v for row in b.per_block for v in row]])
