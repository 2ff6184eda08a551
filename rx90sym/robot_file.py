"""Robot files (TOML): the bundled robots and a user's own, loaded and validated the same way.

The format is strict: every section and key is in :data:`SCHEMA`; an unknown one is an error
naming the file, the line and the nearest valid name (a typo such as ``velocty`` would otherwise
leave a limit infinite). Every field, its unit and default: docs/robot-files.md.
"""
from __future__ import annotations

import difflib
import math
import tomllib
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from .description import Coupling, Limits, Robot
from .nominal_table import FLANGE_KEYS, NOMINAL_KEYS, NominalError, parse_flange, parse_nominal
from .spring import SPRING_CONSTANTS, Spring, read_spring_table
from .toml_lines import Lines, scan
from .urdf_snap import SNAP_LENGTH_M, SNAP_RAD

ROBOTS_DIR = Path(__file__).parent / "robots"
JOINT_FIELDS = ("sigma", "alpha", "d", "theta", "r")

# Every section and its keys. "" is the top level; "joints" is the array of [[joints]] tables.
# [staubli] is the old name of [controller] (still accepted).
_OFFSETS = ("offsets", "offsets_deg", "rate_hz")  # rate_hz: the set-point stream rate [Hz]
SCHEMA: dict[str, tuple[str, ...]] = {
    "": ("name", "description", "n", "joint_names"),
    "joints": ("sigma", "alpha", "alpha_deg", "d", "theta", "theta_deg", "r", "d_label", "r_label"),
    "controller": _OFFSETS,
    "staubli": _OFFSETS,
    "limits": ("position_min", "position_min_deg", "position_max", "position_max_deg", "velocity",
               "velocity_deg_s", "acceleration", "acceleration_deg_s2", "torque"),
    "transmission": ("gear_ratios", "wrist_coupling"),
    "coupling": ("joints", "coulomb_sign"),
    "friction": ("asymmetric_coulomb",),
    "spring": ("joint", "k", "a", "b", "L0", "angle_offset", "angle_offset_deg", "table", "placeholder"),
    "nominal": NOMINAL_KEYS,     # prior parameters with their sources (rx90sym.nominal_table)
    "flange": FLANGE_KEYS,       # frame n -> the maker's tool flange
    # Read by the excitation's safety envelope (excitation/robot_geometry.py), not by the model.
    "excitation": ("mounting_plane_z", "tool_point"),
    "capsules": ("name", "frame", "a", "b", "radius"),
}
ARRAY_TABLES = ("joints", "capsules")  # [[...]] arrays of tables


class RobotFileError(ValueError):
    """A robot file that cannot be used; the message names the file, the line and the field."""


def bundled_robots() -> list[str]:
    """Names of the robots shipped with the package."""
    return sorted(p.stem for p in ROBOTS_DIR.glob("*.toml"))


def load_robot(name_or_path: str | Path = "rx90", offsets: bool = False,
               coulomb_sign: str | None = None, tip: str | None = None,
               asymmetric_coulomb: Any = None, acceleration: Any = None, snap: float = SNAP_RAD,
               snap_length: float = SNAP_LENGTH_M) -> Robot:
    """Load a bundled robot by name ("rx90", "tx40", "ur10e", "panda": :func:`bundled_robots`), a robot
    file or a URDF (``*.urdf``) by path. A bundled name always means the bundled robot, even when
    the working directory holds a file of that name (give such a file as ``./rx90``).

    offsets: append the per-joint torque offsets OFF1..OFFn to the parameters.
    coulomb_sign: override the coupling's Coulomb form ("paper" or "motor").
    tip: for a URDF, the link that ends the chain (rx90sym.urdf.load_urdf).
    asymmetric_coulomb: joint numbers (1-based) with FS+ / FS- instead of FS (overrides the file's
        ``[friction] asymmetric_coulomb``); () for none.
    acceleration: for a URDF, the joint acceleration limits [rad/s^2 or m/s^2], one number or one
        per joint (a URDF has none; rx90sym.urdf.load_urdf).
    snap [rad], snap_length [m]: for a URDF, joint origin angles this close to a multiple of pi/2
        and lengths this close to 0 are made exact, every change listed in a warning; snap=0
        turns both off (rx90sym.urdf_snap, docs/urdf.md). A robot file's angles are exact already:
        other values than these defaults are refused for it.
    """
    path = Path(name_or_path)
    if path.suffix.lower() == ".urdf":
        from .urdf import load_urdf

        if coulomb_sign is not None:
            raise RobotFileError(f"{path}: coulomb_sign given but a URDF robot has no coupling")
        if snap == 0 and snap_length not in (0, SNAP_LENGTH_M):
            raise RobotFileError(f"{path}: snap=0 turns snapping off, lengths included: snap_length="
                                 f"{snap_length!r} would be ignored (give snap > 0 or no snap_length)")
        robot = load_urdf(path, tip=tip, acceleration=acceleration, snap=snap, snap_length=snap_length)
        changes: dict[str, Any] = {"offsets": True} if offsets else {}
        if asymmetric_coulomb is not None:
            changes["asymmetric_coulomb"] = _joint_numbers(asymmetric_coulomb, robot.n,
                                                           f"{path}: asymmetric_coulomb")
        return robot.with_options(**changes) if changes else robot
    if tip is not None:
        raise RobotFileError(f"{path}: tip={tip!r} is for a URDF (*.urdf), not a robot file")
    if (snap, snap_length) != (SNAP_RAD, SNAP_LENGTH_M):
        raise RobotFileError(f"{path}: snap={snap!r}, snap_length={snap_length!r} are for a URDF (*.urdf): "
                             f"a robot file's angles and lengths are exact already")
    if acceleration is not None:
        raise RobotFileError(f"{path}: acceleration limits given, but a robot file has its own "
                             f"([limits] acceleration_deg_s2); the option is for a URDF (*.urdf)")
    # A bundled robot's bare name means the bundled robot, even when a file or folder of that name
    # lies in the working directory (write ./rx90 for such a file).
    bundled = isinstance(name_or_path, str) and name_or_path in bundled_robots()
    if bundled or (path.suffix != ".toml" and not path.exists()):
        candidate = ROBOTS_DIR / f"{name_or_path}.toml"
        if not candidate.exists():
            raise RobotFileError(f"unknown robot {str(name_or_path)!r}: not a file and not one of "
                                 f"the bundled robots {bundled_robots()}")
        path = candidate
    if not path.exists():
        raise RobotFileError(f"{path}: robot file not found")
    if path.is_dir():
        raise RobotFileError(f"{path}: is a folder, not a robot file")
    try:
        text = path.read_text(encoding="utf-8")
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise RobotFileError(f"{path}: not valid TOML ({exc})") from None
    robot = parse_robot(data, str(path), scan(text))
    changes: dict[str, Any] = {}
    if offsets:
        changes["offsets"] = True
    if coulomb_sign is not None:
        if robot.coupling is None:
            raise RobotFileError(f"{path}: coulomb_sign given but the robot has no [coupling]")
        changes["coupling"] = Coupling(robot.coupling.joints, _sign_option(coulomb_sign, str(path)))
    if asymmetric_coulomb is not None:
        changes["asymmetric_coulomb"] = _joint_numbers(asymmetric_coulomb, robot.n, f"{path}: asymmetric_coulomb")
    try:
        return robot.with_options(**changes) if changes else robot
    except ValueError as exc:
        raise RobotFileError(f"{path}: {exc}") from None


def _joint_numbers(value: Any, n: int, where: str) -> tuple[int, ...]:
    """1-based joint numbers -> 0-based tuple (refuses anything else)."""
    if not (isinstance(value, (list, tuple)) and all(isinstance(x, int) and not isinstance(x, bool)
                                                      and 1 <= x <= n for x in value)):
        raise RobotFileError(f"{where}: expected a list of joint numbers in 1..{n}, got {value!r}")
    return tuple(int(x) - 1 for x in value)


class _Where:
    """Error locations: 'file, line N: [section] ...'."""

    def __init__(self, source: str, lines: Lines | None) -> None:
        self.source, self.lines = source, lines or Lines()

    def __call__(self, table: str, key: str | None = None, index: int = 0) -> str:
        line = self.lines.key(table, key, index) if key is not None else None
        if line is None:
            line = self.lines.table(table, index)
        label = f"joints[{index + 1}]" if table == "joints" else (f"[{table}]" if table else "")
        place = self.source + (f", line {line}" if line is not None else "")
        return f"{place}: {label}" if label else place


def _nearest(name: str, valid: Any) -> str:
    match = difflib.get_close_matches(name, list(valid), n=1, cutoff=0.6)
    return match[0] if match else ""


def check_schema(data: dict, where: _Where) -> None:
    """Refuse unknown sections and keys, naming the nearest valid one."""
    sections = [s for s in SCHEMA if s]
    for key, value in data.items():
        if key in SCHEMA[""]:
            continue
        if key not in SCHEMA:
            near = _nearest(key, sections + list(SCHEMA[""]))
            hint = (f"; did you mean [{near}]?" if near in SCHEMA else f"; did you mean {near!r}?") if near else ""
            valid = ", ".join("[" + s + "]" for s in sections if s != "staubli")
            if isinstance(value, (dict, list)):
                line = where.lines.table(key)
                place = where.source + (f", line {line}" if line is not None else "")
                raise RobotFileError(f"{place}: unknown section [{key}]{hint} (valid sections: {valid})")
            raise RobotFileError(f"{where('', key)}: unknown key {key!r}{hint} (valid top-level keys: "
                                 f"{', '.join(SCHEMA[''])}; sections: {valid})")
        tables = value if key in ARRAY_TABLES and isinstance(value, list) else [value]
        for index, table in enumerate(tables):
            if not isinstance(table, dict):
                raise RobotFileError(f"{where(key, index=index)}: {key!r} must be a "
                                     f"{'[[' + key + ']] table' if key in ARRAY_TABLES else '[' + key + '] table'}")
            for field_name in table:
                if field_name not in SCHEMA[key]:
                    near = _nearest(field_name, SCHEMA[key])
                    raise RobotFileError(
                        f"{where(key, field_name, index)}: unknown key {field_name!r}"
                        + (f"; did you mean {near!r}?" if near else "")
                        + f" (valid keys: {', '.join(SCHEMA[key])})")
    if "controller" in data and "staubli" in data:
        raise RobotFileError(f"{where('staubli')}: give [controller] or its old name [staubli], not both")


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


def _vector_either(table: dict, key: str, n: int, where: Any, default: np.ndarray) -> np.ndarray:
    """A vector given as KEY (SI) or KEY with '_deg' / '_deg_s' / '_deg_s2' (degrees).

    where: a function key -> location text."""
    given = [k for k in (key, key + "_deg", key + "_deg_s", key + "_deg_s2") if k in table]
    if len(given) > 1:
        raise RobotFileError(f"{where(given[1])}: give {given[0]!r} or {given[1]!r}, not both")
    if not given:
        return default
    return _vector(table, given[0], n, where(given[0]), deg=given[0] != key)


def parse_robot(data: dict, source: str, lines: Lines | None = None) -> Robot:
    """Robot from the parsed TOML of a robot file (see docs/robot-files.md for the format).

    lines: where each table and key is written (rx90sym.toml_lines.scan), for error messages."""
    where = _Where(source, lines)
    check_schema(data, where)
    name = data.get("name")
    if not isinstance(name, str) or not name:
        raise RobotFileError(f"{where('', 'name')}: missing field 'name' (a string)")
    joints = data.get("joints")
    if not isinstance(joints, list) or not joints:
        raise RobotFileError(f"{source}: missing [[joints]] table (one per joint)")
    n = len(joints)
    if "n" in data and data["n"] != n:
        raise RobotFileError(f"{where('', 'n')}: field 'n' says {data['n']} joints but there are {n} "
                             f"[[joints]] rows")
    cols, d_labels, r_labels = _parse_joints(joints, where)

    section = "controller" if "controller" in data else "staubli"
    offsets = _vector_either(data.get(section, {}), "offsets", n,
                             lambda key: where(section, key), np.zeros(n))
    rate = data.get(section, {}).get("rate_hz")
    if rate is not None and (isinstance(rate, bool) or not isinstance(rate, (int, float)) or not rate > 0):
        raise RobotFileError(f"{where(section, 'rate_hz')}: rate_hz must be a number > 0 (Hz), got {rate!r}")
    limits = _parse_limits(data.get("limits", {}), n, offsets, lambda key: where("limits", key))
    gear, Rq, Rt = _parse_transmission(data.get("transmission", {}), n, lambda key: where("transmission", key))
    coupling = _parse_coupling(data["coupling"], n, where) if "coupling" in data else None
    spring = _parse_spring(data["spring"], n, source, lambda key: where("spring", key)) if "spring" in data else None
    names = data.get("joint_names", [])
    if not (isinstance(names, list) and all(isinstance(x, str) and x for x in names)
            and len(names) in (0, n) and len(set(names)) == len(names)):
        raise RobotFileError(f"{where('', 'joint_names')}: field 'joint_names' must list {n} distinct "
                             f"joint names (the names a ROS joint_states message uses)")
    friction = data.get("friction", {})
    asym = _joint_numbers(friction.get("asymmetric_coulomb", []), n, where("friction", "asymmetric_coulomb"))
    try:
        nominal = (parse_nominal(data["nominal"], n, lambda key: where("nominal", key or None))
                   if "nominal" in data else None)
        flange = parse_flange(data["flange"], lambda key: where("flange", key or None)) if "flange" in data else None
    except NominalError as exc:
        raise RobotFileError(str(exc)) from None
    robot = Robot(name=name, sigma=cols[0], alpha=cols[1], d=cols[2], theta=cols[3], r=cols[4],
                  limits=limits, d_labels=tuple(d_labels), r_labels=tuple(r_labels),
                  controller_offsets=offsets, gear_ratios=gear, Rq=Rq, Rt=Rt, spring=spring,
                  coupling=coupling, asymmetric_coulomb=asym, description=str(data.get("description", "")),
                  source=source, nominal=nominal, flange=flange, joint_names=tuple(names),
                  controller_rate=None if rate is None else float(rate))
    if nominal is not None:  # [nominal] bodies are a prior, never a gate: those not physical said once
        from .description_prior import DescriptionWarning, description_warning

        said = description_warning(robot)
        if said:
            warnings.warn(said, DescriptionWarning, stacklevel=3)
    return robot


def _parse_joints(joints: list, where: Any) -> tuple[list, list[str], list[str]]:
    """The [[joints]] rows: columns (sigma, alpha, d, theta, r) and the d and r labels."""
    rows = []
    d_labels, r_labels = [], []
    for j, row in enumerate(joints, 1):
        at = where("joints", index=j - 1)
        if "sigma" not in row:
            raise RobotFileError(f"{at}: missing field 'sigma'")
        if row["sigma"] not in (0, 1) or isinstance(row["sigma"], bool):
            raise RobotFileError(f"{where('joints', 'sigma', j - 1)}: unknown joint type sigma={row['sigma']!r} "
                                 f"(0 revolute, 1 prismatic)")
        for key in ("alpha", "theta"):
            if key not in row and f"{key}_deg" not in row:
                raise RobotFileError(f"{at}: missing field {key!r}")
        rows.append((int(row["sigma"]), _angle(row, "alpha", at), _number(row, "d", at),
                     _angle(row, "theta", at), _number(row, "r", at)))
        d_labels.append(str(row.get("d_label", f"D{j}")))
        r_labels.append(str(row.get("r_label", f"RL{j}")))
    return list(zip(*rows)), d_labels, r_labels


def _parse_coupling(c: dict, n: int, where: Any) -> Coupling:
    """The [coupling] table: the two coupled joints (1-based in the file) and the Coulomb sign."""
    pair = c.get("joints")
    if not (isinstance(pair, list) and len(pair) == 2 and all(isinstance(x, int) for x in pair)
            and 1 <= pair[0] <= n and 1 <= pair[1] <= n and pair[0] != pair[1]):
        raise RobotFileError(f"{where('coupling', 'joints')}: field 'joints' must be two distinct "
                             f"joint numbers in 1..{n}")
    return Coupling((pair[0] - 1, pair[1] - 1),
                    _sign_option(c.get("coulomb_sign", "paper"), where("coupling", "coulomb_sign")))


def _parse_limits(table: dict, n: int, controller_offsets: np.ndarray, where: Any) -> Limits:
    inf = np.full(n, np.inf)
    # Position limits are given in the controller's convention, stored in model (Khalil) angles.
    q_min = _vector_either(table, "position_min", n, where, -inf) - controller_offsets
    q_max = _vector_either(table, "position_max", n, where, inf) - controller_offsets
    bad = np.flatnonzero(q_min > q_max)
    if len(bad):
        raise RobotFileError(f"{where('position_min')}: position_min > position_max for joint {bad[0] + 1}")
    values = {key: _vector_either(table, key, n, where, inf) for key in ("velocity", "acceleration", "torque")}
    for key, v in values.items():
        bad = np.flatnonzero(v <= 0)
        if len(bad):
            given = next((k for k in table if k.startswith(key)), key)
            raise RobotFileError(f"{where(given)}: {key} limit of joint {bad[0] + 1} must be > 0 "
                                 f"(min > max)")
    return Limits(q_min, q_max, values["velocity"], values["acceleration"], values["torque"])


def _parse_transmission(table: dict, n: int, where: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    gear = _vector(table, "gear_ratios", n, where("gear_ratios")) if "gear_ratios" in table else np.ones(n)
    if np.any(gear == 0):
        raise RobotFileError(f"{where('gear_ratios')}: gear ratio of joint "
                             f"{int(np.argmin(np.abs(gear))) + 1} is 0")
    Rq, Rt = np.diag(gear), np.diag(gear)
    if "wrist_coupling" in table:
        pair = table["wrist_coupling"]
        if not (isinstance(pair, list) and len(pair) == 2 and all(isinstance(x, int) for x in pair)
                and 1 <= min(pair) and max(pair) <= n):
            raise RobotFileError(f"{where('wrist_coupling')}: field 'wrist_coupling' must be two joint "
                                 f"numbers in 1..{n}")
        a, b = pair[0] - 1, pair[1] - 1
        # Motor b turns when joint a turns: q_motor_b = N_b (q_a + q_b); tau_a gets N_b tau_motor_b.
        Rq[b, a] = gear[b]
        Rt[a, b] = gear[b]
    return gear, Rq, Rt


def _parse_spring(table: dict, n: int, source: str, where: Any) -> Spring:
    """[spring]: joint, then either a table or every constant of the model (no defaults: the
    RX90's are placeholders, and a partial spring must not silently take them)."""
    joint = table.get("joint")
    if isinstance(joint, bool) or not isinstance(joint, int) or not 1 <= joint <= n:
        raise RobotFileError(f"{where('joint' if 'joint' in table else None)}: field 'joint' must be "
                             f"a joint number in 1..{n}")
    placeholder = table.get("placeholder", False)
    if not isinstance(placeholder, bool):
        raise RobotFileError(f"{where('placeholder')}: field 'placeholder' must be true or false")
    if "table" in table:
        extra = [k for k in SPRING_CONSTANTS + ("angle_offset_deg",) if k in table]
        if extra:
            raise RobotFileError(f"{where(extra[0])}: give a spring 'table' or the model's constants, "
                                 f"not both")
        path = Path(source).parent / str(table["table"])
        try:
            spring_table = read_spring_table(str(path))
        except ValueError as exc:
            raise RobotFileError(f"{where('table')}: {exc}") from None
        return Spring(joint=joint - 1, table=spring_table, placeholder=placeholder)
    missing = [k for k in SPRING_CONSTANTS if k not in table and not (k == "angle_offset" and
                                                                       "angle_offset_deg" in table)]
    if missing:
        raise RobotFileError(
            f"{where(None)}: the spring model needs {', '.join(SPRING_CONSTANTS)} (missing "
            f"{', '.join(missing)}; no defaults). Give them, a 'table' CSV, or remove [spring] and "
            f"identify the spring from data (rx90 identify --spring identify --spring-joint {joint})")
    values = {k: _number(table, k, where(k)) for k in ("k", "a", "b", "L0")}
    for k in ("a", "b"):
        if values[k] <= 0:
            raise RobotFileError(f"{where(k)}: field {k!r} must be > 0")
    offset_key = "angle_offset_deg" if "angle_offset_deg" in table else "angle_offset"
    offset = _angle(table, "angle_offset", where(offset_key))
    return Spring(joint=joint - 1, angle_offset=offset, placeholder=placeholder, **values)
