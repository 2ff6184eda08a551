"""Robot files (TOML): the bundled robots and a user's own, loaded and validated the same way."""
from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from .description import Coupling, Limits, Robot
from .spring import Spring, read_spring_table

ROBOTS_DIR = Path(__file__).parent / "robots"
JOINT_FIELDS = ("sigma", "alpha", "d", "theta", "r")


class RobotFileError(ValueError):
    """A robot file that cannot be used; the message names the file and the field."""


def bundled_robots() -> list[str]:
    """Names of the robots shipped with the package."""
    return sorted(p.stem for p in ROBOTS_DIR.glob("*.toml"))


def load_robot(name_or_path: str | Path = "rx90", offsets: bool = False,
               coulomb_sign: str | None = None) -> Robot:
    """Load a bundled robot by name ("rx90", "tx40") or a robot file by path.

    offsets: append the per-joint torque offsets OFF1..OFFn to the parameters.
    coulomb_sign: override the coupling's Coulomb form ("paper" or "motor").
    """
    path = Path(name_or_path)
    if path.suffix != ".toml" and not path.exists():
        candidate = ROBOTS_DIR / f"{name_or_path}.toml"
        if not candidate.exists():
            raise RobotFileError(f"unknown robot {str(name_or_path)!r}: not a file and not one of "
                                 f"the bundled robots {bundled_robots()}")
        path = candidate
    if not path.exists():
        raise RobotFileError(f"{path}: robot file not found")
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise RobotFileError(f"{path}: not valid TOML ({exc})") from None
    robot = parse_robot(data, str(path))
    changes: dict[str, Any] = {}
    if offsets:
        changes["offsets"] = True
    if coulomb_sign is not None:
        if robot.coupling is None:
            raise RobotFileError(f"{path}: coulomb_sign given but the robot has no [coupling]")
        changes["coupling"] = Coupling(robot.coupling.joints, _sign_option(coulomb_sign, str(path)))
    return robot.with_options(**changes) if changes else robot


def _sign_option(value: Any, where: str) -> str:
    if value not in ("paper", "motor"):
        raise RobotFileError(f"{where}: coupling.coulomb_sign must be 'paper' or 'motor', got {value!r}")
    return value


def _number(table: dict, key: str, where: str, default: Any = None) -> float:
    if key not in table:
        if default is None:
            raise RobotFileError(f"{where}: missing field {key!r}")
        return default
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise RobotFileError(f"{where}: field {key!r} must be a finite number, got {value!r}")
    return float(value)


def _angle(table: dict, key: str, where: str) -> float:
    """An angle given as KEY (rad) or KEY_deg (degrees)."""
    if f"{key}_deg" in table and key in table:
        raise RobotFileError(f"{where}: give {key!r} or {key + '_deg'!r}, not both")
    if f"{key}_deg" in table:
        return math.radians(_number(table, f"{key}_deg", where))
    return _number(table, key, where)


def _vector(table: dict, key: str, n: int, where: str, deg: bool = False) -> np.ndarray:
    value = table[key]
    if not isinstance(value, list) or len(value) != n:
        got = len(value) if isinstance(value, list) else type(value).__name__
        raise RobotFileError(f"{where}: field {key!r} needs {n} values (one per joint), got {got}")
    for i, v in enumerate(value, 1):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise RobotFileError(f"{where}: field {key!r}, joint {i}: not a finite number ({v!r})")
    arr = np.array(value, dtype=float)
    return np.radians(arr) if deg else arr


def _vector_either(table: dict, key: str, n: int, where: str, default: np.ndarray) -> np.ndarray:
    """A vector given as KEY (SI) or KEY with '_deg' / '_deg_s' / '_deg_s2' (degrees)."""
    for suffix in ("_deg", "_deg_s", "_deg_s2"):
        if key + suffix in table:
            return _vector(table, key + suffix, n, where, deg=True)
    if key in table:
        return _vector(table, key, n, where)
    return default


def parse_robot(data: dict, source: str) -> Robot:
    """Robot from the parsed TOML of a robot file (see robots/rx90.toml for the format)."""
    name = data.get("name")
    if not isinstance(name, str) or not name:
        raise RobotFileError(f"{source}: missing field 'name'")
    joints = data.get("joints")
    if not isinstance(joints, list) or not joints:
        raise RobotFileError(f"{source}: missing [[joints]] table (one per joint)")
    n = len(joints)
    if "n" in data and data["n"] != n:
        raise RobotFileError(f"{source}: field 'n' says {data['n']} joints but there are {n} "
                             f"[[joints]] rows")
    rows = []
    d_labels, r_labels = [], []
    for j, row in enumerate(joints, 1):
        where = f"{source}: joints[{j}]"
        if "sigma" not in row:
            raise RobotFileError(f"{where}: missing field 'sigma'")
        if row["sigma"] not in (0, 1) or isinstance(row["sigma"], bool):
            raise RobotFileError(f"{where}: unknown joint type sigma={row['sigma']!r} "
                                 f"(0 revolute, 1 prismatic)")
        for key in ("alpha", "theta"):
            if key not in row and f"{key}_deg" not in row:
                raise RobotFileError(f"{where}: missing field {key!r}")
        unknown = set(row) - {"sigma", "alpha", "alpha_deg", "d", "theta", "theta_deg", "r",
                              "d_label", "r_label"}
        if unknown:
            raise RobotFileError(f"{where}: unknown field(s) {sorted(unknown)}")
        rows.append((int(row["sigma"]), _angle(row, "alpha", where), _number(row, "d", where),
                     _angle(row, "theta", where), _number(row, "r", where)))
        d_labels.append(str(row.get("d_label", f"D{j}")))
        r_labels.append(str(row.get("r_label", f"RL{j}")))
    cols = list(zip(*rows))

    staubli = data.get("staubli", {})
    offsets = _vector_either(staubli, "offsets", n, f"{source}: [staubli]", np.zeros(n))

    limits = _parse_limits(data.get("limits", {}), n, offsets, f"{source}: [limits]")
    gear, Rq, Rt = _parse_transmission(data.get("transmission", {}), n, f"{source}: [transmission]")
    coupling = None
    if "coupling" in data:
        where = f"{source}: [coupling]"
        c = data["coupling"]
        pair = c.get("joints")
        if not (isinstance(pair, list) and len(pair) == 2 and all(isinstance(x, int) for x in pair)
                and 1 <= pair[0] <= n and 1 <= pair[1] <= n and pair[0] != pair[1]):
            raise RobotFileError(f"{where}: field 'joints' must be two distinct joint numbers in 1..{n}")
        coupling = Coupling((pair[0] - 1, pair[1] - 1), _sign_option(c.get("coulomb_sign", "paper"), where))
    spring = _parse_spring(data["spring"], n, source) if "spring" in data else None
    return Robot(name=name, sigma=cols[0], alpha=cols[1], d=cols[2], theta=cols[3], r=cols[4],
                 limits=limits, d_labels=tuple(d_labels), r_labels=tuple(r_labels),
                 staubli_offsets=offsets, gear_ratios=gear, Rq=Rq, Rt=Rt, spring=spring,
                 coupling=coupling, description=str(data.get("description", "")), source=source)


def _parse_limits(table: dict, n: int, staubli_offsets: np.ndarray, where: str) -> Limits:
    inf = np.full(n, np.inf)
    # Position limits are given in the controller's (Staubli) convention, stored in Khalil angles.
    q_min = _vector_either(table, "position_min", n, where, -inf) - staubli_offsets
    q_max = _vector_either(table, "position_max", n, where, inf) - staubli_offsets
    bad = np.flatnonzero(q_min > q_max)
    if len(bad):
        raise RobotFileError(f"{where}: position_min > position_max for joint {bad[0] + 1}")
    qd = _vector_either(table, "velocity", n, where, inf)
    qdd = _vector_either(table, "acceleration", n, where, inf)
    tau = _vector_either(table, "torque", n, where, inf)
    for key, v in (("velocity", qd), ("acceleration", qdd), ("torque", tau)):
        bad = np.flatnonzero(v <= 0)
        if len(bad):
            raise RobotFileError(f"{where}: {key} limit of joint {bad[0] + 1} must be > 0 "
                                 f"(min > max)")
    return Limits(q_min, q_max, qd, qdd, tau)


def _parse_transmission(table: dict, n: int, where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    gear = _vector(table, "gear_ratios", n, where) if "gear_ratios" in table else np.ones(n)
    if np.any(gear == 0):
        raise RobotFileError(f"{where}: gear ratio of joint {int(np.argmin(np.abs(gear))) + 1} is 0")
    Rq, Rt = np.diag(gear), np.diag(gear)
    if "wrist_coupling" in table:
        pair = table["wrist_coupling"]
        if not (isinstance(pair, list) and len(pair) == 2 and all(isinstance(x, int) for x in pair)
                and 1 <= min(pair) and max(pair) <= n):
            raise RobotFileError(f"{where}: field 'wrist_coupling' must be two joint numbers in 1..{n}")
        a, b = pair[0] - 1, pair[1] - 1
        # Motor b turns when joint a turns: q_motor_b = N_b (q_a + q_b); tau_a gets N_b tau_motor_b.
        Rq[b, a] = gear[b]
        Rt[a, b] = gear[b]
    return gear, Rq, Rt


def _parse_spring(table: dict, n: int, source: str) -> Spring:
    where = f"{source}: [spring]"
    joint = table.get("joint", 2)
    if not isinstance(joint, int) or not 1 <= joint <= n:
        raise RobotFileError(f"{where}: field 'joint' must be a joint number in 1..{n}")
    spring_table = None
    if "table" in table:
        path = Path(source).parent / str(table["table"])
        try:
            spring_table = read_spring_table(str(path))
        except ValueError as exc:
            raise RobotFileError(f"{where}: {exc}") from None
    offset = _angle(table, "angle_offset", where) if ("angle_offset" in table or "angle_offset_deg" in table) else math.pi / 2
    values = {k: _number(table, k, where, default) for k, default in
              (("k", 4000.0), ("a", 0.10), ("b", 0.30), ("L0", 0.05))}
    for k in ("a", "b"):
        if values[k] <= 0:
            raise RobotFileError(f"{where}: field {k!r} must be > 0")
    return Spring(joint=joint - 1, angle_offset=offset, table=spring_table, **values)
