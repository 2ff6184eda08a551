"""The fit file: what an identification was run with and found, in one versioned JSON.

Written by :meth:`identify.Fit.save` (and ``rx90 identify --json``), read by
:func:`identify.load_fit`. Its records each have their own ``to_json``/``from_json``
(``model`` below, ``processing`` in :mod:`identify.observation.processing`, the result in
:mod:`identify.estimation.results`), so a new field goes into one record. ``schema_version``
says which layout a file has; a file without it, or of an unknown version, is refused.
"""
from __future__ import annotations

from dataclasses import MISSING, asdict, dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from rx90sym.files import file_sha256, read_json
import rx90sym

from identify.fitting.embedded import EmbeddedRobot, robot_differences
from identify.io.gains import DriveGains

__all__ = ["SCHEMA_VERSION", "FitModel", "read_fit_file", "robot_file_hash", "toolkit_version",
           "robot_of", "gains_of"]

#: Layout of the fit file. 2: the first with ``schema_version`` and ``processing`` (1: the
#: identification JSON before them); 3: the rest policy may be one per joint (a list), and the
#: processing's ``rest`` and ``cross_validate`` may be null (open, automatic); the friction form
#: (``processing.friction``, ``model.friction.form``) may be one per joint (a list; a file whose
#: form is the same on every joint keeps the one name, so earlier version-3 files read the same).
#: Version 2 files are still read (their fields mean the same in 3). 4: ``model.description`` embeds
#: the robot description (:class:`~identify.fitting.embedded.EmbeddedRobot`) and ``model.robot_file``
#: is absolute; versions 2 and 3 are still read (their robot from the recorded path or the name).
#: Also in 4: ``baseline`` (the plain OLS baseline's parameters and figures, identify.fitting.baseline),
#: ``model.offset_joints`` (torque offsets chosen per joint) and the processing choice's ``offsets``,
#: ``offset_candidate`` and ``scored_against``; a file without them reads None.
#: 5: the second yardstick, ``user_model`` (the model the user had: the description's rigid bodies as written
#: plus viscous, Coulomb and offset per joint fitted on the baseline's samples; its parameters over the
#: baseline's names, where its bodies come from, its figures: identify.fitting.user_model.UserModel), or
#: ``{"computed": false, "reason"}`` where the description has no inertial parameters; the validation's
#: ``user_model_rms_error[_moving]``, ``user_model_note``, ``yardstick_ratio[_moving]``,
#: ``better_yardstick[_moving]`` and ``beats_both[_moving]``. Versions 2-4 are still read (no model the user
#: had: the validation says so).
#: Also in 5 (the other fields of this version, each with its line here):
#: ``identified`` (the identified model: its standard parameters, the prior, its weight λ and its
#: choice, the data's share of each base parameter); a file without it reads None (a consistent result
#: is its own identified model).
SCHEMA_VERSION = 5
#: Older layouts read as they are.
READABLE_VERSIONS = (2, 3, 4, SCHEMA_VERSION)


def robot_file_hash(robot: rx90sym.Robot) -> str | None:
    """SHA-256 of the robot file the description was read from (None for a robot built in memory)."""
    return file_sha256(robot.source) if robot.source else None


def toolkit_version() -> str:
    try:
        return metadata.version("rx90sym")
    except metadata.PackageNotFoundError:
        return "unknown"


@dataclass(frozen=True)
class FitModel:
    """The model and the achieved signal processing of one identification (the file's ``model``).

    robot: name; robot_file: path it was read from; robot_file_sha256; toolkit_version;
    convention: angles of the files ("controller"/"model" or None: from each file); gains: the drive
    gains' dictionary (None: torque recordings); rest: a policy of
    identify.observation.processing.REST_POLICIES, or one per joint; min_velocity
    [rad/s] (None: no rest mask); coulomb_sign: the coupling's Coulomb form (None: no coupling);
    offsets: torque offsets OFFj identified; spring: "default" | "none" | "identify" |
    "identify-k" | a table file; cutoff_hz (the one used, also when chosen on the data),
    decimate_to_hz (None: no decimation), rate_hz (achieved), delay_s: torque lag compensated;
    tip: the tip link of a URDF robot (None otherwise); snap_rad [rad], snap_length_m [m]: the
    tolerances its joint origins were snapped with (rx90sym.urdf_snap; reused when the robot is
    rebuilt); friction: the smooth friction form (one, or
    a list of one per joint) and its velocity scales (null on a Coulomb joint;
    identify.friction.scales.VelocityScales.to_json), the presliding travels; None: Coulomb;
    description: the robot description itself (EmbeddedRobot.to_json; None: a robot built in memory,
    or a file of schema version 3 or older); offset_joints: the joints (1-based) the cross-validated
    choice gave a torque offset OFFj (None: none; an older file reads None); torque_left_out: the joints
    (1-based) whose torque was constant in the fitted recordings (a channel not logged), left out of the
    fit and not predicted (None: none; an older file reads None).
    """

    robot: str
    robot_file: str | None
    robot_file_sha256: str | None
    toolkit_version: str
    convention: str | None
    gains: dict | None
    rest: str | tuple[str, ...]
    min_velocity: float | None
    coulomb_sign: str | None
    offsets: bool
    spring: str
    cutoff_hz: float
    decimate_to_hz: float | None
    rate_hz: float
    delay_s: float
    tip: str | None = None
    friction: dict | None = None
    description: dict | None = None
    snap_rad: float | None = None       # a URDF's joint origin tolerances (rx90sym.urdf_snap); None: not a
    snap_length_m: float | None = None  # URDF, or a file written before snapping (read as 1e-9 rad, 0 m)
    offset_joints: tuple[int, ...] | None = None
    torque_left_out: tuple[int, ...] | None = None

    @classmethod
    def of(cls, robot: rx90sym.Robot, **fields: Any) -> "FitModel":
        emb = EmbeddedRobot.of(robot)
        fields.setdefault("description", None if emb is None else emb.to_json())
        return cls(robot=robot.name, robot_file=str(Path(robot.source).resolve()) if robot.source else None,
                   robot_file_sha256=robot_file_hash(robot), toolkit_version=toolkit_version(),
                   coulomb_sign=robot.coupling.coulomb_sign if robot.coupling is not None else None,
                   offsets=bool(robot.offsets),
                   tip=robot.urdf.tip if getattr(robot, "urdf", None) is not None else None,
                   **_snap_of(robot), **fields)

    def to_json(self) -> dict[str, Any]:
        d = asdict(self)
        for key in ("rest", "offset_joints", "torque_left_out"):  # tuples written as the lists they read back as
            if isinstance(d.get(key), tuple):
                d[key] = list(d[key])
        return d

    to_dict = to_json

    @classmethod
    def from_json(cls, d: dict[str, Any], where: str = "fit file") -> "FitModel":
        names = cls.__dataclass_fields__
        required = [k for k, f in names.items() if f.default is MISSING]
        missing = [k for k in required if k not in d]
        if missing:
            raise ValueError(f"{where}: 'model' lacks {', '.join(missing)} (written by an older version?)")
        values = {k: d[k] for k in names if k in d}
        if isinstance(values["rest"], list):  # one policy per joint
            values["rest"] = tuple(values["rest"])
        for key in ("offset_joints", "torque_left_out"):
            if values.get(key) is not None:
                values[key] = tuple(int(j) for j in values[key])
        return cls(**values)

    from_dict = from_json

    def filtering(self) -> dict[str, Any]:
        """Keyword arguments of predict/validate that reproduce the fit's processing."""
        return {"cutoff": self.cutoff_hz, "decimate_to": self.decimate_to_hz,
                "min_velocity": self.min_velocity, "delay": self.delay_s,
                "spring": self.spring != "none", "rest": self.rest}

    def embedded(self) -> EmbeddedRobot | None:
        """The embedded robot description (None in files of schema version 3 or older)."""
        return None if self.description is None else EmbeddedRobot.from_json(self.description)

    def check_robot(self, robot: rx90sym.Robot) -> str:
        """A warning ('' if none) when ``robot`` is not the description the fit used."""
        emb = self.embedded()
        if emb is not None:
            if file_sha256(robot.source) == emb.robot_sha256 if robot.source else False:
                return emb.differs_from(self.robot_file)
            listed = robot_differences(robot_of(self), robot)
            return (f"robot {robot.name!r} ({robot.source or 'built in memory'}) is used instead of the "
                    f"description embedded in the fit" + (": " + "; ".join(listed) if listed else
                                                           " (same geometry and limits)"))
        if robot.name != self.robot:
            return f"the identification is of robot {self.robot!r}, not {robot.name!r}"
        digest = robot_file_hash(robot)
        if self.robot_file_sha256 and digest and digest != self.robot_file_sha256:
            return (f"robot file {robot.source} changed since the identification "
                    f"(sha256 {digest[:12]} vs {self.robot_file_sha256[:12]})")
        return ""


def read_fit_file(path: str | Path) -> dict[str, Any]:
    """The parsed fit file, its layout checked (ValueError naming the file otherwise)."""
    data = read_json(path)   # ValueError naming the file (and line, column)
    if not isinstance(data, dict) or "parameters" not in data:
        raise ValueError(f"{path}: not a fit file (no 'parameters')")
    version = data.get("schema_version")
    if version is None:
        raise ValueError(f"{path}: a fit file without 'schema_version' (written before version "
                         f"{SCHEMA_VERSION} of the format): identify again to write it in the current format")
    if version not in READABLE_VERSIONS:
        raise ValueError(f"{path}: fit file schema_version {version!r} is not supported "
                         f"(this version reads {', '.join(map(str, READABLE_VERSIONS))})")
    if "model" not in data:
        raise ValueError(f"{path}: no 'model' record")
    return data


#: How a fit file without snap tolerances (written before them) had its URDF read: rotation
#: entries within 1e-9 of 0 or +-1 made exact, lengths as written.
LEGACY_SNAP_RAD = 1e-9


def _snap_of(robot: rx90sym.Robot) -> dict[str, float | None]:
    urdf = getattr(robot, "urdf", None)
    return {"snap_rad": urdf.snap, "snap_length_m": urdf.snap_length} if urdf is not None else {}


def robot_of(model: FitModel, spec: str | None = None) -> rx90sym.Robot:
    """The robot the identification used, with its friction form, offsets and spring: rebuilt from
    the description embedded in the fit file (schema 4), else from its recorded file or name.
    ``spec`` (a name or file) overrides it; ValueError when it cannot be the same arm (another
    joint count or other parameters; the lesser differences: :meth:`FitModel.check_robot`)."""
    emb = model.embedded()
    if spec is not None and emb is not None:
        robot = _rebuilt(model, spec, None)
        robot_differences(robot_of(model, None), robot)  # the embedded one: raises when they cannot be the same arm
        return robot
    if emb is not None:
        return _rebuilt(model, str(emb.path()), emb.acceleration)
    return _rebuilt(model, spec, None)


def _rebuilt(model: FitModel, spec: str | None, acceleration: Any) -> rx90sym.Robot:
    source = spec or (model.robot_file if model.robot_file and Path(model.robot_file).is_file() else model.robot)
    if model.spring in ("identify", "identify-k"):
        raise ValueError(f"the identification identified its spring ({model.spring}): the robot cannot "
                         "be rebuilt with it yet; validate within the identification instead")
    urdf = str(source).lower().endswith(".urdf")
    snap = ({"snap": model.snap_rad, "snap_length": model.snap_length_m} if model.snap_rad is not None
            else {"snap": LEGACY_SNAP_RAD, "snap_length": 0.0}) if urdf else {}
    if acceleration is not None and urdf:
        snap["acceleration"] = list(acceleration)
    robot = rx90sym.load_robot(source, offsets=model.offsets, tip=model.tip if urdf else None, **snap)
    if model.coulomb_sign is not None and robot.coupling is not None:
        robot = robot.with_options(coupling=rx90sym.Coupling(robot.coupling.joints, model.coulomb_sign))
    if model.spring == "none":
        robot = robot.with_options(spring=None)
    elif model.spring != "default":
        from rx90sym.spring import read_spring_table

        joint = robot.spring.joint if robot.spring is not None else 1
        robot = robot.with_options(spring=rx90sym.Spring(joint=joint, table=read_spring_table(model.spring)))
    return robot


def gains_of(model: FitModel) -> DriveGains | None:
    """The drive gains the identification applied to current recordings (None: torque recordings)."""
    if model.gains is None:
        return None
    g = model.gains
    std = None if g.get("std") is None else [np.nan if s is None else s for s in g["std"]]
    return DriveGains(np.asarray(g["gains"], dtype=float), side=str(g.get("side", "joint")),
                      current_offsets=g.get("current_offsets"), std=std, robot=str(g.get("robot", "")),
                      source="fit file")
