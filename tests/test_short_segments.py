"""Logs checked and cut the same way read whole or block by block: units checked on the block converter,
segments too short to filter dropped and counted, a log of short segments only refused."""
from __future__ import annotations

import re

import numpy as np
import pytest

import rx90sym
from motions import multisine


@pytest.fixture(scope="module")
def rx90_logs(rx90, tmp_path_factory):
    """Controller logs of a 8 s twin run at 250 Hz (2000 rows): t, q1..q6, qd1..qd6, tau1..tau6 as
    recorded, in degrees, and with the q and qd groups swapped."""
    d = tmp_path_factory.mktemp("units")
    rec = rx90sym.twin.simulate(rx90, multisine(rx90, 4, duration=8.0), duration=8.0, rate=250.0,
                                noise="quantised", seed=4)
    qc = np.asarray(rx90.to_controller(rec.q))
    qd = np.gradient(rec.q, rec.t, axis=0)
    out = {}
    for name, cols in (("log.csv", (qc, qd)), ("degrees.csv", (np.rad2deg(qc), np.rad2deg(qd))),
                       ("swapped.csv", (qd, qc))):
        np.savetxt(d / name, np.column_stack([rec.t, *cols, rec.tau]), delimiter=",", fmt="%.12g")
        out[name] = d / name
    return out


@pytest.mark.parametrize("name, words", [("degrees.csv", "positions look like degrees"),
                                         ("swapped.csv", "position and velocity groups look swapped")])
def test_the_block_converter_checks_the_units_as_the_reader(rx90, rx90_logs, tmp_path, capsys, name, words):
    """A log in degrees or with q/qd swapped, longer than --block: the reader's message (degrees: the
    counts of the block refused), exit 2, nothing written. Before, the block path skipped the check
    and called the rows corrupt (degrees) or named a velocity mismatch (swapped)."""
    from identify.app.cli import main
    from identify import read_log
    from rx90sym.recording import RecordingError

    cols = "t,q1..q6,qd1..qd6,tau1..tau6"
    with pytest.raises(RecordingError) as whole:
        read_log(rx90_logs[name], rx90, cols)
    out = tmp_path / "rec.csv"
    code = main(["convert", str(rx90_logs[name]), "--robot", "rx90", "--no-header", "--columns", cols,
                 "--block", "1000", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and words in err and not out.exists(), err
    # The same message (degrees: the same first line, joint and value; the counts are the block's).
    counts = re.compile(r"\d+ of \d+ rows")
    assert counts.sub("", str(whole.value)) in counts.sub("", err.splitlines()[-1])
    assert main(["convert", str(rx90_logs["log.csv"]), "--robot", "rx90", "--no-header", "--columns", cols,
                 "--block", "1000", "--out", str(out)]) == 0 and out.exists()


def _write_rows(path, table, keep):
    np.savetxt(path, table[keep], delimiter=",", fmt="%.12g")
    return path


def test_a_segment_too_short_to_filter_is_dropped_and_counted(rx90, rx90_logs, tmp_path, capsys):
    """Gaps of 21 periods (84 ms, beyond the 50 ms bridged) around one row, then 18 rows, then 19: the
    one row and the 18 are dropped and counted (report, printed), the 19 kept as a segment; the block
    converter writes the same recording for blocks ending anywhere near them. Before, resampling
    failed inside scipy ("`x` must contain at least 2 elements")."""
    from identify.app.cli import main
    from identify.io.log_blocks import convert_log
    from identify import read_log
    from identify.io.recordings import read_recording

    table = np.loadtxt(rx90_logs["log.csv"], delimiter=",")
    rows = np.arange(table.shape[0])
    keep = (rows < 700) | (rows == 720) | ((rows >= 741) & (rows < 759)) | ((rows >= 780) & (rows < 799)) | (rows >= 820)
    path = _write_rows(tmp_path / "short.csv", table, keep)
    cols = "t,q1..q6,qd1..qd6,tau1..tau6"
    line = {int(r): k + 1 for k, r in enumerate(rows[keep])}  # file line of each row kept
    whole = read_log(path, rx90, cols, resample=250.0)
    gaps = whole.meta["log"]["gaps"]
    from identify.io.gaps import MIN_SEGMENT_ROWS
    assert MIN_SEGMENT_ROWS == 19 and whole.n_segments == gaps["segments"] == 3
    assert gaps["dropped_segments"] == 2 and gaps["dropped_rows"] == 19
    assert gaps["dropped_lines"] == [[line[720], line[720]], [line[741], line[758]]]
    t = np.asarray(whole.t)
    assert not np.any((t > table[700, 0]) & (t < table[780, 0]))  # nothing of the dropped rows
    for block in (line[720], line[720] + 1, line[741] + 5, line[758], 1000):
        out = tmp_path / f"b{block}.csv"
        report = convert_log(path, rx90, cols, out, resample=250.0, block=block)
        got = read_recording(out, rx90)
        assert report["gaps"]["dropped_lines"] == gaps["dropped_lines"] and report["gaps"]["segments"] == 3
        np.testing.assert_array_equal(got.segment, whole.segment)
        np.testing.assert_allclose(got.t, whole.t, rtol=0, atol=1e-12)
        np.testing.assert_allclose(got.q, whole.q, rtol=0, atol=1e-9)
    out = tmp_path / "rec.csv"
    assert main(["convert", str(path), "--robot", "rx90", "--no-header", "--columns", cols, "--resample", "250",
                 "--out", str(out)]) == 0
    assert f"segments too short to filter dropped: 2 (19 rows" in capsys.readouterr().out


def test_a_log_of_short_segments_only_is_refused_on_both_paths(rx90, rx90_logs, tmp_path):
    from identify.io.log_blocks import convert_log
    from identify import read_log
    from rx90sym.recording import RecordingError

    table = np.loadtxt(rx90_logs["log.csv"], delimiter=",")
    rows = np.arange(400)
    path = _write_rows(tmp_path / "bits.csv", table[:400], rows % 40 < 10)  # 10 rows, then 30 lost (120 ms)
    cols = "t,q1..q6,qd1..qd6,tau1..tau6"
    with pytest.raises(RecordingError, match="fewer than 19 rows .lines 1..10 the first.: none is long enough"):
        read_log(path, rx90, cols, resample=250.0)
    out = tmp_path / "rec.csv"
    with pytest.raises(RecordingError, match="none is long enough to filter"):
        convert_log(path, rx90, cols, out, resample=250.0, block=25)
    assert not out.exists()
