"""One file per signal, no time column (identify.io.joint_files, rx90 convert --positions ...),
and --period for a one-file log without time column (issue 29 item 4).

The reference is the one-file log reader (identify.read_log) on the same numbers pasted into one
file with a time column t = k * period: the recordings must be byte-identical.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import rx90sym
from identify import read_log
from identify.app import cli
from identify.io.joint_files import read_joint_files
from identify.io.recordings import RecordingWarning, write_recording
from rx90sym.recording import RecordingError
from rx90sym.twin import CurrentSensor

from motions import multisine

PERIOD = 0.01  # s: a 100 Hz dataset
GAINS = (0.5, 0.6, 0.4, 0.3, 0.25, 0.2)  # N·m/A, joint side


@pytest.fixture(scope="module")
def run(rx90):
    """A 3 s twin run at 100 Hz in controller angles (q, qd, tau, i), as a dataset would hold it."""
    f = multisine(rx90, 0)
    rec = rx90sym.twin.simulate(rx90, f, duration=3.0, rate=1 / PERIOD, noise="quantised", seed=0)
    sensor = CurrentSensor(GAINS, "joint", noise=0.0)
    cur = rx90sym.twin.simulate(rx90, f, duration=3.0, rate=1 / PERIOD, noise="quantised", seed=0, currents=sensor)
    q = np.asarray(rx90.to_controller(rec.q))
    dq = np.gradient(q, rec.t, axis=0)  # "recorded" velocities (the twin records none)
    return q, dq, np.asarray(rec.tau), np.asarray(cur.current)


def _write(path: Path, values: np.ndarray, header: str | None = None, comment: str = "") -> Path:
    with open(path, "w") as fh:
        fh.write(comment)
        if header is not None:
            fh.write(header + "\n")
        np.savetxt(fh, values, fmt="%.17g", delimiter=",")
    return path


def _bytes(rec, robot, path: Path) -> bytes:
    write_recording(path, rec, robot, convention="controller")
    return path.read_bytes()


def test_two_files_give_the_recording_of_one_pasted_file(rx90, run, tmp_path):
    q, dq, tau, _ = run
    n = len(q)
    t = np.arange(n) * PERIOD
    pasted = _write(tmp_path / "pasted.csv", np.column_stack([t, q, dq, tau]))
    reference = read_log(pasted, rx90, "t,q1..q6,qd1..qd6,tau1..tau6")
    # Files with a header (names not interpreted) or none, and a comment line.
    files = {"positions": _write(tmp_path / "Q.csv", q, "a,b,c,d,e,f", "# exported by the maker\n"),
             "velocities": _write(tmp_path / "V.csv", dq),
             "torques": _write(tmp_path / "T.csv", tau, ",".join(f"Joint_{j}" for j in range(1, 7)))}
    rec = read_joint_files(rx90, files, PERIOD)
    assert rec.t[0] == 0.0 and rec.n_samples == n
    assert _bytes(rec, rx90, tmp_path / "a.csv") == _bytes(reference, rx90, tmp_path / "b.csv")
    # The one-file form without time column: --period.
    nameless = _write(tmp_path / "nameless.csv", np.column_stack([q, dq, tau]))
    one = read_log(nameless, rx90, "q1..q6,qd1..qd6,tau1..tau6", period=PERIOD)
    assert _bytes(one, rx90, tmp_path / "c.csv") == _bytes(reference, rx90, tmp_path / "b.csv")
    # The command line writes the same bytes.
    out = tmp_path / "cli.csv"
    code = cli.main(["convert", "--robot", "rx90", "--positions", str(files["positions"]), "--velocities",
                     str(files["velocities"]), "--torques", str(files["torques"]), "--period", str(PERIOD),
                     "--out", str(out)])
    assert code == 0 and out.read_bytes() == (tmp_path / "b.csv").read_bytes()


def test_repeated_rows_are_samples_with_a_period(rx90, run, tmp_path):
    """With the period's clock no row is stale: a robot at rest repeats rows, and each is a sample."""
    q, _, tau, _ = run
    q, tau = (np.insert(a, 100, np.repeat(a[99:100], 10, axis=0), axis=0) for a in (q, tau))  # 10 rows at rest
    rec = read_joint_files(rx90, {"positions": _write(tmp_path / "Q.csv", q),
                                  "torques": _write(tmp_path / "T.csv", tau)}, PERIOD)
    assert rec.n_samples == len(q) and rec.meta["log"]["stale_rows"] == 0


def test_currents_through_gains_and_a_negative_gain_warns(rx90, run, tmp_path, capsys):
    q, _, tau, cur = run
    files = {"positions": _write(tmp_path / "Q.csv", q), "currents": _write(tmp_path / "I.csv", cur)}
    rec = read_joint_files(rx90, files, PERIOD, gains=",".join(map(str, GAINS)))
    np.testing.assert_allclose(rec.tau, tau, rtol=1e-9, atol=1e-9)  # the twin's torques, from i = tau / k
    wrong = list(GAINS)
    wrong[1] = -wrong[1]
    with pytest.warns(RecordingWarning, match=r"joint 2: -0\.6"):
        read_joint_files(rx90, files, PERIOD, gains=",".join(map(str, wrong)))
    out = tmp_path / "rec.csv"
    with warnings.catch_warnings():
        warnings.simplefilter("always")  # the command prints warnings as lines (tests make them errors)
        code = cli.main(["convert", "--robot", "rx90", "--positions", str(files["positions"]), "--currents",
                         str(files["currents"]), "--gains=" + ",".join(map(str, wrong)), "--period", "0.01",
                         "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 0 and "negative drive gain (joint 2: -0.6 N·m/A)" in err, err


def _refused(args: list[str], out: Path, capsys) -> str:
    code = cli.main(["convert", "--robot", "rx90", *args, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert not out.exists()
    return err


def test_bad_input_exits_2_naming_file_line_and_column(rx90, run, tmp_path, capsys):
    q, _, tau, _ = run
    Q = _write(tmp_path / "Q.csv", q, "a,b,c,d,e,f")
    T = _write(tmp_path / "T.csv", tau)
    out = tmp_path / "rec.csv"
    both = ["--positions", str(Q), "--torques", str(T)]
    # Files of different lengths: both row counts and both files named.
    short = _write(tmp_path / "short.csv", tau[:-3])
    err = _refused(["--positions", str(Q), "--torques", str(short), "--period", "0.01"], out, capsys)
    assert f"Q.csv has {len(q)} rows, short.csv has {len(q) - 3} rows" in err and "mismatched lengths" in err
    # A period <= 0.
    for bad in ("0", "-0.01"):
        assert "--period must be a positive" in _refused([*both, "--period", bad], out, capsys)
    # A cell that is not a number: file, row, line and column (the header is line 1).
    lines = Q.read_text().splitlines()
    cells = lines[7].split(",")
    cells[3] = "n/a"
    lines[7] = ",".join(cells)
    bad = tmp_path / "Qbad.csv"
    bad.write_text("\n".join(lines) + "\n")
    err = _refused(["--positions", str(bad), "--torques", str(T), "--period", "0.01"], out, capsys)
    assert "Qbad.csv: column 'd', row 7 (line 8): cell 'n/a' is not a number" in err, err
    # A wrong column count (a time column left in): the count and the robot's joints named.
    wide = _write(tmp_path / "wide.csv", np.column_stack([np.arange(len(q)) * 0.01, q]))
    err = _refused(["--positions", str(wide), "--torques", str(T), "--period", "0.01"], out, capsys)
    assert "wide.csv (--positions): 7 columns, robot 'rx90' has 6 joints" in err, err
    # A row with a cell missing.
    lines = T.read_text().splitlines()
    lines[20] = ",".join(lines[20].split(",")[:-1])
    (tmp_path / "Tcut.csv").write_text("\n".join(lines) + "\n")
    err = _refused(["--positions", str(Q), "--torques", str(tmp_path / "Tcut.csv"), "--period", "0.01"], out, capsys)
    assert "Tcut.csv: row 21 (line 21) has 5 cells, the first row has 6 columns" in err, err
    # Options of other forms, gains without currents, no period.
    assert "--columns" in _refused([*both, "--period", "0.01", "--columns", "t,q1..q6"], out, capsys)
    assert "no --currents" in _refused([*both, "--period", "0.01", "--gains", "1,1,1,1,1,1"], out, capsys)
    assert "--period S" in _refused(both, out, capsys)


def test_the_checks_of_the_one_file_form_apply(rx90, run, tmp_path):
    q, dq, tau, _ = run
    T = _write(tmp_path / "T.csv", tau)
    degrees = _write(tmp_path / "Qdeg.csv", np.degrees(q))
    with pytest.raises(RecordingError, match="degree"):
        read_joint_files(rx90, {"positions": degrees, "torques": T}, PERIOD)
    swapped = dq[:, [1, 0, 2, 3, 4, 5]]
    with pytest.raises(RecordingError, match="are columns swapped"):
        read_joint_files(rx90, {"positions": _write(tmp_path / "Q.csv", q), "torques": T,
                                "velocities": _write(tmp_path / "V.csv", swapped)}, PERIOD)


def test_period_on_a_log_is_refused_with_a_time_column_or_a_clock_window(rx90, run, tmp_path):
    q, _, tau, _ = run
    log = _write(tmp_path / "log.csv", np.column_stack([np.arange(len(q)) * PERIOD, q, tau]))
    with pytest.raises(ValueError, match="no time column"):
        read_log(log, rx90, "t,q1..q6,tau1..tau6", period=PERIOD)
    with pytest.raises(ValueError, match="--rows"):
        read_log(log, rx90, "_,q1..q6,tau1..tau6", period=PERIOD, t_from=1.0)
    with pytest.raises(ValueError, match="positive"):
        read_log(log, rx90, "_,q1..q6,tau1..tau6", period=0.0)
    # A window by lines: t = 0 at its first row.
    rec = read_log(log, rx90, "_,q1..q6,tau1..tau6", period=PERIOD, rows=(51, 250))
    assert rec.t[0] == 0.0 and rec.n_samples == 200
    np.testing.assert_array_equal(rec.tau, tau[50:250])
