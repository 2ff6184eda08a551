"""Controller logs (identify.read_log, rx90 convert LOG.csv): column maps, corrupt rows named by
line number, windows, the 1 % time rule, resampling against an analytic motion, drive gains, and
the real UR10e logs (read in place from ../shared, skipped when absent: they carry no licence)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import rx90sym
from conftest import SHARED
from identify import read_log, read_recording
from identify.app import cli
from identify import parse_columns
from identify.io.recordings import RecordingWarning
from rx90sym.recording import RecordingError

UR_DATA = SHARED / "data" / "ur10e"
needs_ur = pytest.mark.skipif(not (UR_DATA / "ur-20_02_19_14harm50sec.csv").exists(),
                              reason=f"UR10e logs not found in {UR_DATA} (../shared is absent)")
UR_COLUMNS = "t,q1..q6,qd1..qd6,i1..i6,x:i_target1..x:i_target6,x:tau_target1..x:tau_target6"
UR_GAINS = (10.0, 10.70, 8.46, 9.00, 9.48, 10.12)  # N·m/A, README (the source repository's estimates)
COLUMNS = "t,q1..q6,qd1..qd6,i1..i6,x:extra"
AMPLITUDE, OMEGA = 0.8, 2 * np.pi * 0.4  # rad, rad/s of the analytic test motion


def ur10e_robot() -> rx90sym.Robot:
    """UR10e from the README: standard DH rewritten as Khalil's modified DH (frame j takes alpha
    and a of standard row j-1), limits +-360 deg, 120/180 deg/s, rated torques."""
    pi = np.pi
    table = [(0, 0.0, 0.0, 0.0, 0.1807), (0, pi / 2, 0.0, 0.0, 0.0), (0, 0.0, -0.6127, 0.0, 0.0),
             (0, 0.0, -0.57155, 0.0, 0.17415), (0, pi / 2, 0.0, 0.0, 0.11985), (0, -pi / 2, 0.0, 0.0, 0.11655)]
    inf = np.full(6, np.inf)
    limits = rx90sym.Limits(np.full(6, -2 * pi), np.full(6, 2 * pi),
                            np.radians([120.0, 120, 180, 180, 180, 180]), inf, np.array([330.0, 330, 150, 56, 56, 56]))
    return rx90sym.robot_from_table(table, name="ur10e", limits=limits)


@pytest.fixture(scope="module")
def ur():
    return ur10e_robot()


def analytic(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q, qd (rad, rad/s) and a current (A) of a smooth motion, per joint phase-shifted."""
    phase = np.arange(6)[None, :] * 0.7
    arg = OMEGA * t[:, None] + phase
    return AMPLITUDE * np.sin(arg), AMPLITUDE * OMEGA * np.cos(arg), 2.0 * np.cos(arg)


def jittered_times(n: int, seed: int) -> np.ndarray:
    """Time stamps like the UR10e logs: steps of 8-12 ms, starting at 838 s."""
    rng = np.random.default_rng(seed)
    return 838.0 + np.concatenate([[0.0], np.cumsum(rng.uniform(0.008, 0.012, n - 1))])


def log_lines(t: np.ndarray, fmt: str = "%.17g") -> list[str]:
    q, qd, i = analytic(t)
    table = np.column_stack([t, q, qd, i, np.zeros_like(t)])
    return [",".join(fmt % v for v in row) for row in table]


def write_log(path: Path, lines: list[str], ending: str = "\n") -> Path:
    path.write_text("\n".join(lines) + ending, encoding="utf-8")
    return path


def regular_log(tmp_path: Path, n: int = 200, step: float = 0.01) -> tuple[Path, list[str]]:
    lines = log_lines(838.0 + step * np.arange(n))
    return write_log(tmp_path / "log.csv", lines), lines


def convert(args: list[str], capsys) -> tuple[int, str, str]:
    code = cli.main(["convert", *args])
    out, err = capsys.readouterr()
    return code, out, err


# --------------------------------------------------------------------------------------------
# Column maps
# --------------------------------------------------------------------------------------------


def test_ranges_and_explicit_lists_are_the_same_map(ur):
    explicit = "t," + ",".join(f"q{j}" for j in range(1, 7)) + ",_,_,_," + ",".join(f"i{j}" for j in range(1, 7))
    a, b = parse_columns(explicit, ur), parse_columns("t,q1..q6,_*3,i1..i6", ur)
    assert a == b and a.q == tuple(range(1, 7)) and a.i == tuple(range(10, 16)) and a.qd == ()


@pytest.mark.parametrize("spec, needle", [
    ("t,q1..q7,i1..i6", "'q7': robot 'ur10e' has 6 joints"),
    ("t,q1..q6,qd1..qd5,i1..i6", "'qd6' is missing"),
    ("t,q1..q6", "neither joint torques"),
    ("q1..q6,i1..i6", "no time column"),
    ("t,q1..q6,i1..i6,speed", "'speed' is unknown"),
    ("t,q1..q6,i1..i6,x:a,x:a", "'a' appears twice"),
    ("t,q1..q6,i6..i1", "range 'i6..i1'"),
])
def test_bad_column_maps_are_refused(ur, spec, needle):
    with pytest.raises(ValueError, match=needle.replace("(", r"\(").replace(".", r"\.")):
        parse_columns(spec, ur)


# --------------------------------------------------------------------------------------------
# Every bad-input class through the command line: exit 2, the line named, nothing written
# --------------------------------------------------------------------------------------------


def _set(lines: list[str], line: int, column: int, text) -> None:
    """Put ``text`` (or ``text(old cell)``) in 1-based ``column`` of 1-based ``line``."""
    cells = lines[line - 1].split(",")
    cells[column - 1] = text(cells[column - 1]) if callable(text) else text
    lines[line - 1] = ",".join(cells)


def _corrupt(kind: str, lines: list[str]) -> tuple[list[str], str, str]:
    """(lines, ending, text the message must contain) for one class of bad input."""
    lines = list(lines)
    if kind == "corrupt head":  # the UR logging artefact: short rows, time back and forth, 1e154
        lines[0] = ",".join(lines[0].split(",")[:12])
        _set(lines, 2, 4, "1e154")
        _set(lines, 3, 1, "900.5")
        return lines, "\n", "line 1: 12 cells, the column map names 20; line 2: column 4 ('q3'): value 1e+154"
    if kind == "truncated last line":
        return lines[:-1] + [lines[-1][:25]], "", f"line {len(lines)}: "
    if kind == "wrong column count":
        lines[99] += ",0.5"
        return lines, "\n", "line 100: 21 cells, the column map names 20"
    if kind == "text":
        _set(lines, 50, 4, "n/a")
        return lines, "\n", "line 50: column 4 ('q3'): 'n/a' is not a number"
    if kind == "time going back":
        _set(lines, 121, 1, lambda t: repr(float(t) - 0.05))
        return lines, "\n", "line 121: time"
    if kind == "gap":
        del lines[60:70]  # 11 steps of 10 ms missing at once
        return lines, "\n", "line 60: gap of 0.11 s to line 61"
    if kind == "absurd value":
        _set(lines, 31, 15, "-3e154")
        return lines, "\n", "line 31: column 15 ('i2'): value -3e+154 is absurdly large"
    if kind == "beyond the limits":
        _set(lines, 11, 3, "9.5")
        return lines, "\n", "line 11: column 3 ('q2'): 9.5 rad"
    if kind == "jump":
        _set(lines, 11, 3, lambda q: repr(float(q) + 0.5))
        return lines, "\n", "line 11: joint 2 jumps"
    if kind == "semicolons":
        return [line.replace(",", ";") for line in lines], "\n", "seems to use ';' as separator"
    raise AssertionError(kind)


BAD = ["corrupt head", "truncated last line", "wrong column count", "text", "time going back", "gap",
       "absurd value", "beyond the limits", "jump", "semicolons"]


@pytest.mark.parametrize("kind", BAD)
def test_every_bad_input_class_exits_2_naming_the_line(tmp_path, capsys, kind):
    _, lines = regular_log(tmp_path)
    bad, ending, needle = _corrupt(kind, lines)
    path = write_log(tmp_path / "bad.csv", bad, ending)
    out = tmp_path / "rec.csv"
    # A gap longer than --max-gap is an error only when segments are refused.
    extra = ["--no-segments"] if kind == "gap" else []
    code, _, err = convert([str(path), "--robot", str(ur10e_toml(tmp_path)), "--columns", COLUMNS,
                            "--no-header", "--out", str(out), *extra], capsys)
    message = err.strip().splitlines()[-1]
    assert code == 2 and needle in message and "bad.csv" in message, err
    assert "np.float64" not in message
    assert {p.name for p in tmp_path.iterdir()} == {"log.csv", "bad.csv", "ur10e.toml"}  # nothing written


def test_a_window_after_the_corrupt_head_reads_clean(tmp_path, ur):
    _, lines = regular_log(tmp_path)
    bad, _, _ = _corrupt("corrupt head", lines)
    path = write_log(tmp_path / "bad.csv", bad)
    rec = read_log(path, ur, COLUMNS, rows=(4, len(bad)))
    assert rec.meta["log"]["lines"] == [4, len(bad)] and rec.n_samples == len(bad) - 3
    clock = rec.t + rec.meta["log"]["t0_s"]  # the recording starts at 0 s; the log's clock kept
    np.testing.assert_allclose(rec.q, analytic(clock)[0], atol=1e-12)


def test_the_window_is_the_only_part_checked(tmp_path, ur):
    _, lines = regular_log(tmp_path)
    bad, _, _ = _corrupt("gap", lines)
    path = write_log(tmp_path / "bad.csv", bad)
    with pytest.raises(RecordingError, match="line 60: gap"):
        read_log(path, ur, COLUMNS, t_to=float(bad[100].split(",")[0]), segments=False)
    rec = read_log(path, ur, COLUMNS, t_to=float(bad[58].split(",")[0]))
    assert rec.meta["log"]["lines"] == [1, 59]
    rec = read_log(path, ur, COLUMNS, t_from=float(bad[60].split(",")[0]) - 1e-9)
    assert rec.meta["log"]["lines"] == [61, len(bad)] and rec.t[0] == 0.0
    assert rec.meta["log"]["t0_s"] == float(bad[60].split(",")[0])  # the log's clock at the first sample


def test_line_numbers_count_comments_and_the_header(tmp_path, ur):
    _, lines = regular_log(tmp_path)
    header = ",".join(parse_columns(COLUMNS, ur).names).replace("x:", "")
    bad, _, _ = _corrupt("text", lines)  # data row 50
    path = write_log(tmp_path / "h.csv", ["# logged by the controller", header] + bad)
    with pytest.raises(RecordingError, match="line 52: column 4"):
        read_log(path, ur, COLUMNS, header=True)
    rec = read_log(path, ur, COLUMNS, header=True, rows=(1, 51))  # the comment and header are no rows
    assert rec.meta["log"]["lines"] == [3, 51] and rec.n_samples == 49
    np.testing.assert_allclose(rec.t + rec.meta["log"]["t0_s"], [float(line.split(",")[0]) for line in lines[:49]],
                               rtol=0, atol=1e-9)


def test_column_the_robot_does_not_have_exits_2(tmp_path, capsys):
    path, _ = regular_log(tmp_path)
    out = tmp_path / "rec.csv"
    code, _, err = convert([str(path), "--robot", str(ur10e_toml(tmp_path)), "--columns", "t,q1..q7,_*5,i1..i6,_",
                            "--no-header", "--out", str(out)], capsys)
    assert code == 2 and "'q7': robot 'ur10e' has 6 joints" in err and not out.exists()


def test_currents_without_gains_are_refused_at_identify_time_with_the_hint(tmp_path, capsys):
    path, _ = regular_log(tmp_path, n=400)
    robot_file = str(ur10e_toml(tmp_path))
    rec = tmp_path / "rec.csv"
    code, out, _ = convert([str(path), "--robot", robot_file, "--columns", COLUMNS, "--no-header",
                            "--out", str(rec)], capsys)
    assert code == 0 and "no gains: the file keeps currents" in out
    assert read_recording(rec, ur10e_robot()).tau is None
    code = cli.main(["identify", str(rec), "--robot", robot_file])
    err = capsys.readouterr().err
    assert code == 2 and "motor currents" in err and "--gains" in err, err


def test_options_of_the_other_form_are_usage_errors(tmp_path, capsys):
    path, _ = regular_log(tmp_path)
    out = str(tmp_path / "rec.csv")
    code, _, err = convert([str(path), "--robot", str(ur10e_toml(tmp_path)), "--columns", COLUMNS, "--no-header",
                            "--period", "0.01", "--out", out], capsys)
    assert code == 2 and "a log read with a sampling period (--period" in err and "map the column as _" in err
    code, _, err = convert([str(path), "--columns", COLUMNS, "--motor-torques", "t.csv", "--out", out], capsys)
    assert code == 2 and "--motor-torques belongs to the motor form, not to a LOG.csv" in err
    code, _, err = convert(["--motor-positions", "p.csv", "--motor-torques", "t.csv", "--period", "0.01",
                            "--resample", "100", "--out", out], capsys)
    assert code == 2 and "--resample belongs to the log form" in err
    code, _, err = convert([str(path), "--robot", str(ur10e_toml(tmp_path)), "--columns", COLUMNS,
                            "--rows", "2:50", "--from", "838", "--out", out], capsys)
    assert code == 2 and "not both" in err and not Path(out).exists()
    code, _, err = convert([str(path), "--robot", str(ur10e_toml(tmp_path)), "--columns", COLUMNS,
                            "--no-header", "--resample", "-100", "--out", out], capsys)
    assert code == 2 and "expected a positive rate in Hz, got -100" in err and not Path(out).exists()


def test_the_rx90_script_exits_2_with_one_line(tmp_path):
    path, lines = regular_log(tmp_path)
    bad, ending, needle = _corrupt("time going back", lines)
    write_log(path, bad, ending)
    out = tmp_path / "rec.csv"
    proc = subprocess.run([str(Path(sys.executable).parent / "rx90"), "convert", str(path), "--robot",
                           str(ur10e_toml(tmp_path)), "--columns", COLUMNS, "--no-header", "--out", str(out)],
                          capture_output=True, text=True)
    lines_err = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and needle in lines_err[-1] and len(lines_err) == 3 and "robot" in lines_err[0] and not out.exists()


# --------------------------------------------------------------------------------------------
# Time rule and resampling
# --------------------------------------------------------------------------------------------


def test_irregular_steps_are_refused_with_the_figures(tmp_path, ur):
    path = write_log(tmp_path / "log.csv", log_lines(jittered_times(300, seed=1)))
    with pytest.raises(RecordingError, match=r"irregular time steps: \d+ of 299 steps .* resample"):
        read_log(path, ur, COLUMNS)


def test_steps_within_one_percent_are_regular(tmp_path, ur):
    rng = np.random.default_rng(3)
    t = 838.0 + 0.01 * (np.arange(300) + rng.uniform(-0.004, 0.004, 300))  # at most 0.8 % off
    rec = read_log(write_log(tmp_path / "log.csv", log_lines(t)), ur, COLUMNS)
    assert rec.meta["log"]["resampled_hz"] is None and rec.meta["log"]["irregular_steps"] == 0
    assert rec.rate == pytest.approx(299 / (t[-1] - t[0]), rel=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_resampling_follows_the_analytic_motion(tmp_path, ur, seed):
    """Cubic Hermite with the recorded velocities: |q - q_true| <= h^4/384 max|q''''| (the
    interpolation bound), currents linearly: <= h^2/8 max|i''|; h the largest step."""
    t = jittered_times(600, seed)
    rec = read_log(write_log(tmp_path / "log.csv", log_lines(t)), ur, COLUMNS, resample=100.0)
    h = float(np.max(np.diff(t)))
    clock = rec.t + rec.meta["log"]["t0_s"]  # the recording starts at 0 s; the log's clock kept
    q_true, qd_true, i_true = analytic(clock)
    assert np.allclose(np.diff(rec.t), 0.01, rtol=0, atol=1e-9) and rec.t[0] == 0 and clock[0] == t[0] and clock[-1] <= t[-1] + 1e-9
    assert np.max(np.abs(rec.q - q_true)) <= h ** 4 / 384 * AMPLITUDE * OMEGA ** 4 * 1.001
    assert np.max(np.abs(rec.current - i_true)) <= h ** 2 / 8 * 2.0 * OMEGA ** 2 * 1.001
    assert np.max(np.abs(rec.dq - qd_true)) <= h ** 2 / 8 * AMPLITUDE * OMEGA ** 3 * 1.001
    # Without the recorded velocities, the spline through the positions alone is less exact.
    no_qd = read_log(tmp_path / "log.csv", ur, "t,q1..q6,_*6,i1..i6,x:extra", resample=100.0)
    assert no_qd.dq is None and np.max(np.abs(no_qd.q - q_true)) > np.max(np.abs(rec.q - q_true))
    assert rec.meta["log"]["largest_gap_s"] == pytest.approx(h, abs=1e-12)


def test_gains_turn_currents_into_torques(tmp_path, ur):
    path, _ = regular_log(tmp_path)
    rec = read_log(path, ur, COLUMNS, gains="1,2,3,4,5,6")
    np.testing.assert_allclose(rec.tau, rec.current * np.arange(1, 7), rtol=1e-15)
    assert rec.meta["log"]["gains"].startswith("1,2,3,4,5,6")
    with pytest.raises(ValueError, match="no motor currents"):
        read_log(path, ur, "t,q1..q6,_*6,tau1..tau6,_", gains="1,2,3,4,5,6")


def test_controller_angles_are_converted_once(tmp_path, rx90):
    """An RX90 log holds the Stäubli angles: q_model = q_controller - offsets."""
    t = 0.004 * np.arange(100)
    centre = 0.5 * (rx90.limits.q_min + rx90.limits.q_max)
    q_model = centre + 0.3 * np.sin(t[:, None] + np.arange(6))
    tau = 1.0 + 0.1 * np.cos(t[:, None] + np.arange(6))  # live torques (one value on every row: a warning)
    rows = np.column_stack([t, rx90.to_controller(q_model), tau])
    path = write_log(tmp_path / "rx.csv", [",".join(repr(float(v)) for v in r) for r in rows])
    np.testing.assert_allclose(read_log(path, rx90, "t,q1..q6,tau1..tau6").q, q_model, atol=1e-15)
    model = read_log(path, rx90, "t,q1..q6,tau1..tau6", convention="model")
    np.testing.assert_allclose(model.q, rx90.to_controller(q_model), atol=1e-15)


# --------------------------------------------------------------------------------------------
# The real UR10e logs
# --------------------------------------------------------------------------------------------


@needs_ur
def test_real_ur10e_log_window_rate_gap_and_torques(ur):
    path = UR_DATA / "ur-20_02_19_14harm50sec.csv"
    raw = np.loadtxt(path, delimiter=",")[194:4966]  # lines 195..4966, read independently
    with pytest.raises(RecordingError, match="irregular time steps"):
        read_log(path, ur, UR_COLUMNS, rows=(195, 4966))
    rec = read_log(path, ur, UR_COLUMNS, rows=(195, 4966), resample=100.0, gains=",".join(map(str, UR_GAINS)))
    log = rec.meta["log"]
    dt = np.diff(raw[:, 0])
    assert log["lines"] == [195, 4966] and log["rows"] == 4772
    assert log["rate_hz"] == pytest.approx(1 / dt.mean(), rel=1e-12)
    assert log["largest_gap_s"] == pytest.approx(dt.max(), abs=1e-12) and dt.max() < 1.5 * 0.01
    assert rec.t[0] == 0 and rec.meta["log"]["t0_s"] == raw[0, 0] and np.allclose(np.diff(rec.t), 0.01, atol=1e-9)
    clock = rec.t + raw[0, 0]
    # Positions at the log's own samples: within the log's 4-decimal rounding of the grid's
    # Hermite interpolant (checked at the grid points that coincide with a log sample).
    common, i_rec, i_raw = np.intersect1d(np.round(clock, 6), np.round(raw[:, 0], 6), return_indices=True)
    assert common.size > 500
    np.testing.assert_allclose(rec.q[i_rec], raw[i_raw, 1:7], atol=1e-9)
    # Torques: the README's gains times the currents, interpolated here from the raw columns.
    current = np.column_stack([np.interp(clock, raw[:, 0], raw[:, 13 + j]) for j in range(6)])
    np.testing.assert_allclose(rec.tau, current * UR_GAINS, rtol=1e-12, atol=1e-9)  # clock rebuilt from t + t0_s
    # Physical sanity: on the gravity-loaded joints 2 and 3 they follow the controller's own model
    # torque (tau_target, its internal model, not a measurement): correlation 0.965 and 0.933.
    for j in (1, 2):
        assert np.corrcoef(rec.tau[:, j], rec.aux[f"tau_target{j + 1}"])[0, 1] > 0.9


@needs_ur
def test_real_ur10e_logs_through_the_command_line(tmp_path, capsys):
    out = tmp_path / "empty.csv"
    code, stdout, err = convert([str(UR_DATA / "ur-20_02_19_14harm50sec.csv"), "--robot", str(ur10e_toml(tmp_path)),
                                 "--columns", UR_COLUMNS, "--no-header", "--rows", "195:4966", "--resample", "100",
                                 "--out", str(out)], capsys)
    assert code == 0, err
    assert "read lines 195..4966" in stdout and "4772 rows" in stdout and "resampled to 100 Hz" in stdout
    back = read_recording(out, ur10e_robot())
    assert back.current is not None and back.dq is not None and back.tau is None and len(back.aux) == 12


def ur10e_toml(folder: Path) -> Path:
    """The test robot as a robot file (the CLI takes a path); same table and limits."""
    path = folder / "ur10e.toml"
    if path.exists():
        return path
    joints = [(0.0, 0.0, 0.1807), (90.0, 0.0, 0.0), (0.0, -0.6127, 0.0), (0.0, -0.57155, 0.17415),
              (90.0, 0.0, 0.11985), (-90.0, 0.0, 0.11655)]
    text = 'name = "ur10e"\n' + "".join(
        f"\n[[joints]]\nsigma = 0\nalpha_deg = {a}\nd = {d}\ntheta_deg = 0.0\nr = {r}\n" for a, d, r in joints)
    text += ("\n[limits]\nposition_min_deg = [-360.0, -360.0, -360.0, -360.0, -360.0, -360.0]\n"
             "position_max_deg = [360.0, 360.0, 360.0, 360.0, 360.0, 360.0]\n"
             "velocity_deg_s = [120.0, 120.0, 180.0, 180.0, 180.0, 180.0]\n"
             "torque = [330.0, 330.0, 150.0, 56.0, 56.0, 56.0]\n")
    path.write_text(text, encoding="utf-8")
    return path


def test_the_robot_file_and_the_table_agree(tmp_path, ur):
    from_file = rx90sym.load_robot(ur10e_toml(tmp_path))
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, 6)
    np.testing.assert_allclose(np.array(from_file.forward_kinematics(q)[0]),
                               np.array(ur.forward_kinematics(q)[0]), atol=1e-12)
    np.testing.assert_allclose(from_file.limits.qd_max, ur.limits.qd_max)


def test_a_column_map_that_does_not_fit_any_row_is_named_as_such(tmp_path, ur):
    """Not 200 corrupt rows and a hint to select a window: the map is wrong."""
    path, _ = regular_log(tmp_path)
    with pytest.raises(RecordingError, match=r"log.csv: every row of lines 1..200 has 20 cells, the column map "
                                             r"names 21; fix the column map \(--columns"):
        read_log(path, ur, COLUMNS + ",_")


def log_with_velocities(path: Path, velocity) -> Path:
    """The analytic 100 Hz log with its velocity columns replaced by ``velocity(qd)``."""
    t = 838.0 + 0.01 * np.arange(200)
    q, qd, i = analytic(t)
    rows = np.column_stack([t, q, velocity(qd), i, np.zeros_like(t)])
    return write_log(path, [",".join(repr(float(v)) for v in r) for r in rows])


def test_a_velocity_column_of_zeros_under_motion_is_refused(tmp_path, ur):
    path = log_with_velocities(tmp_path / "z.csv", np.zeros_like)
    with pytest.raises(RecordingError, match=r"column 8 \('qd1'\) is 0 on every row of lines 1..200 while joint 1 moves"):
        read_log(path, ur, COLUMNS)


def test_velocity_columns_that_are_not_the_derivative_of_their_positions_are_refused(tmp_path, ur):
    """Swapped qd1/qd2 (phases 0.7 rad apart: 68 % RMS difference) and qd in deg/s (5630 %) are
    refused naming the column; the right map passes (the derivative matches to < 1 %)."""
    path, _ = regular_log(tmp_path)
    assert read_log(path, ur, COLUMNS).dq is not None
    swapped = COLUMNS.replace("qd1..qd6", "qd2,qd1,qd3..qd6")
    with pytest.raises(RecordingError, match=r"column 9 \('qd1'\) is not the velocity of column 2 \('q1'\): "
                                             r"RMS difference .* 68% .*it matches the derivative of q2 \(0%\)"):
        read_log(path, ur, swapped)
    degrees = log_with_velocities(tmp_path / "deg.csv", np.degrees)
    with pytest.raises(RecordingError, match=r"column 8 \('qd1'\) is not the velocity .*the unit \(rad/s\)"):
        read_log(degrees, ur, COLUMNS)


@needs_ur
def test_real_ur10e_velocities_match_their_positions_well_inside_the_tolerance(ur):
    """The margin of the rule on real data: 1.4-1.8 % RMS difference on every joint of both
    excitation runs, against the 50 % tolerance."""
    from identify.io.logs import VELOCITY_MISMATCH
    for name in ("ur-20_02_19_14harm50sec.csv", "ur-20_02_19_14harm50secLoad.csv"):
        raw = np.loadtxt(UR_DATA / name, delimiter=",", max_rows=5000)[150:]
        derivative = np.gradient(raw[:, 1:7], raw[:, 0], axis=0)
        off = np.sqrt(np.mean((raw[:, 7:13] - derivative) ** 2, 0) / np.mean(derivative ** 2, 0))
        assert np.all(off < 0.1 * VELOCITY_MISMATCH), off


@needs_ur
def test_the_p4_validation_log_holds_no_motion(ur):
    """ur-20_01_17-p4.csv (README: 'point-to-point motion with stops') is at rest throughout:
    every joint spans 1e-4 rad (one unit of its 4th decimal) and every qd is 0."""
    with pytest.warns(RecordingWarning, match=r"no joint moves in lines 1..896 \(largest position span 0.0001"):
        rec = read_log(UR_DATA / "ur-20_01_17-p4.csv", ur, UR_COLUMNS, resample=100.0)
    assert max(rec.meta["log"]["position_span_rad"]) < 2e-4


def test_windows_line_endings_keep_the_line_numbers(tmp_path, ur):
    _, lines = regular_log(tmp_path)
    bad, _, needle = _corrupt("text", lines)
    path = tmp_path / "crlf.csv"
    path.write_bytes(("\r\n".join(bad) + "\r\n").encode())
    with pytest.raises(RecordingError, match=needle.replace("(", r"\(").replace(")", r"\)")):
        read_log(path, ur, COLUMNS)
    assert read_log(path, ur, COLUMNS, rows=(1, 49)).n_samples == 49


def test_the_reader_gives_the_same_recording_whatever_its_block(tmp_path, ur):
    """One reader for every length: a log read 7 lines at a time equals the log read in one block, with a
    time window, with lost packets resampled, and without time column (a sampling period)."""
    t = jittered_times(300, seed=3)
    t = np.delete(t, np.r_[100:104])  # a lost burst: bridged by the resampling
    lines = log_lines(t)
    path = write_log(tmp_path / "log.csv", lines)
    regular = log_lines(838.0 + 0.01 * np.arange(300))
    nameless = write_log(tmp_path / "nameless.csv", [line.split(",", 1)[1] for line in regular])
    cases = [(path, COLUMNS, dict(resample=100.0, t_from=838.2, t_to=840.5)),
             (nameless, COLUMNS.split(",", 1)[1], dict(period=0.01, rows=(5, 250)))]
    for log, columns, options in cases:
        whole = read_log(log, ur, columns, block=10**6, **options)
        small = read_log(log, ur, columns, block=7, **options)
        assert whole.n_samples > 150 and whole.meta["log"]["lines"] == small.meta["log"]["lines"]
        for name in ("t", "q", "dq", "current", "measured_mask", "segment"):
            np.testing.assert_array_equal(getattr(small, name), getattr(whole, name), err_msg=name)
        assert small.meta["log"]["samples"] == whole.meta["log"]["samples"]
    # The window of a resampled log starts inside the burst's neighbourhood: the bridged samples are counted.
    assert read_log(path, ur, COLUMNS, block=7, resample=100.0).meta["log"]["bridged_samples"] > 0


def test_a_converted_log_keeps_its_clock_and_counts(tmp_path, capsys):
    """rx90 convert writes each block as it comes and fills the header fields at the end: the log's clock
    at the first sample (t0_s) and the stale rows read back as identify.read_log reports them."""
    t = jittered_times(200, seed=5)
    lines = log_lines(t)
    lines.insert(50, lines[49].replace(lines[49].split(",")[0], f"{t[49] + 0.004:.17g}", 1))  # a stale row
    path = write_log(tmp_path / "log.csv", lines)
    out = tmp_path / "rec.csv"
    robot_file = ur10e_toml(tmp_path)
    code, _, err = convert([str(path), "--robot", str(robot_file), "--columns", COLUMNS, "--no-header",
                            "--resample", "100", "--out", str(out)], capsys)
    assert code == 0, err
    rec = read_recording(out, rx90sym.load_robot(str(robot_file)))
    ref = read_log(path, ur10e_robot(), COLUMNS, resample=100.0)
    assert rec.meta["log"]["t0_s"] == ref.meta["log"]["t0_s"] == pytest.approx(838.0)
    assert rec.meta["log"]["stale_rows"] == ref.meta["log"]["stale_rows"] == 1
    np.testing.assert_allclose(rec.q, ref.q, rtol=0, atol=1e-12)
