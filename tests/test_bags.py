"""ROS bags (ROS 1, ROS 2 sqlite3 and MCAP) written with rosbags' own writer from a twin run: the
same recording as the CSV route; UR RTDE CSVs recognised by their header; bad bags exit 2."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import rx90sym
from identify.app.cli import main
from identify.io.bags import read_bag
from identify import read_log
from identify.io.recordings import read_recording
from motions import multisine, panda_truth
from rx90sym.host_log import HostFaults, host_log

rosbags = pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")

EPOCH_NS = 1_732_000_000_123_456_789  # a real clock's stamps: far from 0


@pytest.fixture(scope="module")
def panda():
    return rx90sym.load_robot("panda")


@pytest.fixture(scope="module")
def host_table(panda):
    """A 3 s, 1 kHz Panda twin run as a host logs it (lost packets, 5 % stale rows, jitter)."""
    rec = rx90sym.twin.simulate(panda, multisine(panda, 3, duration=3.0), params=panda_truth(panda),
                                duration=3.0, rate=1000.0, noise="quantised", seed=3)
    table, _, _ = host_log(rec, HostFaults(gap_every_s=(0.5, 1.0)), seed=3)
    return table


def _stamps(table: np.ndarray) -> np.ndarray:
    return EPOCH_NS + np.round(table[:, 0] * 1e9).astype(np.int64)


def write_bag(path: Path, table: np.ndarray, names: list[str], kind: str, seed: int = 0,
              topic: str = "/joint_states") -> Path:
    """Messages of ``table`` (t, q, qd, tau; robot order) on ``topic`` with names in the order given
    (and an extra gripper joint), written in a receive order that is not the stamp order."""
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC if kind == "ros1" else Stores.ROS2_HUMBLE)
    JointState = store.types["sensor_msgs/msg/JointState"]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    n = (table.shape[1] - 1) // 3
    robot_names = [f"panda_joint{j}" for j in range(1, n + 1)]
    order = [robot_names.index(nm) for nm in names]
    stamps = _stamps(table)
    received = stamps + np.random.default_rng(seed).integers(0, 3_000_000, stamps.size)  # up to 3 ms late
    msgtype = "sensor_msgs/msg/JointState"

    def message(k: int):
        stamp = int(stamps[k])
        q, qd, tau = (table[k, 1 + a * n:1 + (a + 1) * n][order] for a in range(3))
        return JointState(header=Header(seq=k, stamp=Time(sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id="")
                          if kind == "ros1" else Header(stamp=Time(sec=stamp // 10**9, nanosec=stamp % 10**9),
                                                        frame_id=""),
                          name=names + ["panda_finger_joint1"], position=np.r_[q, 0.04],
                          velocity=np.r_[qd, 0.0], effort=np.r_[tau, 1.0])

    if kind == "ros1":
        from rosbags.rosbag1 import Writer

        with Writer(path) as writer:
            conn = writer.add_connection(topic, msgtype, typestore=store)
            for k in np.argsort(received, kind="stable"):
                writer.write(conn, int(received[k]), store.serialize_ros1(message(k), msgtype))
        return path
    from rosbags.rosbag2 import StoragePlugin, Writer

    plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        conn = writer.add_connection(topic, msgtype, typestore=store)
        for k in np.argsort(received, kind="stable"):
            writer.write(conn, int(received[k]), store.serialize_cdr(message(k), msgtype))
    return path


def csv_route(tmp_path: Path, table: np.ndarray, robot, **options):
    """The same samples through the CSV reader: time from the first stamp, robot order."""
    stamps = _stamps(table)
    rows = table.copy()
    rows[:, 0] = (stamps - stamps[0]) * 1e-9
    path = tmp_path / "route.csv"
    np.savetxt(path, rows, fmt="%.17g", delimiter=",")
    n = robot.n
    return read_log(path, robot, f"t,q1..q{n},qd1..qd{n},tau1..tau{n}", **options)


@pytest.mark.parametrize("kind", ["ros1", "sqlite3", "mcap"])
def test_a_bag_gives_the_recording_of_the_csv_route(tmp_path, panda, host_table, kind):
    names = sorted(f"panda_joint{j}" for j in range(1, 8))[::-1]  # not the robot's order
    bag = write_bag(tmp_path / ("run.bag" if kind == "ros1" else "run"), host_table, names, kind)
    rec = read_bag(bag, panda, "/joint_states", resample=1000.0)
    ref = csv_route(tmp_path, host_table, panda, resample=1000.0)
    for name in ("t", "q", "dq", "tau", "measured", "segment"):
        a, b = getattr(rec, name), getattr(ref, name)
        assert (a is None) == (b is None), name
        if a is not None:
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12, err_msg=name)
    assert rec.measured is not None and 0 < np.sum(~rec.measured) < 0.2 * rec.n_samples  # bridged samples
    log = rec.meta["log"]
    assert log["reordered"] > 0 and log["duplicate_stamps"] == 0 and log["velocities"] == "recorded"
    assert log["stale_rows"] == ref.meta["log"]["stale_rows"] > 0
    assert log["t0_ns"] == _stamps(host_table)[0]


def test_bad_bags_exit_2_naming_the_problem(tmp_path, capsys, panda, host_table):
    names = [f"panda_joint{j}" for j in range(1, 8)]
    bag = write_bag(tmp_path / "run", host_table, names, "sqlite3")
    out = tmp_path / "rec.csv"
    cases = [(["--topic", "/other"], "no topic '/other' in the bag (its topics: /joint_states"),
             (["--topic", "/joint_states", "--robot", "ur10e"], "no message names every joint of the robot"),
             (["--topic", "/joint_states", "--resample", "1000", "--max-gap", "0.004", "--no-segments"],
              "longer than the 0.004 s that can be bridged")]
    for extra, needle in cases:
        robot = [] if "--robot" in extra else ["--robot", "panda"]
        code = main(["convert", str(bag), *robot, *extra, "--out", str(out)])
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert code == 2 and needle in err, err
        assert not out.exists()
    code = main(["convert", str(bag), "--robot", "panda", "--topic", "/joint_states", "--resample", "1000",
                 "--out", str(out)])
    printed = capsys.readouterr().out
    assert code == 0 and out.exists() and "stale rows dropped" in printed and "lost packets" in printed


def test_options_a_bag_does_not_take_are_named_in_bag_terms(tmp_path, capsys, host_table):
    """Gains on a torque bag name --effort current (there is no column map); a motor-form option says
    'not to a bag'; --block (a LOG.csv's lines per block, which a bag ignored) is refused in one line
    whatever its value (500 was refused by argparse with the whole usage text)."""
    bag = write_bag(tmp_path / "run.bag", host_table, [f"panda_joint{j}" for j in range(1, 8)], "ros1")
    out = tmp_path / "rec.csv"
    cases = [(["--gains", "1,1,1,1,1,1,1"], "drive gains given, but the messages' effort is read as joint torques "
                                            "(--effort torque, the default; effort= in Python): give --effort current"),
             (["--motor-positions", "p.csv"], "--motor-positions belongs to the motor form, not to a bag"),
             (["--block", "500"], "--block belongs to the LOG.csv form, not to a bag (a bag is read whole)"),
             (["--block", "5000"], "--block belongs to the LOG.csv form, not to a bag (a bag is read whole)")]
    for extra, needle in cases:
        code = main(["convert", str(bag), "--topic", "/joint_states", "--robot", "panda", *extra, "--out", str(out)])
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and needle in err[-1] and "column map" not in err[-1], err
        assert not any(line.startswith("usage:") for line in err) and not out.exists()
    with pytest.raises(ValueError, match="give --effort current"):
        read_bag(bag, rx90sym.load_robot("panda"), "/joint_states", gains="1,1,1,1,1,1,1")


def test_refusals_of_a_bag_advise_only_what_a_bag_takes(tmp_path, capsys, host_table):
    """A gap refused with --no-segments: the advice names --max-gap (with a value that bridges it) and
    leaving out --no-segments, never --rows/--from (refused for a bag) nor the Python max_gap alone; a
    position beyond the limits names the message and advises no window either."""
    out = tmp_path / "rec.csv"
    bag = write_bag(tmp_path / "run.bag", host_table, [f"panda_joint{j}" for j in range(1, 8)], "ros1")
    code = main(["convert", str(bag), "--topic", "/joint_states", "--robot", "panda", "--resample", "1000",
                 "--max-gap", "0.004", "--no-segments", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert code == 2 and "longer than the 0.004 s that can be bridged" in err, err
    assert "; let it split the log into segments (without --no-segments) or bridge it with --max-gap " in err
    assert "--rows" not in err and "--from" not in err and "a longer max_gap" not in err and not out.exists()
    suggested = err.split("--max-gap ")[1].split()[0]  # bridges every gap: the same command then converts
    assert main(["convert", str(bag), "--topic", "/joint_states", "--robot", "panda", "--resample", "1000",
                 "--max-gap", suggested, "--no-segments", "--out", str(out)]) == 0 and out.exists()
    out.unlink()
    capsys.readouterr()
    corrupt = host_table.copy()
    corrupt[100, 1] = 50.0  # joint 1 far beyond its limits
    bag = write_bag(tmp_path / "corrupt.bag", corrupt, [f"panda_joint{j}" for j in range(1, 8)], "ros1")
    code = main(["convert", str(bag), "--topic", "/joint_states", "--robot", "panda", "--resample", "1000",
                 "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert code == 2 and "beyond joint 1's limits" in err and "--rows" not in err and not out.exists(), err


def test_without_rosbags_the_message_names_the_extra(tmp_path, monkeypatch, panda):
    import sys

    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)  # import fails as if not installed
    with pytest.raises(ImportError, match=r"pip install 'rx90sym\[ros\]'"):
        read_bag(tmp_path, panda, "/joint_states")


def test_an_rtde_csv_needs_no_column_map(tmp_path, capsys):
    """UR's RTDE recorder: a header of names, cells separated by blanks; columns found by name."""
    ur = rx90sym.load_robot("ur10e")
    rng = np.random.default_rng(4)
    t = 0.002 * np.arange(400)
    q = 0.3 * np.sin(np.outer(t, np.arange(1, 7)))
    qd = 0.3 * np.arange(1, 7) * np.cos(np.outer(t, np.arange(1, 7)))
    cur, moment, target = rng.normal(size=(3, t.size, 6))
    groups = [("target_q", q), ("actual_q", q), ("actual_qd", qd), ("actual_current", cur),
              ("target_moment", moment)]
    header = ["timestamp"] + [f"{g}_{j}" for g, _ in groups for j in range(6)] + ["robot_mode"]
    table = np.column_stack([1234.5 + t] + [a for _, a in groups] + [np.full(t.size, 7.0)])
    path = tmp_path / "rtde.csv"
    path.write_text(" ".join(header) + "\n" + "\n".join(" ".join(f"{v:.17g}" for v in row) for row in table) + "\n")
    rec = read_log(path, ur, None, header=True)
    np.testing.assert_array_equal(rec.q, q)
    np.testing.assert_array_equal(rec.dq, qd)
    np.testing.assert_array_equal(rec.current, cur)
    np.testing.assert_array_equal(rec.aux["target_moment1"], moment[:, 0])
    out = tmp_path / "rec.csv"
    assert main(["convert", str(path), "--robot", "ur10e", "--gains", "10,10,10,10,10,10", "--out", str(out)]) == 0
    np.testing.assert_allclose(read_recording(out, ur).torques, 10 * cur, rtol=1e-14)


def test_a_path_that_is_no_bag_says_what_a_bag_is(tmp_path, capsys):
    """An empty directory, a directory of other files and a .mcap file without its bag's metadata.yaml:
    one line naming the path and the forms a bag takes (rosbags said "Expected metadata file ... does
    not exist.")."""
    empty, other = tmp_path / "emptydir", tmp_path / "other"
    empty.mkdir(), other.mkdir()
    (other / "notes.txt").write_text("x")
    (other / "run.mcap").write_bytes(b"")
    cases = [(empty, "emptydir: an empty directory is not a ROS bag"),
             (other, "other: a directory without metadata.yaml is not a ROS bag"),
             (other / "run.mcap", "run.mcap: its directory holds no metadata.yaml")]
    for path, needle in cases:
        out = tmp_path / "rec.csv"
        code = main(["convert", str(path), "--topic", "/joint_states", "--robot", "panda", "--out", str(out)])
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert code == 2 and needle in err and "a ROS 1 .bag file, a ROS 2 bag directory (holding metadata.yaml)" in err, err
        assert not out.exists()


def test_an_rtde_csv_without_currents_says_what_was_found_and_what_is_missing(tmp_path, capsys):
    """Only target_moment (the controller's target) as effort: the message says the header was read as
    RTDE, names the RTDE columns found and the actual_current_j missing (it said 'column map: neither
    joint torques (tau1..tau6) nor motor currents', though no column map was given)."""
    t = 0.002 * np.arange(300)
    q = 0.3 * np.sin(np.outer(t, np.arange(1, 7)))
    groups = [("actual_q", q), ("actual_qd", np.gradient(q, t, axis=0)), ("target_moment", np.cos(q)),
              ("actual_current", np.sin(q))]
    out = tmp_path / "rec.csv"
    for kept, missing in ((3, "missing actual_current_0..actual_current_5 (motor currents"),
                          (4, "missing actual_current_4, actual_current_5 (motor currents")):
        header = ["timestamp"] + [f"{g}_{j}" for g, _ in groups[:kept] for j in range(6)]
        table = np.column_stack([t] + [a for _, a in groups[:kept]])
        if kept == 4:  # currents of joints 1-4 only
            header, table = header[:-2], table[:, :-2]
        path = tmp_path / "rtde.csv"
        path.write_text(" ".join(header) + "\n" + "\n".join(" ".join(f"{v:.17g}" for v in r) for r in table) + "\n")
        code = main(["convert", str(path), "--robot", "ur10e", "--out", str(out)])
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert code == 2 and "rtde.csv: the header was recognised as a UR RTDE log: found timestamp, " \
            "actual_q_0..actual_q_5 (positions), actual_qd_0..actual_qd_5 (velocities), " in err, err
        assert "target_moment_0..target_moment_5 (the controller's target torques, kept as x:target_moment1.., " \
            "never a torque)" in err
        assert missing in err and "column map" not in err and not out.exists()
