"""The column map of a controller log: what each column holds (see :mod:`identify.io.logs`).

Names (n = the robot's number of joints): ``t``; ``q1..qn``, ``qd1..qdn``, ``tau1..taun``,
``i1..in`` (each group all or none; positions required; torques or currents required); ``_``
(ignored); ``x:NAME`` (auxiliary, kept, never a torque). Shorthands: ``q1..q6`` (one prefix,
increasing numbers) and ``_*3`` (three ignored columns).
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Sequence

import rx90sym

__all__ = ["ColumnMap", "parse_columns", "rtde_columns", "rtde_refusal", "RTDE_NAMES"]

#: UR's RTDE recorder's column names -> the column map's (``actual_q_0`` is joint 1's position):
#: measured positions, velocities and motor currents; the controller's target torque
#: (``target_moment``, its model, not a measurement) and target current are kept as auxiliaries.
RTDE_NAMES = {"actual_q": "q", "actual_qd": "qd", "actual_current": "i",
              "target_moment": "x:target_moment", "target_current": "x:target_current"}

_GROUPS = ("q", "qd", "tau", "i")
_NAME = re.compile(r"^(q|qd|tau|i)(\d+)$")
_RANGE = re.compile(r"^(.*?)(\d+)\.\.(.*?)(\d+)$")
_REPEAT = re.compile(r"^_\s*\*\s*(\d+)$")


@dataclass(frozen=True)
class ColumnMap:
    """What each column of a log holds (0-based column indices).

    Attributes:
        names: the expanded name of every column, in file order (``_`` for ignored ones).
        t: column of the time stamps (-1 for a map parsed with ``time=False``: the log has none).
        q, qd, tau, i: columns of joint j's position, velocity, torque, current (empty tuple
            when the log has none of that kind).
        aux: auxiliary name -> column.
    """

    names: tuple[str, ...]
    t: int
    q: tuple[int, ...]
    qd: tuple[int, ...]
    tau: tuple[int, ...]
    i: tuple[int, ...]
    aux: tuple[tuple[str, int], ...]


def _expand(token: str) -> list[str]:
    """``q1..q6`` -> q1, ..., q6; ``_*3`` -> _, _, _; anything else as is."""
    repeat = _REPEAT.match(token)
    if repeat:
        return ["_"] * int(repeat.group(1))
    rng = _RANGE.match(token)
    if not rng:
        return [token]
    prefix, a, prefix_b, b = rng.group(1), int(rng.group(2)), rng.group(3), int(rng.group(4))
    if prefix != prefix_b or b < a:
        raise ValueError(f"column map: range {token!r} must be PREFIXa..PREFIXb with one prefix and "
                         f"a <= b (e.g. q1..q6)")
    return [f"{prefix}{k}" for k in range(a, b + 1)]


def parse_columns(spec: str | Sequence[str], robot: rx90sym.Robot, time: bool = True) -> ColumnMap:
    """Parse a column map (module docstring) for ``robot``; ``time=False``: the log has no time
    column (its clock comes from a sampling period) and the map must not name one.

    Raises:
        ValueError: an unknown or repeated name, a joint the robot does not have (``q7`` on a
            6-joint robot), an incomplete group (``qd1..qd5`` of 6), no ``t``, no positions, or
            neither torques nor currents.
    """
    tokens = [s.strip() for s in spec.split(",")] if isinstance(spec, str) else [str(s).strip() for s in spec]
    names: list[str] = []
    for token in tokens:
        if not token:
            raise ValueError(f"column map: empty name at position {len(names) + 1} (two commas in a row?)")
        names.extend(_expand(token))
    n = int(robot.n)
    groups: dict[str, dict[int, int]] = {g: {} for g in _GROUPS}
    aux: dict[str, int] = {}
    t_col = None
    for col, name in enumerate(names):
        where = f"column map: column {col + 1} '{name}'"
        if name == "_":
            continue
        if name == "t":
            if not time:
                raise ValueError(f"{where}: a log read with a sampling period (--period, period= in Python) has "
                                 f"no time column; map the column as _ or give no period")
            if t_col is not None:
                raise ValueError(f"{where}: 't' appears twice (columns {t_col + 1} and {col + 1})")
            t_col = col
            continue
        if name.startswith("x:"):
            key = name[2:].strip()
            if not key:
                raise ValueError(f"{where}: an auxiliary column needs a name (x:NAME)")
            if key in aux:
                raise ValueError(f"{where}: auxiliary name '{key}' appears twice")
            aux[key] = col
            continue
        m = _NAME.match(name)
        if not m:
            raise ValueError(f"{where} is unknown: expected t, q1..q{n}, qd1..qd{n}, tau1..tau{n}, "
                             f"i1..i{n}, _ or x:NAME")
        group, joint = m.group(1), int(m.group(2))
        if not 1 <= joint <= n:
            raise ValueError(f"{where}: robot '{robot.name}' has {n} joints ({group}1..{group}{n})")
        if joint in groups[group]:
            raise ValueError(f"{where} appears twice")
        groups[group][joint] = col
    if t_col is None and time:
        raise ValueError("column map: no time column 't' (a log without one: give its sampling period with "
                         "--period S, period= in Python)")
    for group, found in groups.items():
        if found and len(found) != n:
            missing = next(j for j in range(1, n + 1) if j not in found)
            raise ValueError(f"column map: '{group}{missing}' is missing ({group}1..{group}{n} come all "
                             f"together or not at all)")
    if not groups["q"]:
        raise ValueError(f"column map: no joint positions (q1..q{n})")
    if not groups["tau"] and not groups["i"]:
        raise ValueError(f"column map: neither joint torques (tau1..tau{n}) nor motor currents (i1..i{n})")

    def cols(group: str) -> tuple[int, ...]:
        return tuple(groups[group][j] for j in range(1, n + 1)) if groups[group] else ()

    return ColumnMap(names=tuple(names), t=-1 if t_col is None else t_col, q=cols("q"), qd=cols("qd"), tau=cols("tau"),
                     i=cols("i"), aux=tuple(aux.items()))


def rtde_columns(header: Sequence[str], robot: rx90sym.Robot) -> str | None:
    """The column map of a UR RTDE recording from its header (``timestamp``, ``actual_q_0`` ...,
    other columns ignored), or None when ``header`` is not one: a ``timestamp`` column and
    ``actual_q_0``..``actual_q_{n-1}`` are needed."""
    names = [h.strip() for h in header]
    wanted = [f"actual_q_{j}" for j in range(robot.n)]
    if "timestamp" not in names or not set(wanted) <= set(names):
        return None
    out = []
    for name in names:
        match = re.fullmatch(r"(.+)_(\d+)", name)
        if name == "timestamp":
            out.append("t")
        elif match and match.group(1) in RTDE_NAMES and int(match.group(2)) < robot.n:
            out.append(f"{RTDE_NAMES[match.group(1)]}{int(match.group(2)) + 1}")
        else:
            out.append("_")
    return ",".join(out)


def rtde_refusal(header: Sequence[str], robot: rx90sym.Robot) -> str | None:
    """Why a header :func:`rtde_columns` recognises cannot be read without a column map (None: it can):
    the RTDE columns found and used, and the motor currents ``actual_current_j`` missing, the only
    effort this reader takes from an RTDE log (``target_moment_j`` is the controller's target, kept
    as an auxiliary, never a torque)."""
    names = {h.strip() for h in header}
    n = robot.n
    missing = [f"actual_current_{j}" for j in range(n) if f"actual_current_{j}" not in names]
    if not missing:
        return None

    def listed(prefix: str) -> str | None:
        have = [j for j in range(n) if f"{prefix}_{j}" in names]
        if not have:
            return None
        return (f"{prefix}_0..{prefix}_{n - 1}" if len(have) == n
                else ", ".join(f"{prefix}_{j}" for j in have))

    found = [f"{listed(prefix)} ({what})" for prefix, what in (
        ("actual_q", "positions"), ("actual_qd", "velocities"), ("actual_current", "motor currents"),
        ("target_moment", "the controller's target torques, kept as x:target_moment1.., never a torque"),
        ("target_current", "target currents, kept as x:target_current1..")) if listed(prefix)]
    gone = (f"actual_current_0..actual_current_{n - 1}" if len(missing) == n else ", ".join(missing))
    return (f"the header was recognised as a UR RTDE log: found timestamp, {', '.join(found)}; missing "
            f"{gone} (motor currents, the only effort read from an RTDE log: record them; --gains then turns "
            f"them into joint torques)")
