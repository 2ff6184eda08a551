"""The robot description a fit was made with, embedded in its fit file (the file travels alone).

The description's text (a robot file or a URDF), its SHA-256, the files it reads (a robot file's
spring table), the tip and the acceleration limits given to a URDF. A fit file read elsewhere
rebuilds its robot from this copy, written once into the cache by its SHA-256
(:func:`rx90sym.compiled.cache_dir`), so a file moved, edited or deleted at the recorded path
changes nothing; ``--robot`` (``robot=``) overrides it, with the differences said.
"""
from __future__ import annotations

import hashlib
import os
import tempfile
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import rx90sym
from rx90sym.files import file_sha256

__all__ = ["EmbeddedRobot", "robot_differences"]


def _sha256(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


@dataclass(frozen=True)
class EmbeddedRobot:
    """robot_text: the description file's text; robot_format: "urdf" or "toml"; file_name: its
    name; robot_sha256: SHA-256 of robot_text (UTF-8); files: relative path -> text of the files it
    reads; acceleration: a URDF's acceleration limits as given [rad/s^2, m/s^2] (None: the loader's)."""

    robot_text: str
    robot_format: str
    file_name: str
    robot_sha256: str
    files: dict[str, str] = field(default_factory=dict)
    acceleration: tuple[float, ...] | None = None

    @classmethod
    def of(cls, robot: rx90sym.Robot) -> "EmbeddedRobot | None":
        """The description ``robot`` was read from (None for a robot built in memory)."""
        if not robot.source or not Path(robot.source).is_file():
            return None
        path = Path(robot.source)
        text = path.read_text()
        fmt = "urdf" if path.suffix.lower() == ".urdf" else "toml"
        files = {}
        if fmt == "toml":
            table = tomllib.loads(text).get("spring", {}).get("table")
            if table is not None:
                files[str(table)] = (path.parent / str(table)).read_text()
        from rx90sym.urdf import default_acceleration

        given = robot.urdf is not None and not default_acceleration(robot)
        acceleration = tuple(float(a) for a in robot.limits.qdd_max) if given else None
        return cls(text, fmt, path.name, _sha256(text), files, acceleration)

    def to_json(self) -> dict[str, Any]:
        return {"robot_text": self.robot_text, "robot_format": self.robot_format, "file_name": self.file_name,
                "robot_sha256": self.robot_sha256, "files": dict(self.files),
                "acceleration": None if self.acceleration is None else list(self.acceleration)}

    @classmethod
    def from_json(cls, d: dict[str, Any], where: str = "fit file") -> "EmbeddedRobot":
        try:
            emb = cls(str(d["robot_text"]), str(d["robot_format"]), str(d["file_name"]), str(d["robot_sha256"]),
                      {str(k): str(v) for k, v in (d.get("files") or {}).items()},
                      None if d.get("acceleration") is None else tuple(float(a) for a in d["acceleration"]))
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"{where}: model.description is malformed ({exc})") from None
        if _sha256(emb.robot_text) != emb.robot_sha256:
            raise ValueError(f"{where}: model.description: the robot text does not match its SHA-256 "
                             f"({_sha256(emb.robot_text)[:12]} vs {emb.robot_sha256[:12]}): the file was edited")
        if emb.robot_format not in ("urdf", "toml") or Path(emb.file_name).name != emb.file_name:
            raise ValueError(f"{where}: model.description: format {emb.robot_format!r}, name {emb.file_name!r}")
        return emb

    def path(self) -> Path:
        """The description written into the cache (once, by its SHA-256), with the files it reads."""
        from rx90sym.compiled import cache_dir

        folder = cache_dir() / "robots" / self.robot_sha256[:32]
        for rel, text in [(self.file_name, self.robot_text), *self.files.items()]:
            target = folder / rel
            if target.is_file() and target.read_text() == text:
                continue
            if not target.resolve().is_relative_to(folder.resolve()):
                raise ValueError(f"model.description: file {rel!r} lies outside the description's folder")
            target.parent.mkdir(parents=True, exist_ok=True)
            with tempfile.NamedTemporaryFile("w", dir=target.parent, delete=False, suffix=".tmp") as tmp:
                tmp.write(text)
            os.replace(tmp.name, target)  # atomic: a concurrent reader sees the whole file or none
        return folder / self.file_name

    def differs_from(self, recorded: str | None) -> str:
        """'' or a sentence saying the file at the recorded path is not the embedded description."""
        if not recorded or not Path(recorded).is_file():
            return ""
        digest = file_sha256(recorded)
        if digest == self.robot_sha256:
            return ""
        return (f"the robot file at the recorded path {recorded} differs from the description embedded in the fit "
                f"file (sha256 {str(digest)[:12]} vs {self.robot_sha256[:12]}): the embedded one is used "
                f"(give --robot to use another)")


def robot_differences(embedded: rx90sym.Robot, given: rx90sym.Robot) -> list[str]:
    """What differs between the fit's robot and one given instead: geometry, limits, gravity (plain
    numbers, 1-based joints). Raises ValueError when they cannot be the same arm (joint count or
    parameter names differ)."""
    if embedded.n != given.n:
        raise ValueError(f"the robot given has {given.n} joints, the fit's {embedded.name!r} {embedded.n}")
    if tuple(embedded.parameter_names) != tuple(given.parameter_names):
        only = sorted(set(embedded.parameter_names) ^ set(given.parameter_names))
        raise ValueError(f"the robot given has other parameters than the fit's ({', '.join(only[:8]) or 'order'})")
    out = []
    if embedded.name != given.name:
        out.append(f"name {embedded.name!r} vs {given.name!r}")
    for key in ("sigma", "alpha", "d", "theta", "r"):
        a, b = np.asarray(getattr(embedded, key), float), np.asarray(getattr(given, key), float)
        for j in np.flatnonzero(~np.isclose(a, b, rtol=0.0, atol=1e-12)):
            out.append(f"joint {j + 1}: {key} {a[j]:.9g} vs {b[j]:.9g}")
    for key in ("q_min", "q_max", "qd_max", "qdd_max", "tau_max"):
        a, b = (np.asarray(getattr(r.limits, key, np.nan), float) for r in (embedded, given))
        if a.shape == b.shape and not np.allclose(a, b, equal_nan=True):
            out.append(f"limits {key}: {np.array2string(a, precision=4)} vs {np.array2string(b, precision=4)}")
    if not np.allclose(embedded.gravity_vector, given.gravity_vector):
        out.append(f"gravity {embedded.gravity_vector} vs {given.gravity_vector}")
    return out
