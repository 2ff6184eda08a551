"""Files as users have them: Windows line endings, torque columns counting the other way, a time
column that counts samples (identify.io.torque_signs, identify.io.units.sample_clock_refusal).

Each reader is checked against itself on the same data with Unix line endings; the signs against the
log read without them; the sample counter on logs whose clock is known (a 1 kHz log counted in
samples, a genuine 1 Hz log), and on the Kinova Gen3 log (../shared, skipped when absent).
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import rx90sym
import excitation
from identify.app.cli import main
from identify.io.blocks import block_source
from identify.io.joint_files import read_joint_files
from identify.io.log_blocks import convert_log, read_log
from identify.io.motor_files import read_motor_recording
from identify.io.recordings import read_recording
from rx90sym.recording import RecordingError

from conftest import SHARED

COLUMNS = "t,q1..q6,qd1..qd6,tau1..tau6"


@pytest.fixture(scope="module")
def tx40():
    return rx90sym.load_robot("tx40")


def _log(path: Path, rate: float, seconds: float, counter: bool = False, velocities: bool = True) -> Path:
    """A TX40 log (controller angles) of smooth motion at ``rate`` [Hz]: time in s, or sample numbers
    (``counter``); recorded velocities (the positions' derivative) unless ``velocities`` is False."""
    t = np.arange(int(round(seconds * rate))) / rate
    w = 2 * np.pi * np.array([0.3, 0.2, 0.25, 0.4, 0.35, 0.5]) * (1.0 if rate > 10 else 0.1)
    q = 0.4 * np.sin(np.outer(t, w)) + np.array([0.0, np.pi / 2, -np.pi / 2, 0.0, 0.0, 0.0])
    qd = 0.4 * w * np.cos(np.outer(t, w))
    tau = 20 * np.cos(np.outer(t, w)) + 5.0
    clock = np.arange(t.size, dtype=float) if counter else t
    cols = [clock[:, None], q] + ([qd] if velocities else []) + [tau]
    header = "t," + ",".join(f"q{j}" for j in range(1, 7)) + ("," + ",".join(f"qd{j}" for j in range(1, 7))
                                                              if velocities else "") + "," + ",".join(f"tau{j}" for j in range(1, 7))
    np.savetxt(path, np.hstack(cols), delimiter=",", header=header, comments="", fmt="%.10g")
    return path


def _crlf(src: Path, dst: Path) -> Path:
    dst.write_bytes(src.read_bytes().replace(b"\r\n", b"\n").replace(b"\n", b"\r\n"))
    assert b"\r\n" in dst.read_bytes()
    return dst


def _same(a, b) -> None:
    for name in ("t", "q", "tau", "dq", "current"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None) == (y is None), name
        if x is not None:
            np.testing.assert_array_equal(x, y, err_msg=name)


def test_windows_line_endings_read_like_any_other_by_every_reader(tmp_path, tx40):
    lf = _log(tmp_path / "log.csv", 250.0, 2.0)
    crlf = _crlf(lf, tmp_path / "log_crlf.csv")
    for kwargs in ({}, {"block": 100}):  # whole, and block by block
        _same(read_log(crlf, tx40, COLUMNS, header=True, **kwargs), read_log(lf, tx40, COLUMNS, header=True, **kwargs))
    convert_log(crlf, tx40, COLUMNS, tmp_path / "rec.csv", header=True, block=100)
    convert_log(lf, tx40, COLUMNS, tmp_path / "rec_lf.csv", header=True, block=100)
    assert (tmp_path / "rec.csv").read_bytes() == (tmp_path / "rec_lf.csv").read_bytes()
    # The recording reader, whole and in windows (a long file's block source).
    rec = _crlf(tmp_path / "rec_lf.csv", tmp_path / "rec_crlf.csv")
    _same(read_recording(rec, tx40), read_recording(tmp_path / "rec_lf.csv", tx40))
    spans = [(0, 200), (200, 500)]
    for a, b in zip(block_source(str(rec), tx40, None, None).windows(spans),
                    block_source(str(tmp_path / "rec_lf.csv"), tx40, None, None).windows(spans)):
        _same(a, b)
    # One file per signal (with a header), and the motor-side files.
    got = read_log(lf, tx40, COLUMNS, header=True)
    files = {}
    for name, values in (("positions", tx40.to_controller(got.q)), ("torques", got.tau)):
        plain = tmp_path / f"{name}.csv"
        np.savetxt(plain, values, delimiter=",", header=",".join(f"j{j}" for j in range(1, 7)), comments="")
        files[name] = _crlf(plain, tmp_path / f"{name}_crlf.csv")
    _same(read_joint_files(tx40, files, 0.004),
          read_joint_files(tx40, {k: tmp_path / f"{k}.csv" for k in files}, 0.004))
    data = rx90sym.datasets.tx40()
    motor = {}
    for key, src in (("pos", data.positions), ("tau", data.torques)):
        head = tmp_path / f"{key}.csv"
        head.write_text("".join(src.read_text().splitlines(keepends=True)[:400]))
        motor[key] = (head, _crlf(head, tmp_path / f"{key}_crlf.csv"))
    _same(read_motor_recording(motor["pos"][1], motor["tau"][1], tx40, period=data.period),
          read_motor_recording(motor["pos"][0], motor["tau"][0], tx40, period=data.period))
    # An excitation trajectory.
    traj = excitation.random_trajectory(tx40, 2.0, 3, seed=1)
    traj.save(tmp_path / "traj.csv", rate=100.0)
    for x, y in zip(excitation.read_trajectory(_crlf(tmp_path / "traj.csv", tmp_path / "traj_crlf.csv"), tx40),
                    excitation.read_trajectory(tmp_path / "traj.csv", tx40)):
        np.testing.assert_array_equal(x, y)


def test_torque_signs_negate_the_joints_given_in_every_form(tmp_path, tx40, capsys):
    log = _log(tmp_path / "log.csv", 250.0, 2.0)
    signs = (1, -1, 1, 1, 1, -1)
    plain = read_log(log, tx40, COLUMNS, header=True)
    signed = read_log(log, tx40, COLUMNS, header=True, torque_signs="1,-1,1,1,1,-1")
    np.testing.assert_array_equal(signed.tau, plain.tau * np.array(signs))
    np.testing.assert_array_equal(signed.q, plain.q)
    assert signed.meta["log"]["torque_signs"] == [1.0, -1.0, 1.0, 1.0, 1.0, -1.0]
    # Currents: negated before the drive gains, so the torques come out negated too.
    currents = read_log(log, tx40, COLUMNS.replace("tau", "i"), header=True, gains="2,2,2,2,2,2", torque_signs=signs)
    np.testing.assert_array_equal(currents.tau, 2.0 * plain.tau * np.array(signs))
    # The command, in the log and joint files forms.
    out = tmp_path / "rec.csv"
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        code = main(["convert", str(log), "--robot", "tx40", "--columns", COLUMNS, "--torque-signs", "1,-1,1,1,1,-1",
                     "--out", str(out)])
    assert code == 0 and "torque signs 1,-1,1,1,1,-1" in capsys.readouterr().out
    np.testing.assert_allclose(read_recording(out, tx40).tau, signed.tau, rtol=0, atol=0)
    np.savetxt(tmp_path / "q.csv", tx40.to_controller(plain.q), delimiter=",")
    np.savetxt(tmp_path / "t.csv", plain.tau, delimiter=",")
    files = read_joint_files(tx40, {"positions": tmp_path / "q.csv", "torques": tmp_path / "t.csv"}, 0.004,
                             torque_signs=signs)
    np.testing.assert_array_equal(files.tau, plain.tau * np.array(signs))
    # Bad signs: exit 2 naming the count or every bad value, nothing written.
    for given, needle in (("1,-1,1", "3 sign(s) given for the 6 joints of robot 'tx40'"),
                          ("1,0,1,x,1,2", "joint 2's sign 0, joint 4's sign 'x', joint 6's sign 2 are not 1 or -1")):
        bad = tmp_path / "bad.csv"
        code = main(["convert", str(log), "--robot", "tx40", "--columns", COLUMNS, "--torque-signs", given,
                     "--out", str(bad)])
        err = capsys.readouterr().err
        assert code == 2 and not bad.exists() and f"--torque-signs: {needle}" in err, err
    with pytest.raises(ValueError, match="torque_signs: 2 sign"):
        read_log(log, tx40, COLUMNS, header=True, torque_signs=(1, 1))


def test_a_time_column_that_counts_samples_is_named_with_the_fix(tmp_path, tx40, capsys):
    counted = _log(tmp_path / "counted.csv", 1000.0, 1.0, counter=True)
    with pytest.raises(RecordingError, match=r"the time column \(column 1, t\) counts samples \(or milliseconds\), "
                                             r"not seconds: whole numbers \(0, 1, 2, ...\).* the recorded velocities "
                                             r"say the rows are 0.001 s apart; map the column as _ and give the "
                                             r"sampling period with --period S .*e.g. --period 0.001"):
        read_log(counted, tx40, COLUMNS, header=True)
    # A clock in milliseconds at 500 Hz: steps of 2.
    ms = tmp_path / "ms.csv"
    seconds = _log(tmp_path / "ms_s.csv", 500.0, 1.0)
    table = np.loadtxt(seconds, delimiter=",", skiprows=1)
    table[:, 0] = np.round(table[:, 0] * 1000.0)
    np.savetxt(ms, table, delimiter=",", header=seconds.read_text().splitlines()[0], comments="", fmt="%.10g")
    with pytest.raises(RecordingError, match=r"in steps of 2 \(read as seconds: a rate of 0.5 Hz\).*rows are "
                                             r"0.002 s apart.*e.g. --period 0.002"):
        read_log(ms, tx40, COLUMNS, header=True)
    bare = _log(tmp_path / "bare.csv", 1000.0, 1.0, counter=True, velocities=False)
    cols = "t,q1..q6,tau1..tau6"
    with pytest.raises(RecordingError, match=r"counts samples.*read in seconds the arm would move at 0.\d+ % of "
                                             r"its velocity limits or less \(95 % of the rows\); map the column as _"):
        read_log(bare, tx40, cols, header=True)
    # The fix: the column ignored and the period given.
    fixed = read_log(counted, tx40, "_" + COLUMNS[1:], header=True, period=0.001)
    assert fixed.meta["log"]["rate_hz"] == pytest.approx(1000.0)
    # A genuine 1 Hz log (time in s, the arm moving at a few % of its limits per row) is read as it is.
    slow = read_log(_log(tmp_path / "slow.csv", 1.0, 120.0), tx40, COLUMNS, header=True)
    assert slow.meta["log"]["rate_hz"] == pytest.approx(1.0)
    slow = read_log(_log(tmp_path / "slow_bare.csv", 1.0, 120.0, velocities=False), tx40, cols, header=True)
    assert slow.meta["log"]["rate_hz"] == pytest.approx(1.0)
    # The command: exit 2, the column and the fix named, nothing written.
    out = tmp_path / "rec.csv"
    code = main(["convert", str(counted), "--robot", "tx40", "--columns", COLUMNS, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and not out.exists() and "counts samples" in err and "--period S" in err


def test_a_counted_clock_is_retimed_from_the_motion(tmp_path, tx40):
    """A 1 kHz log counted in samples whose logger lost cycles and logged others twice (as the Gen3's):
    with --period, the rows repeated are dropped and those after a loss moved by the cycles lost
    (identify.io.gaps.sample_periods), so the positions sit at their true times; read by the count,
    they lag behind by every cycle lost."""
    seconds = _log(tmp_path / "true.csv", 1000.0, 2.0)
    table = np.loadtxt(seconds, delimiter=",", skiprows=1)
    rng = np.random.default_rng(3)
    lost = np.sort(rng.choice(np.arange(50, table.shape[0] - 50), 12, replace=False))
    twice = np.sort(rng.choice(np.setdiff1d(np.arange(50, table.shape[0] - 50), lost), 7, replace=False))
    rows = np.repeat(np.arange(table.shape[0]), np.where(np.isin(np.arange(table.shape[0]), twice), 2, 1))
    logged = table[rows[~np.isin(rows, lost)]]
    logged[:, 0] = np.arange(logged.shape[0])  # the counter
    path = tmp_path / "counted.csv"
    np.savetxt(path, logged, delimiter=",", header=seconds.read_text().splitlines()[0], comments="", fmt="%.10g")
    rec = read_log(path, tx40, "_" + COLUMNS[1:], header=True, period=0.001)
    log = rec.meta["log"]
    assert log["lost_cycles"] == lost.size and log["stale_rows"] == twice.size, log
    def truth(t):  # the controller angles of _log's motion
        w = 2 * np.pi * np.array([0.3, 0.2, 0.25, 0.4, 0.35, 0.5])
        return 0.4 * np.sin(np.outer(t, w)) + np.array([0.0, np.pi / 2, -np.pi / 2, 0.0, 0.0, 0.0])

    retimed = np.abs(tx40.to_controller(rec.q) - truth(rec.t)).max()
    counted = np.abs(logged[:, 1:7] - truth(logged[:, 0] / 1000.0)).max()
    assert retimed < 1e-6 and counted > 1e3 * retimed, (retimed, counted)


GEN3_LOG = SHARED / "data" / "kinova_gen3" / "RunTrajectory1.csv"
GEN3 = Path(__file__).resolve().parent / "data" / "kinova_gen3" / "gen3.urdf"


def test_the_gen3_log_counted_in_samples_is_refused_and_reads_with_its_period(tmp_path, capsys):
    if not GEN3_LOG.exists():
        pytest.skip(f"Gen3 logs not found in {GEN3_LOG.parent} (../shared is absent)")
    spec = "t,q1..q7,qd1..qd7,_*7,tau1..tau7,_*7,_*7,_*7,_*28"
    out = tmp_path / "run1.csv"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the URDF's own warnings (test_description_prior)
        code = main(["convert", str(GEN3_LOG), "--robot", str(GEN3), "--rows", "1:400", "--columns", spec,
                     "--out", str(out)])
        err = capsys.readouterr().err
        assert code == 2 and not out.exists(), err
        assert "the time column (column 1, t) counts samples" in err and "e.g. --period 0.001" in err
        code = main(["convert", str(GEN3_LOG), "--robot", str(GEN3), "--rows", "1:400", "--columns", "_" + spec[1:],
                     "--period", "0.001", "--out", str(out)])
    assert code == 0 and "rate 1000 Hz" in capsys.readouterr().out
