"""A robot file's ``[nominal]`` and ``[flange]`` tables: the prior parameters and the tool flange.

``[nominal]`` gives, per link j in frame j of the file (Khalil frames), SI units:

- ``mass`` [kg; 0: unknown], ``com`` [m] (centre of mass), and the inertia about the centre of mass either
  as ``inertia`` ([Ixx, Iyy, Izz, Ixy, Ixz, Iyz], kg m^2, frame j's axes) or as ``shape`` (a
  solid of uniform density centred on the centre of mass, whose inertia is computed: a
  cylinder ``{kind, axis, radius, length}`` or a box ``{kind, size = [x, y, z]}``);
- ``rotor_inertia`` IAj [kg m^2], ``viscous`` FVj [N m s/rad], ``coulomb`` FSj [N m];
- for a coupled wrist ``coupled_viscous`` FVM, ``coupled_coulomb`` FSM;
- ``total_mass`` [kg]: the maker's figure for the whole arm (base included), for checks.

Every value has a source: each key KEY comes with ``KEY_source``, one text for the whole array
or one per link (a value derived here, not published, says "derived: how").

``[flange]``: ``translation`` [m] and ``rpy_deg`` (roll, pitch, yaw about fixed x, y, z) of the
maker's tool flange frame in frame n, with a ``source``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np

from .rigid_body import RigidBody

PER_LINK = ("mass", "com", "inertia", "shape", "rotor_inertia", "viscous", "coulomb")
SCALARS = ("coupled_viscous", "coupled_coulomb", "total_mass")
NOMINAL_KEYS: tuple[str, ...] = tuple(k for key in PER_LINK + SCALARS for k in (key, f"{key}_source"))
FLANGE_KEYS: tuple[str, ...] = ("translation", "rpy_deg", "source")
REQUIRED = ("mass", "com", "rotor_inertia", "viscous", "coulomb")

Where = Callable[[str], str]


class NominalError(ValueError):
    """A ``[nominal]`` or ``[flange]`` table that cannot be used (the message names the place)."""


@dataclass(frozen=True, eq=False)
class NominalTable:
    """The parsed ``[nominal]`` table of a robot file (arrays per link, SI units, frame j).

    inertia_com: (n, 3, 3) inertia about each link's centre of mass [kg m^2];
    sources: key -> one source text per link (scalars: one text)."""

    mass: np.ndarray
    com: np.ndarray
    inertia_com: np.ndarray
    rotor_inertia: np.ndarray
    viscous: np.ndarray
    coulomb: np.ndarray
    coupled_viscous: float | None
    coupled_coulomb: float | None
    total_mass: float | None
    sources: Mapping[str, tuple[str, ...]]

    def body(self, j: int) -> RigidBody:
        """Link j's (0-based) rigid body about frame j's origin."""
        return RigidBody.from_com(float(self.mass[j]), self.com[j], np.eye(3), self.inertia_com[j])


def cylinder_inertia(mass: float, axis: str, radius: float, length: float) -> np.ndarray:
    """Inertia [kg m^2] of a solid cylinder about its centre: m r^2 / 2 about its axis,
    m (3 r^2 + L^2) / 12 about the two others."""
    k = "xyz".index(axis)
    diagonal = np.full(3, mass * (3 * radius ** 2 + length ** 2) / 12.0)
    diagonal[k] = mass * radius ** 2 / 2.0
    return np.diag(diagonal)


def box_inertia(mass: float, size: np.ndarray) -> np.ndarray:
    """Inertia [kg m^2] of a solid box of edge lengths ``size`` about its centre."""
    x, y, z = (float(s) ** 2 for s in size)
    return np.diag([mass * (y + z) / 12.0, mass * (x + z) / 12.0, mass * (x + y) / 12.0])


def parse_flange(table: Any, where: Where) -> np.ndarray:
    """4x4 transform of the tool flange frame in frame n from a ``[flange]`` table."""
    if not isinstance(table, dict):
        raise NominalError(f"{where('')}: [flange] must be a table")
    for key in FLANGE_KEYS:
        if key not in table:
            raise NominalError(f"{where('')}: missing field {key!r} (translation [m], rpy_deg, source)")
    p = _numbers(table["translation"], 3, where("translation"), "translation")
    rpy = np.radians(_numbers(table["rpy_deg"], 3, where("rpy_deg"), "rpy_deg"))
    _source_texts(table["source"], 1, where("source"), "source")
    T = np.eye(4)
    T[:3, :3] = rpy_matrix(rpy)
    T[:3, 3] = p
    return T


def rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    """Rz(yaw) Ry(pitch) Rx(roll) (URDF's fixed-axis roll, pitch, yaw)."""
    r, p, y = (float(a) for a in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def parse_nominal(table: Any, n: int, where: Where) -> NominalTable:
    """The ``[nominal]`` table of a robot with n joints; errors name the key and the link."""
    if not isinstance(table, dict):
        raise NominalError(f"{where('')}: [nominal] must be a table")
    missing = [k for k in REQUIRED if k not in table]
    if "inertia" not in table and "shape" not in table:
        missing.append("inertia or shape")
    if "inertia" in table and "shape" in table:
        raise NominalError(f"{where('shape')}: give 'inertia' or 'shape', not both")
    if missing:
        raise NominalError(f"{where('')}: missing field(s) {', '.join(missing)}")
    sources = {}
    for key in PER_LINK + SCALARS:
        if key in table:
            if f"{key}_source" not in table:
                raise NominalError(f"{where(key)}: {key!r} has no {key + '_source'!r} (where does it come from?)")
            count = 1 if key in SCALARS else n
            sources[key] = _source_texts(table[f"{key}_source"], count, where(f"{key}_source"), f"{key}_source")
    mass = _numbers(table["mass"], n, where("mass"), "mass")
    com = np.array([_numbers(c, 3, where("com"), f"com, link {j}") for j, c in enumerate(_rows(table["com"], n, where("com"), "com"), 1)])
    inertia = _inertia(table, mass, n, where)
    scalars = {k: (_number(table[k], where(k), k) if k in table else None) for k in SCALARS}
    nominal = NominalTable(mass, com, inertia, *(_numbers(table[k], n, where(k), k) for k in
                                                ("rotor_inertia", "viscous", "coulomb")),
                           scalars["coupled_viscous"], scalars["coupled_coulomb"], scalars["total_mass"], sources)
    return nominal  # bodies that are not physical are a prior all the same (rx90sym.description_prior)


def _inertia(table: dict, mass: np.ndarray, n: int, where: Where) -> np.ndarray:
    if "inertia" in table:
        out = []
        for j, row in enumerate(_rows(table["inertia"], n, where("inertia"), "inertia"), 1):
            xx, yy, zz, xy, xz, yz = _numbers(row, 6, where("inertia"), f"inertia, link {j}")
            out.append([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        return np.array(out)
    out = []
    for j, shape in enumerate(_rows(table["shape"], n, where("shape"), "shape"), 1):
        at = f"{where('shape')}: shape of link {j}"
        if not isinstance(shape, dict) or shape.get("kind") not in ("cylinder", "box"):
            raise NominalError(f"{at}: expected {{kind = \"cylinder\" | \"box\", ...}}, got {shape!r}")
        m = float(mass[j - 1])
        if shape["kind"] == "box":
            size = _numbers(shape.get("size"), 3, at, "size")
            if np.any(size <= 0):
                raise NominalError(f"{at}: box sizes must be > 0 m")
            out.append(box_inertia(m, size))
            continue
        if shape.get("axis") not in ("x", "y", "z"):
            raise NominalError(f"{at}: cylinder axis must be \"x\", \"y\" or \"z\", got {shape.get('axis')!r}")
        radius, length = (_number(shape.get(k), at, k) for k in ("radius", "length"))
        if radius <= 0 or length <= 0:
            raise NominalError(f"{at}: cylinder radius and length must be > 0 m")
        out.append(cylinder_inertia(m, shape["axis"], radius, length))
    return np.array(out)


def _rows(value: Any, n: int, where: str, key: str) -> list:
    if not isinstance(value, list) or len(value) != n:
        got = len(value) if isinstance(value, list) else type(value).__name__
        raise NominalError(f"{where}: {key!r} needs {n} entries (one per link), got {got}")
    return value


def _number(value: Any, where: str, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise NominalError(f"{where}: {key!r} must be a finite number, got {value!r}")
    return float(value)


def _numbers(value: Any, count: int, where: str, key: str) -> np.ndarray:
    if not isinstance(value, list) or len(value) != count:
        got = len(value) if isinstance(value, list) else type(value).__name__
        raise NominalError(f"{where}: {key!r} needs {count} numbers, got {got}")
    return np.array([_number(v, where, key) for v in value])


def _source_texts(value: Any, count: int, where: str, key: str) -> tuple[str, ...]:
    if isinstance(value, str) and value.strip():
        return (value,) * count
    if (isinstance(value, list) and len(value) == count and
            all(isinstance(v, str) and v.strip() for v in value)):
        return tuple(value)
    raise NominalError(f"{where}: {key!r} must be a text, or {count} texts (one per link)")


def nominal_values(robot: Any, table: NominalTable) -> dict[str, float]:
    """Standard parameters name -> value [SI] of ``robot`` from its ``[nominal]`` table
    (eq. 4: inertia about frame j's origin, first moments m c); offsets OFFj are 0."""
    n = robot.n
    if len(table.mass) != n:
        raise NominalError(f"[nominal] has {len(table.mass)} links, robot {robot.name!r} has {n} joints")
    values: dict[str, float] = {}
    for j in range(n):
        XX, XY, XZ, YY, YZ, ZZ, MX, MY, MZ, M = table.body(j).vector()
        values.update({f"{k}{j + 1}": float(v) for k, v in zip(
            ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M"), (XX, XY, XZ, YY, YZ, ZZ, MX, MY, MZ, M))})
        values[f"IA{j + 1}"] = float(table.rotor_inertia[j])
        values[f"FV{j + 1}"] = float(table.viscous[j])
        values[f"FS{j + 1}"] = float(table.coulomb[j])
    if robot.coupling is not None:
        b = robot.coupling.joints[1] + 1
        for kind, value in (("FVM", table.coupled_viscous), ("FSM", table.coupled_coulomb)):
            if value is None:
                raise NominalError(f"robot {robot.name!r} has a coupled wrist: [nominal] needs "
                                   f"'coupled_viscous' and 'coupled_coulomb' ({kind}{b})")
            values[f"{kind}{b}"] = float(value)
    for j in robot.asymmetric_coulomb:  # FS+ = FS- = the nominal Coulomb; FSj's column is then 0
        values[f"FSP{j + 1}"] = values[f"FSN{j + 1}"] = values[f"FS{j + 1}"]
        values[f"FS{j + 1}"] = 0.0
    if robot.offsets:
        values.update({f"OFF{j + 1}": 0.0 for j in range(n)})
    return values
