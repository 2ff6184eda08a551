"""What an identification was run with: the model record stored in its JSON and reused by
``predict``, ``--validate`` and payload runs (one filtering for fit and validation)."""
from __future__ import annotations

import hashlib
from dataclasses import MISSING, asdict, dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

import rx90sym

__all__ = ["FitModel", "robot_file_hash", "toolkit_version"]


def robot_file_hash(robot: rx90sym.Robot) -> str | None:
    """SHA-256 of the robot file the description was read from (None for a robot built in memory)."""
    path = Path(robot.source) if robot.source else None
    if path is None or not path.is_file():
        return None
    return hashlib.sha256(path.read_bytes()).hexdigest()


def toolkit_version() -> str:
    try:
        return metadata.version("rx90sym")
    except metadata.PackageNotFoundError:
        return "unknown"


@dataclass(frozen=True)
class FitModel:
    """The model and signal processing of one identification.

    robot: name; robot_file: path it was read from; robot_file_sha256; toolkit_version;
    convention: angles of the files ("staubli"/"khalil" or None: from each file); gains: the drive
    gains' dictionary (None: torque recordings); rest: "drop" | "zero-coulomb"; min_velocity
    [rad/s] (None: no rest mask); coulomb_sign: the coupling's Coulomb form (None: no coupling);
    offsets: torque offsets OFFj identified; spring: "default" | "none" | "identify" |
    "identify-k" | a table file; cutoff_hz, decimate_to_hz (None: no decimation), rate_hz
    (achieved), delay_s: torque lag compensated; tip: the tip link of a URDF robot (None otherwise).
    """

    robot: str
    robot_file: str | None
    robot_file_sha256: str | None
    toolkit_version: str
    convention: str | None
    gains: dict | None
    rest: str
    min_velocity: float | None
    coulomb_sign: str | None
    offsets: bool
    spring: str
    cutoff_hz: float
    decimate_to_hz: float | None
    rate_hz: float
    delay_s: float
    tip: str | None = None

    @classmethod
    def of(cls, robot: rx90sym.Robot, **fields: Any) -> "FitModel":
        return cls(robot=robot.name, robot_file=robot.source or None,
                   robot_file_sha256=robot_file_hash(robot), toolkit_version=toolkit_version(),
                   coulomb_sign=robot.coupling.coulomb_sign if robot.coupling is not None else None,
                   offsets=bool(robot.offsets),
                   tip=robot.urdf.tip if getattr(robot, "urdf", None) is not None else None, **fields)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any], where: str = "identification JSON") -> "FitModel":
        names = cls.__dataclass_fields__
        required = [k for k, f in names.items() if f.default is MISSING]
        missing = [k for k in required if k not in d]
        if missing:
            raise ValueError(f"{where}: 'model' lacks {', '.join(missing)} (written by an older rx90?)")
        return cls(**{k: d[k] for k in names if k in d})

    def filtering(self) -> dict[str, Any]:
        """Keyword arguments of predict/validate that reproduce the fit's processing."""
        return {"cutoff": self.cutoff_hz, "decimate_to": self.decimate_to_hz,
                "min_velocity": self.min_velocity, "delay": self.delay_s,
                "spring": self.spring != "none", "rest": self.rest}

    def check_robot(self, robot: rx90sym.Robot) -> str:
        """A warning ('' if none) when ``robot`` is not the description the fit used."""
        if robot.name != self.robot:
            return f"the identification is of robot {self.robot!r}, not {robot.name!r}"
        digest = robot_file_hash(robot)
        if self.robot_file_sha256 and digest and digest != self.robot_file_sha256:
            return (f"robot file {robot.source} changed since the identification "
                    f"(sha256 {digest[:12]} vs {self.robot_file_sha256[:12]})")
        return ""
