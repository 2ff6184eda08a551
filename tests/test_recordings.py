"""Recordings: file formats, angle conventions, validation messages, atomic writes, TX40 data."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import rx90sym
from identify.signal import filtering
from identify.io import recordings as rec_mod
from identify.io.recordings import (
    Recording,
    RecordingError,
    read_motor_recording,
    read_recording,
    recording_from_arrays,
    split,
    write_recording,
)

TX40_DIR = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "tx40"
RATE = 250.0
N_SAMPLES = 400


@pytest.fixture(scope="module")
def rx90():
    return rx90sym.load_robot("rx90")


@pytest.fixture(scope="module")
def tx40():
    return rx90sym.load_robot("tx40")


def motion(robot, n_samples: int = N_SAMPLES, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Smooth Khalil-angle motion inside the limits, random torques: (t, q, tau, dq)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_samples) / RATE
    phase = rng.uniform(0, 2 * np.pi, robot.n)
    centre = 0.5 * (robot.limits.q_min + robot.limits.q_max)
    q = centre + 0.3 * np.sin(2 * np.pi * 0.5 * t[:, None] + phase)
    dq = 0.3 * 2 * np.pi * 0.5 * np.cos(2 * np.pi * 0.5 * t[:, None] + phase)
    tau = rng.normal(0.0, 10.0, (n_samples, robot.n))
    return t, q, tau, dq


def write_csv(path: Path, columns: list[str], table: np.ndarray | list[list[str]], comments: tuple[str, ...] = ()) -> Path:
    """Write a CSV by hand (independent of write_recording), cells as given."""
    lines = [f"# {c}" for c in comments] + [",".join(columns)]
    for row in table:
        lines.append(",".join(c if isinstance(c, str) else repr(float(c)) for c in row))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def columns_for(n: int, with_dq: bool = False) -> list[str]:
    cols = ["t"] + [f"q{j + 1}" for j in range(n)] + [f"tau{j + 1}" for j in range(n)]
    return cols + ([f"dq{j + 1}" for j in range(n)] if with_dq else [])


def good_table(robot, seed: int = 0) -> np.ndarray:
    """A valid table in Khalil angles (files below declare 'convention: khalil')."""
    t, q, tau, _ = motion(robot, seed=seed)
    return np.column_stack([t, q, tau])


def staubli_from_design(q_khalil: np.ndarray) -> np.ndarray:
    """DESIGN.md, independently of rx90sym: θ2(Stäubli) = θ2 + π/2, θ3(Stäubli) = θ3 − π/2."""
    q = np.array(q_khalil, dtype=float, copy=True)
    q[..., 1] += np.pi / 2
    q[..., 2] -= np.pi / 2
    return q


def assert_names(exc: pytest.ExceptionInfo, *parts: str) -> None:
    message = str(exc.value)
    for part in parts:
        assert part in message, f"{part!r} not in {message!r}"


# ---------------------------------------------------------------------------------------------
# Recording and round trips
# ---------------------------------------------------------------------------------------------


def test_recording_is_read_only_and_checks_shapes(rx90):
    t, q, tau, _ = motion(rx90)
    rec = Recording(t=t, q=q, tau=tau, robot="rx90")
    assert rec.rate == pytest.approx(RATE)
    assert rec.n_samples == N_SAMPLES and rec.n_joints == 6
    with pytest.raises(ValueError):
        rec.q[0, 0] = 1.0  # frozen arrays
    q[0, 0] = 99.0
    assert rec.q[0, 0] != 99.0  # the recording holds a copy
    with pytest.raises(RecordingError, match="tau must have shape"):
        Recording(t=t, q=q, tau=tau[:, :5])
    with pytest.raises(RecordingError, match="q must have shape"):
        Recording(t=t[:-1], q=q, tau=tau)


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
@pytest.mark.parametrize("convention", ["staubli", "khalil"])
@pytest.mark.parametrize("with_dq", [False, True])
def test_write_read_round_trip(tmp_path, rx90, suffix, convention, with_dq):
    t, q, tau, dq = motion(rx90, seed=3)
    # awkward values: full 17 digits needed to round-trip
    t = t + 1e-3 / 3
    rec = recording_from_arrays(t, q, tau, rx90, dq=dq if with_dq else None)
    path = tmp_path / f"motion{suffix}"
    write_recording(path, rec, rx90, convention=convention)
    back = read_recording(path, rx90)  # the convention comes from the file
    assert back.source == path.name and back.robot == "rx90"
    assert np.array_equal(back.t, rec.t)
    assert np.array_equal(back.tau, rec.tau)
    if convention == "khalil":
        assert np.array_equal(back.q, rec.q)  # bit for bit
    else:
        # (q ± π/2) ∓ π/2 is exact to one rounding of numbers below 2π: ≤ 4.5e-16 rad
        assert np.max(np.abs(back.q - rec.q)) <= 1e-15
    if with_dq:
        assert np.array_equal(back.dq, rec.dq)
    else:
        assert back.dq is None
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]  # no temporary file left


def test_csv_written_in_staubli_angles_with_header(tmp_path, rx90):
    t, q, tau, _ = motion(rx90)
    rec = recording_from_arrays(t, q, tau, rx90)
    path = tmp_path / "m.csv"
    write_recording(path, rec, rx90)  # default: Stäubli, like the CS8
    lines = path.read_text().splitlines()
    assert lines[0] == "# convention: controller" and lines[1] == "# robot: rx90"
    assert lines[2] == ",".join(columns_for(6))
    raw = np.loadtxt(path, delimiter=",", comments="#", skiprows=3)
    np.testing.assert_allclose(raw[:, 1:7], staubli_from_design(q), rtol=0, atol=1e-15)


def test_default_convention_is_staubli(tmp_path, rx90):
    table = good_table(rx90)
    path = write_csv(tmp_path / "cs8.csv", columns_for(6), table)  # no convention comment
    rec = read_recording(path, rx90)
    np.testing.assert_allclose(staubli_from_design(rec.q), table[:, 1:7], rtol=0, atol=1e-15)
    rec_k = read_recording(path, rx90, convention="khalil")  # the argument decides when the file is silent
    assert np.array_equal(rec_k.q, table[:, 1:7])


def test_convention_disagreement_and_robot_mismatch(tmp_path, rx90, tx40):
    path = write_csv(tmp_path / "k.csv", columns_for(6), good_table(rx90),
                     comments=("convention: khalil", "robot: rx90"))
    with pytest.raises(RecordingError) as exc:
        read_recording(path, rx90, convention="staubli")
    assert_names(exc, "k.csv", "khalil", "staubli")
    with pytest.raises(RecordingError) as exc:
        read_recording(path, tx40)
    assert_names(exc, "k.csv", "rx90", "tx40")
    with pytest.raises(RecordingError) as exc:
        read_recording(path, rx90, convention="degrees")
    assert_names(exc, "unknown angle convention")


def test_unsupported_suffix(tmp_path, rx90):
    with pytest.raises(RecordingError) as exc:
        read_recording(tmp_path / "m.txt", rx90)
    assert_names(exc, "m.txt", ".csv or .npz")


# ---------------------------------------------------------------------------------------------
# Validation: each broken file names file, column and row
# ---------------------------------------------------------------------------------------------


def broken_csv(tmp_path: Path, robot, name: str, edit) -> Path:
    """A valid Khalil table, altered by ``edit(columns, cells)``, written by hand."""
    table = good_table(robot)
    columns = columns_for(robot.n)
    cells = [[repr(float(v)) for v in row] for row in table]
    columns, cells = edit(columns, cells) or (columns, cells)
    return write_csv(tmp_path / name, columns, cells, comments=("convention: khalil",))


def set_cell(column: str, row: int, text: str):
    """Edit: put ``text`` in ``column`` at 1-based data ``row``."""
    def edit(columns, cells):
        cells[row - 1][columns.index(column)] = text
    return edit


@pytest.mark.parametrize(
    ("edit", "column", "row", "what"),
    [
        (set_cell("q2", 7, "abc"), "q2", 7, "not a number"),
        (set_cell("tau3", 12, ""), "tau3", 12, "not a number"),
        (set_cell("tau4", 5, "nan"), "tau4", 5, "not finite"),
        (set_cell("q6", 250, "inf"), "q6", 250, "not finite"),
        (set_cell("t", 10, "0.0"), "t", 10, "does not increase"),
        (set_cell("t", 20, repr(19 / RATE + 0.3 / RATE)), "t", 20, "irregular time step"),
        (set_cell("q3", 30, "0.5"), "q3", 30, "jump"),
    ],
    ids=["text", "empty", "nan", "inf", "time-back", "time-irregular", "jump"],
)
def test_bad_cells_name_file_column_row(tmp_path, rx90, edit, column, row, what):
    path = broken_csv(tmp_path, rx90, "bad.csv", edit)
    with pytest.raises(RecordingError) as exc:
        read_recording(path, rx90)
    assert_names(exc, "bad.csv", f"column '{column}'", f"row {row}", what)


def test_irregular_step_tolerance_is_one_percent(tmp_path, rx90):
    # 0.5 % of a step off: accepted; 2 %: refused (TIME_RTOL = 1 %)
    ok = broken_csv(tmp_path, rx90, "ok.csv", set_cell("t", 20, repr((19 + 0.005) / RATE)))
    read_recording(ok, rx90)
    bad = broken_csv(tmp_path, rx90, "bad.csv", set_cell("t", 20, repr((19 + 0.02) / RATE)))
    with pytest.raises(RecordingError, match="irregular"):
        read_recording(bad, rx90)


def test_degrees_are_refused(tmp_path, rx90):
    def to_degrees(columns, cells):
        j = columns.index("q1")
        for row in cells:
            row[j] = repr(math.degrees(float(row[j])))
    path = broken_csv(tmp_path, rx90, "deg.csv", to_degrees)
    with pytest.raises(RecordingError) as exc:
        read_recording(path, rx90)
    assert_names(exc, "deg.csv", "column 'q1'", "row ", "degrees")


def test_degrees_rule_range(rx90):
    # |q| within travel + 2π but a span of more than 4π: degrees too (e.g. -8..+8 "rad" on joint 4)
    t, q, tau, _ = motion(rx90)
    q[:, 3] = np.linspace(-6.5, 6.5, q.shape[0])  # 13 rad > 4π, steps of 0.03 rad < jump limit
    with pytest.raises(RecordingError) as exc:
        recording_from_arrays(t, q, tau, rx90)
    assert_names(exc, "<memory>", "column 'q4'", "spans", "degrees")


@pytest.mark.parametrize(
    ("columns_edit", "column", "what"),
    [
        (lambda c: c.remove("tau3"), "tau3", "missing"),
        (lambda c: c.__setitem__(c.index("q4"), "q2"), "q2", "more than once"),
        (lambda c: c.append("temperature"), "temperature", "unknown"),
        (lambda c: c.extend(["dq1", "dq2"]), "dq3", "missing"),
    ],
    ids=["missing", "duplicated", "unknown", "partial-dq"],
)
def test_bad_header_names_file_and_column(tmp_path, rx90, columns_edit, column, what):
    def edit(columns, cells):
        before = len(columns)
        columns_edit(columns)
        extra = len(columns) - before
        for row in cells:  # keep rows as wide as the header, so the header is what fails
            if extra > 0:
                row.extend(["0.0"] * extra)
            elif extra < 0:
                del row[len(columns):]
    path = broken_csv(tmp_path, rx90, "hdr.csv", edit)
    with pytest.raises(RecordingError) as exc:
        read_recording(path, rx90)
    assert_names(exc, "hdr.csv", f"'{column}'", what)


def test_short_row_names_row(tmp_path, rx90):
    def edit(columns, cells):
        del cells[41][-1]
    path = broken_csv(tmp_path, rx90, "short.csv", edit)
    with pytest.raises(RecordingError) as exc:
        read_recording(path, rx90)
    assert_names(exc, "short.csv", "row 42", "12 cells", "13 columns")


def test_too_few_samples(tmp_path, rx90):
    table = good_table(rx90)[: len(rx90.parameter_names) - 1]
    path = write_csv(tmp_path / "few.csv", columns_for(6), table, comments=("convention: khalil",))
    with pytest.raises(RecordingError) as exc:
        read_recording(path, rx90)
    assert_names(exc, "few.csv", "column 't'", f"{len(table)} rows", f"at least {len(rx90.parameter_names)}")


def test_jump_check_skipped_for_unknown_speed_limit(rx90):
    t, q, tau, _ = motion(rx90)
    q[100:, 2] += 0.5  # a step of 0.5 rad in one sample at 250 Hz
    with pytest.raises(RecordingError, match="jump"):
        recording_from_arrays(t, q, tau, rx90)
    limits = rx90.limits
    qd_max = np.array(limits.qd_max, dtype=float)
    qd_max[2] = np.inf
    stand_in = _with_qd_max(rx90, qd_max)
    recording_from_arrays(t, q, tau, stand_in)  # joint 3 limit unknown: accepted


def _with_qd_max(robot, qd_max):
    """A robot-like view of ``robot`` with other speed limits (only what recordings use)."""
    from types import SimpleNamespace
    limits = SimpleNamespace(q_min=robot.limits.q_min, q_max=robot.limits.q_max, qd_max=qd_max)
    return SimpleNamespace(name=robot.name, n=robot.n, parameter_names=robot.parameter_names,
                           limits=limits, to_model=robot.to_model, to_controller=robot.to_controller)


def test_npz_validation(tmp_path, rx90):
    t, q, tau, _ = motion(rx90)
    np.savez(tmp_path / "missing.npz", t=t, q=q)
    with pytest.raises(RecordingError) as exc:
        read_recording(tmp_path / "missing.npz", rx90)
    assert_names(exc, "missing.npz", "'tau'", "missing")
    np.savez(tmp_path / "extra.npz", t=t, q=q, tau=tau, ddq=q)
    with pytest.raises(RecordingError) as exc:
        read_recording(tmp_path / "extra.npz", rx90)
    assert_names(exc, "extra.npz", "'ddq'", "unknown")
    np.savez(tmp_path / "short.npz", t=t, q=q, tau=tau[:-3], convention="khalil")
    with pytest.raises(RecordingError) as exc:
        read_recording(tmp_path / "short.npz", rx90)
    assert_names(exc, "short.npz", "'tau'", f"{N_SAMPLES - 3} rows", f"row {N_SAMPLES - 2}")
    bad = tau.copy()
    bad[17, 1] = np.nan
    np.savez(tmp_path / "nan.npz", t=t, q=q, tau=bad, convention="khalil")
    with pytest.raises(RecordingError) as exc:
        read_recording(tmp_path / "nan.npz", rx90)
    assert_names(exc, "nan.npz", "column 'tau2'", "row 18", "not finite")


def test_recording_from_arrays_names_memory_column_row(rx90):
    t, q, tau, _ = motion(rx90)
    tau[99, 5] = np.inf
    with pytest.raises(RecordingError) as exc:
        recording_from_arrays(t, q, tau, rx90)
    assert_names(exc, "<memory>", "column 'tau6'", "row 100")


# ---------------------------------------------------------------------------------------------
# Atomic writes
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("suffix", "writer"), [(".csv", "savetxt"), (".npz", "savez")])
def test_failing_write_leaves_nothing(tmp_path, rx90, monkeypatch, suffix, writer):
    t, q, tau, _ = motion(rx90)
    rec = recording_from_arrays(t, q, tau, rx90)
    target = tmp_path / f"out{suffix}"

    def boom(fh, *args, **kwargs):
        fh.write(b"partial" if "b" in getattr(fh, "mode", "") else "partial")
        raise OSError("disk full")

    monkeypatch.setattr(rec_mod.np, writer, boom)
    with pytest.raises(OSError, match="disk full"):
        write_recording(target, rec, rx90)
    assert list(tmp_path.iterdir()) == []  # neither the target nor a temporary file
    target.write_text("previous content")
    with pytest.raises(OSError):
        write_recording(target, rec, rx90)
    assert target.read_text() == "previous content"  # an existing file is left untouched
    assert [p.name for p in tmp_path.iterdir()] == [target.name]


def test_write_refuses_other_robot_and_creates_nothing(tmp_path, rx90, tx40):
    t, q, tau, _ = motion(rx90)
    rec = recording_from_arrays(t, q, tau, rx90)
    with pytest.raises(RecordingError) as exc:
        write_recording(tmp_path / "x.csv", rec, tx40)
    assert_names(exc, "x.csv", "rx90", "tx40")
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------------------------
# split
# ---------------------------------------------------------------------------------------------


def test_split_holds_out_the_end(rx90):
    t, q, tau, dq = motion(rx90)
    rec = recording_from_arrays(t, q, tau, rx90, dq=dq)
    fit, val = split(rec, 2 / 3)
    k = round(2 / 3 * N_SAMPLES)
    assert fit.n_samples == k and val.n_samples == N_SAMPLES - k
    assert np.array_equal(np.concatenate([fit.q, val.q]), rec.q)
    assert np.array_equal(np.concatenate([fit.dq, val.dq]), rec.dq)
    assert val.t[0] == rec.t[k]  # times kept as recorded
    for bad in (0.0, 1.0, -0.1, 1.5, 0.001):
        with pytest.raises(ValueError):
            split(rec, bad)


# ---------------------------------------------------------------------------------------------
# Motor-side files (TX40 format)
# ---------------------------------------------------------------------------------------------


def motor_files(tmp_path: Path, robot, n_pos: int = N_SAMPLES, n_tau: int = N_SAMPLES) -> tuple[Path, Path]:
    t, q, tau, _ = motion(robot)
    q_motor = (robot.Rq @ staubli_from_design(q).T).T
    tau_motor = np.linalg.solve(robot.Rt, tau.T).T
    names = [f"Joint_{j + 1}" for j in range(robot.n)]
    return (write_csv(tmp_path / "pos.csv", names, q_motor[:n_pos]),
            write_csv(tmp_path / "cur.csv", names, tau_motor[:n_tau]))


def test_motor_recording_round_trip(tmp_path, tx40):
    pos, cur = motor_files(tmp_path, tx40)
    rec = read_motor_recording(pos, cur, tx40, period=1 / RATE)
    t, q, tau, _ = motion(tx40)
    np.testing.assert_allclose(rec.q, q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rec.tau, tau, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(rec.t, t, rtol=0, atol=1e-12)
    assert rec.robot == "tx40" and "pos.csv" in rec.source


def test_motor_files_of_different_lengths(tmp_path, tx40):
    pos, cur = motor_files(tmp_path, tx40, n_tau=N_SAMPLES - 5)
    with pytest.raises(RecordingError) as exc:
        read_motor_recording(pos, cur, tx40, period=1 / RATE)
    assert_names(exc, "cur.csv", "column 'Joint_1'", f"row {N_SAMPLES - 4}", "mismatched lengths")


def test_motor_file_bad_cell_and_header(tmp_path, tx40):
    pos, cur = motor_files(tmp_path, tx40)
    lines = cur.read_text().splitlines()
    cells = lines[8].split(",")
    cells[4] = "n/a"
    lines[8] = ",".join(cells)  # data row 8, column Joint_5
    cur.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordingError) as exc:
        read_motor_recording(pos, cur, tx40, period=1 / RATE)
    assert_names(exc, "cur.csv", "column 'Joint_5'", "row 8", "not a number")
    lines = pos.read_text().splitlines()
    lines[0] = lines[0].replace("Joint_6", "Joint_7")
    pos.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordingError) as exc:
        read_motor_recording(pos, cur, tx40, period=1 / RATE)
    assert_names(exc, "pos.csv", "'Joint_7'", "unknown")


@pytest.fixture(scope="module")
def tx40_real(tx40):
    pos, cur = TX40_DIR / "pos_read_data.csv", TX40_DIR / "curr_data.csv"
    if not (pos.exists() and cur.exists()):
        pytest.skip(f"TX40 data not found in {TX40_DIR}")
    return read_motor_recording(pos, cur, tx40, period=0.2e-3), pos, cur


def test_real_tx40_files_load(tx40_real, tx40):
    rec, pos, cur = tx40_real
    assert rec.n_samples == 45_000 and rec.n_joints == 6
    assert rec.rate == pytest.approx(5000.0)
    assert rec.duration == pytest.approx(9.0, abs=1e-3)
    # Independent conversion from the data README: q = inv(Rq) q_motor with Rq = diag(N),
    # Rq[6,5] = N6; tau = Rt tau_motor with Rt[5,6] = N6; then Stäubli -> Khalil offsets.
    gears = np.array([32.0, 32.0, 45.0, -48.0, 45.0, 32.0])
    m = np.loadtxt(pos, delimiter=",", skiprows=1)
    c = np.loadtxt(cur, delimiter=",", skiprows=1)
    q = m / gears
    q[:, 5] = (m[:, 5] - gears[5] * q[:, 4]) / gears[5]
    q[:, 1] -= np.pi / 2
    q[:, 2] += np.pi / 2
    tau = c * gears
    tau[:, 4] += gears[5] * c[:, 5]
    np.testing.assert_allclose(rec.q, q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rec.tau, tau, rtol=1e-12, atol=1e-12)
    # the motion starts at the Khalil zero of joints 2 and 3 (motor 50.265 / 32 = π/2 Stäubli)
    assert abs(rec.q[0, 1]) < 1e-4 and abs(rec.q[0, 2]) < 1e-4
    inside = (rec.q >= tx40.limits.q_min) & (rec.q <= tx40.limits.q_max)
    assert inside.all()
    cutoff = filtering.choose_cutoff(rec.q, rec.rate)
    per_joint = filtering.crossover_frequencies(rec.q, rec.rate)
    assert 2.0 <= cutoff <= 0.4 * rec.rate / 2
    print(f"\nTX40: {rec!r}")
    print("  q   min [rad]:", np.array2string(rec.q.min(0), precision=4))
    print("  q   max [rad]:", np.array2string(rec.q.max(0), precision=4))
    print("  tau min [N.m]:", np.array2string(rec.tau.min(0), precision=4))
    print("  tau max [N.m]:", np.array2string(rec.tau.max(0), precision=4))
    print("  crossover per joint [Hz]:", np.array2string(per_joint, precision=1), f"-> cutoff {cutoff:.1f} Hz")


# ---------------------------------------------------------------------------------------------
# Current recordings, the time rule and the messages of issue 14
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
@pytest.mark.parametrize("convention", ["controller", "model"])
def test_currents_velocities_and_aux_round_trip(tmp_path, rx90, suffix, convention):
    t, q, _, dq = motion(rx90, seed=5)
    rng = np.random.default_rng(5)
    current, target = rng.normal(0, 2, q.shape), rng.normal(0, 1, t.shape)
    rec = recording_from_arrays(t, q, None, rx90, dq=dq, current=current, aux={"i_target1": target})
    path = tmp_path / f"i{suffix}"
    write_recording(path, rec, rx90, convention=convention)
    back = read_recording(path, rx90)
    assert back.tau is None and np.array_equal(back.current, current) and np.array_equal(back.dq, dq)
    assert list(back.aux) == ["i_target1"] and np.array_equal(back.aux["i_target1"], target)
    assert np.max(np.abs(back.q - rec.q)) <= (0 if convention == "model" else 1e-15)
    with pytest.raises(RecordingError, match="motor currents, not joint torques; give drive gains"):
        back.torques


def test_a_csv_needs_torques_or_currents(tmp_path, rx90):
    t, q, _, _ = motion(rx90)
    path = write_csv(tmp_path / "q.csv", ["t"] + [f"q{j}" for j in range(1, 7)], np.column_stack([t, q]),
                     comments=("convention: khalil", "robot: rx90"))
    with pytest.raises(RecordingError, match="column 'tau1' is missing .*motor currents i1..i6"):
        read_recording(path, rx90)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_clock_drift_and_microsecond_jitter_are_regular(tmp_path, rx90, seed):
    """A clock off by 0.005 % and +-1 us jitter at 250 Hz are within the 1 % rule; rate = 1/mean step."""
    t, q, tau, _ = motion(rx90, seed=seed)
    t = t * (1 + 5e-5) + np.random.default_rng(seed).uniform(-1e-6, 1e-6, t.size)
    path = write_csv(tmp_path / "drift.csv", columns_for(6), np.column_stack([t, q, tau]),
                     comments=("convention: khalil", "robot: rx90"))
    rec = read_recording(path, rx90)
    assert rec.rate == pytest.approx(1 / np.mean(np.diff(t)), rel=1e-12)
    assert rec.rate == pytest.approx(RATE / (1 + 5e-5), rel=1e-6)


def test_messages_print_plain_numbers(tmp_path, rx90):
    path = broken_csv(tmp_path, rx90, "bad.csv", set_cell("tau4", 5, "nan"))
    with pytest.raises(RecordingError) as exc:
        read_recording(path, rx90)
    assert "value nan is not finite" in str(exc.value) and "np.float64" not in str(exc.value)
    path = broken_csv(tmp_path, rx90, "back.csv", set_cell("t", 10, "0.0"))
    with pytest.raises(RecordingError) as exc:
        read_recording(path, rx90)
    assert "time 0 s does not increase (previous row: 0.032 s)" in str(exc.value)


def test_semicolon_separated_csv_gets_a_hint(tmp_path, rx90):
    path = tmp_path / "excel.csv"
    lines = [";".join(columns_for(6))] + [";".join(repr(float(v)) for v in row) for row in good_table(rx90)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(RecordingError, match="seems to use ';' as separator"):
        read_recording(path, rx90)


def test_file_of_another_robot_names_that_robot(tmp_path, rx90):
    t = np.arange(300) / RATE
    columns = ["t"] + [f"q{j}" for j in range(1, 8)] + [f"tau{j}" for j in range(1, 8)]
    path = write_csv(tmp_path / "panda.csv", columns, np.column_stack([t, np.zeros((300, 14))]),
                     comments=("robot: panda",))
    with pytest.raises(RecordingError) as exc:
        read_recording(path, rx90)
    assert "recorded on robot 'panda'" in str(exc.value) and "q7" not in str(exc.value)


def test_a_file_naming_no_robot_warns_under_another_robot(tmp_path, rx90, tx40):
    path = write_csv(tmp_path / "anon.csv", columns_for(6), good_table(rx90), comments=("convention: khalil",))
    with pytest.warns(rec_mod.RecordingWarning, match="anon.csv: the file names no robot.*read as robot 'tx40'"):
        read_recording(path, tx40)
    read_recording(path, rx90)  # the default robot: no warning (warnings are errors in this suite)


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_a_converted_logs_report_round_trips_and_bad_fields_are_named(tmp_path, rx90, suffix):
    """The stale rows and the gaps that split the log come back from either format (an NPZ kept neither);
    a field that does not read is refused naming the file and the field."""
    t, q, tau, _ = motion(rx90)
    rec = recording_from_arrays(t, q, tau, rx90)
    splits = [{"lines": [120, 121], "duration_s": 0.21000000000000002}, {"lines": [300, 302], "duration_s": 1.5}]
    rec.meta["log"] = {"stale_rows": 357, "gaps": {"splits": splits, "splits_total": 12, "gaps": []}, "t0_s": 838.7}
    path = tmp_path / f"rec{suffix}"
    write_recording(path, rec, rx90)
    assert read_recording(path, rx90).meta["log"] == {"stale_rows": 357, "gaps": {"splits": splits, "splits_total": 12},
                                                      "t0_s": 838.7}  # the log's clock at the first sample
    assert rec_mod.layout_summary(read_recording(path, rx90))["split_gaps_total"] == 12
    for field, value, what in (("stale_rows", "-3", "'# stale_rows: -3' is not a whole number"),
                               ("split_gaps", "1; 12-x 0.2", "'12-x 0.2' is not 'LINE-LINE SECONDS'"),
                               ("split_gaps", "1; 1-2 0.2; 3-4 0.3", "lists 2 gaps, more than its count 1"),
                               ("t0_s", "noon", "'# t0_s: noon' is not a number of seconds")):
        bad = tmp_path / f"bad{suffix}"
        if suffix == ".csv":
            bad.write_text("".join(f"# {field}: {value}\n" if line.startswith(f"# {field}:") else line
                                   for line in path.read_text().splitlines(keepends=True)))
        else:
            with np.load(path) as archive:
                np.savez(bad, **{**{k: archive[k] for k in archive.files}, field: np.array(value)})
        with pytest.raises(RecordingError) as exc:
            read_recording(bad, rx90)
        assert_names(exc, bad.name, what)
