"""ROS bags: the ``sensor_msgs/JointState`` messages of one topic read as a recording.

ROS 1 bags (``.bag``) and ROS 2 bags (a directory with ``metadata.yaml``, or its ``.db3`` /
``.mcap`` file; sqlite3 and MCAP storage) are read with the optional package ``rosbags`` (pure
Python, no ROS installation; the ``ros`` extra). Rules:

* joints matched **by name**: the robot's ROS joint names (``joint_names`` of the robot file, or
  a URDF robot's joint names) in any order (UR's driver publishes them sorted by name); other
  joints of a message (a gripper) are ignored; a message that names none of the robot's joints
  is skipped, one that names only some of them is dropped and counted;
* time from the **header stamps** (the time the sample was taken), not the bag's receive time;
  messages are put in stamp order (counted when they were not), a message whose stamp repeats the
  previous one is dropped and counted; time 0 is the first stamp (``meta["log"]["t0_ns"]``);
* ``effort`` holds joint torques (``effort="torque"``) or motor currents (``"current"``, turned
  into torques by drive gains); velocities are used when every kept message has them;
* then every rule of a controller log (:func:`identify.io.log_rules.rows_to_recording`): stale rows,
  lost packets bridged up to ``max_gap``, segments, resampling, the checks. Messages are numbered
  from 1 in the bag's order; error messages call them lines.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np

import rx90sym
from rx90sym.recording import Recording, RecordingError

from identify.io.columns import parse_columns
from identify.io.gains import DriveGains
from identify.io.log_rules import rows_to_recording
from identify.io.torque_signs import parse_torque_signs
from identify.io.gaps import DEFAULT_MAX_GAP

__all__ = ["MissingExtra", "is_bag", "read_bag", "EXTRA"]

#: The extra that installs ``rosbags``.
EXTRA = "rx90sym[ros]"
_JOINT_STATE = ("sensor_msgs/msg/JointState", "sensor_msgs/JointState")


class MissingExtra(ImportError):
    """An optional package a command needs is not installed; the message names the extra."""


def is_bag(path: str | os.PathLike[str]) -> bool:
    """A ROS bag by its name: a ``.bag``, ``.db3`` or ``.mcap`` file, or a directory."""
    p = Path(path)
    return p.is_dir() or p.suffix.lower() in (".bag", ".db3", ".mcap")


def _reader(path: Path) -> Any:
    """rosbags' reader of the bag ``path`` (checked first: the extra installed, the path a bag)."""
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise MissingExtra(f"{path.name}: reading ROS bags needs the package rosbags: pip install "
                           f"'{EXTRA}'") from None
    _check_bag_path(path)
    # A ROS 2 bag whose messages carry no definitions is read with the standard (Humble) types.
    bag = path.parent if path.suffix.lower() in (".db3", ".mcap") else path
    try:
        return AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
    except Exception as exc:  # rosbags' own errors: a file that is not a bag, a missing part
        raise _unreadable(path, exc) from None


def _unreadable(path: Path, exc: Exception) -> RecordingError:
    return RecordingError(f"{path.name}: not a readable ROS bag ({type(exc).__name__}: {exc}); expected {_BAG_FORMS}")


#: What a bag path may be, for the messages that refuse one.
_BAG_FORMS = ("a ROS 1 .bag file, a ROS 2 bag directory (holding metadata.yaml), or the .db3 or .mcap file "
              "inside one")


def _check_bag_path(path: Path) -> None:
    """A bag that exists and that rosbags can open: a ROS 2 bag (a directory, or its ``.db3``/``.mcap``
    file) is read through its ``metadata.yaml``."""
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such bag")
    if path.is_dir() and not (path / "metadata.yaml").is_file():
        what = "an empty directory" if not any(path.iterdir()) else "a directory without metadata.yaml"
        raise RecordingError(f"{path.name}: {what} is not a ROS bag; expected {_BAG_FORMS}")
    if path.suffix.lower() in (".db3", ".mcap") and not (path.parent / "metadata.yaml").is_file():
        raise RecordingError(f"{path.name}: its directory holds no metadata.yaml (a ROS 2 .db3 or .mcap file is "
                             f"read with its bag's metadata.yaml); expected {_BAG_FORMS}")


def _messages(path: Path, topic: str) -> list[tuple[int, int, Any]]:
    """(header stamp ns, receive time ns, message) of every message of ``topic``, bag order."""
    bag = _reader(path)
    try:
        with bag as reader:
            conns = [c for c in reader.connections if c.topic == topic]
            if not conns:
                found = ", ".join(sorted(f"{c.topic} ({c.msgtype})" for c in reader.connections)) or "none"
                raise RecordingError(f"{path.name}: no topic {topic!r} in the bag (its topics: {found})")
            wrong = [c.msgtype for c in conns if c.msgtype not in _JOINT_STATE]
            if wrong:
                raise RecordingError(f"{path.name}: topic {topic!r} holds {wrong[0]}, not sensor_msgs/JointState")
            out = []
            for conn, received, raw in reader.messages(connections=conns):
                msg = reader.deserialize(raw, conn.msgtype)
                stamp = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
                out.append((stamp, int(received), msg))
    except (MissingExtra, RecordingError):
        raise
    except Exception as exc:  # rosbags' own errors: a file that is not a bag, a broken index, a missing part
        raise _unreadable(path, exc) from None
    if not out:
        raise RecordingError(f"{path.name}: topic {topic!r} holds no message")
    return out


def _table(messages: list, names: tuple[str, ...], source: str, report: dict) -> tuple[np.ndarray, list[int], bool]:
    """Rows (t, q, qd?, effort) of the messages naming every joint; (table, numbers, has_qd)."""
    n = len(names)
    rows, numbers, partial, other = [], [], [], 0
    for k, (stamp, _, msg) in enumerate(messages, start=1):
        where = {name: i for i, name in enumerate(msg.name)}
        found = [where.get(name) for name in names]
        if all(i is None for i in found):
            other += 1
            continue
        if any(i is None for i in found):
            partial.append((k, [nm for nm, i in zip(names, found) if i is None]))
            continue
        idx = np.array(found)
        pos, vel, eff = (np.asarray(a, dtype=float) for a in (msg.position, msg.velocity, msg.effort))
        short = [what for what, a in (("position", pos), ("effort", eff)) if a.size < len(msg.name)]
        if short:
            raise RecordingError(f"{source}: message {k}: its {short[0]} array holds {pos.size if short[0] == 'position' else eff.size} "
                                 f"values for {len(msg.name)} joint names (effort is needed as torque or current)")
        qd = vel[idx] if vel.size >= len(msg.name) else np.full(n, np.nan)
        rows.append(np.r_[0.0, pos[idx], qd, eff[idx]])  # column 0: the time, set from the stamps
        numbers.append(k)
    if not rows:
        seen = sorted({nm for _, _, m in messages for nm in m.name})
        raise RecordingError(f"{source}: no message names every joint of the robot ({', '.join(names)}); "
                             f"the messages name {', '.join(seen) or 'no joint'}"
                             + (f" (message {partial[0][0]} lacks {', '.join(partial[0][1])})" if partial else ""))
    report.update({"messages": len(messages), "other_joint_messages": other, "incomplete_messages": len(partial),
                   "incomplete_first": partial[0][0] if partial else None})
    table = np.array(rows)
    has_qd = bool(np.all(np.isfinite(table[:, 1 + n:1 + 2 * n])))
    report["velocities"] = "recorded" if has_qd else (
        "none" if np.all(np.isnan(table[:, 1 + n:1 + 2 * n])) else "missing in some messages: not used")
    return table, numbers, has_qd


def read_bag(path: str | os.PathLike[str], robot: rx90sym.Robot, topic: str = "/joint_states",
             effort: str = "torque", gains: DriveGains | str | None = None, resample: float | None = None,
             convention: str = "controller", max_gap: float = DEFAULT_MAX_GAP, segments: bool = True,
             torque_signs: str | Sequence[float] | None = None) -> Recording:
    """Read the ``sensor_msgs/JointState`` messages of ``topic`` in a ROS bag as a recording.

    Args:
        path: a ROS 1 ``.bag``, a ROS 2 bag directory or its ``.db3``/``.mcap`` file.
        robot: the robot; its ROS joint names (:meth:`rx90sym.Robot.ros_joint_names`) match the
            message's names.
        effort: ``"torque"`` (joint torques, N·m) or ``"current"`` (motor currents, A).
        gains, resample, convention, max_gap, segments, torque_signs: as for :func:`identify.read_log`.

    Returns:
        The recording (time 0 at the first header stamp); ``meta["log"]`` as for a log plus
        ``topic``, ``t0_ns``, ``messages``, ``reordered``, ``duplicate_stamps``,
        ``other_joint_messages``, ``incomplete_messages``, ``velocities``.

    Raises:
        MissingExtra: rosbags is not installed (the message names the extra).
        ValueError: gains with ``effort="torque"``.
        RecordingError: no such topic, no joint name matching, a bad message (named by number).
    """
    p = Path(path)
    signs = parse_torque_signs(torque_signs, robot)
    if effort not in ("torque", "current"):
        raise ValueError(f"effort must be 'torque' or 'current', got {effort!r}")
    if gains is not None and effort == "torque":  # a bag has no column map: name its own option
        raise ValueError(f"{p.name}: drive gains given, but the messages' effort is read as joint torques "
                         f"(--effort torque, the default; effort= in Python): give --effort current if it "
                         f"holds motor currents")
    names = robot.ros_joint_names()
    if len(names) != robot.n:
        raise ValueError(f"robot {robot.name!r} has no ROS joint names: add joint_names = [...] ({robot.n} "
                         f"names) to its robot file")
    source = f"{p.name}:{topic}"
    messages = _messages(p, topic)
    stamps = np.array([m[0] for m in messages])
    report: dict = {"topic": topic, "reordered": int(np.sum(np.diff(stamps) < 0))}
    if np.all(stamps == 0):
        raise RecordingError(f"{source}: every header stamp is 0: the publisher does not stamp its messages")
    order = np.argsort(stamps, kind="stable")
    messages = [messages[k] for k in order]
    table, numbers, has_qd = _table(messages, names, source, report)
    kept = np.array([messages[k - 1][0] for k in numbers], dtype=np.int64)  # stamps, ns (exact)
    numbers = [int(order[k - 1]) + 1 for k in numbers]  # bag order, for the messages
    repeat = np.r_[False, np.diff(kept) == 0]
    report["duplicate_stamps"] = int(repeat.sum())
    table, numbers, kept = table[~repeat], [k for k, r in zip(numbers, repeat) if not r], kept[~repeat]
    t0 = int(kept[0])
    table[:, 0] = (kept - t0) * 1e-9
    n = robot.n
    kind = "tau" if effort == "torque" else "i"
    if not has_qd:
        table = np.delete(table, np.s_[1 + n:1 + 2 * n], axis=1)
    spec = f"t,q1..q{n}," + (f"qd1..qd{n}," if has_qd else "") + f"{kind}1..{kind}{n}"
    rec = rows_to_recording(source, table, numbers, parse_columns(spec, robot), robot, convention,
                            gains=gains, max_gap=max_gap, segments=segments, resample=resample, window=False,
                            signs=signs)
    rec.meta["log"].update(report, t0_ns=t0, t0_s=t0 * 1e-9)  # the one time origin: 0 s at the first sample
    return rec
