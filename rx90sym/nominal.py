"""Nominal standard parameters of any robot: from a file, from its URDF, or the twin's set.

``nominal_parameters(robot, source)`` is the one place the toolkit asks "what are this robot's
parameters, roughly?" (torque limits of an excitation, plausibility checks, the prior of the
consistent fit, the twin of robots other than the RX90):

1. ``source`` given: a JSON parameter file (see :func:`read_parameter_file`);
2. a robot loaded from a URDF: its inertials (``rx90sym.urdf_parameters``);
3. a robot file with a ``[nominal]`` table (every bundled robot: published values with their
   sources, derived ones named as derived; rx90sym.nominal_table);

   in both, the description's prior (rx90sym.description_prior): a body that is not physical as
   written is the nearest physical one (the warning of the load says which);
4. otherwise ``None``: the caller must say so (no silent defaults).

The RX90 twin's true parameters (``rx90sym/data/rx90_true_params.json``) are NOT the RX90's
nominal parameters: they are the twin's, reached through :func:`twin_parameter_file` and
``rx90sym.twin.default_parameters``.
"""
from __future__ import annotations

import re

from pathlib import Path
from typing import Any, Mapping

from .files import read_json
from .description import Robot
from .parameters import checked_values, split_name
from .robot_file import ROBOTS_DIR

DATA_DIR = Path(__file__).parent / "data"
# Bundled robot file -> the twin's parameter file. Keyed by the file, so a user's own file named
# "rx90" does not silently get the twin's parameters.
TWIN_PARAMETER_FILES: dict[Path, Path] = {
    (ROBOTS_DIR / "rx90.toml").resolve(): DATA_DIR / "rx90_true_params.json",
}


def _source_path(robot: Robot) -> Path | None:
    if not robot.source:
        return None
    try:
        return Path(robot.source).resolve()
    except (OSError, RuntimeError):
        return None


def twin_parameter_file(robot: Robot) -> Path | None:
    """The twin's parameter file when ``robot`` was loaded from a bundled robot file that has
    one (the RX90), else None."""
    path = _source_path(robot)
    return TWIN_PARAMETER_FILES.get(path) if path is not None else None


def nominal_parameters(robot: Robot, source: str | Path | Mapping[str, float] | None = None
                       ) -> dict[str, float] | None:
    """Standard parameters name -> value [SI] for ``robot``, or None when none are known.

    source: a JSON parameter file (path) or a name -> value mapping. Without it: the robot's
    URDF inertials, then its robot file's [nominal] table, then None; a body that is not physical
    as written is replaced by the nearest physical one (rx90sym.description_prior: the description's
    prior; ``description_prior(robot).as_written`` keeps the values as the file gives them).
    Raises ValueError naming the file and the field on a malformed source.
    """
    if isinstance(source, Mapping):
        return _complete(robot, dict(source), "parameters")
    if source is not None:
        return read_parameter_file(robot, source)
    from .description_prior import description_prior

    prior = description_prior(robot)
    return None if prior is None else _complete(robot, dict(prior.values), prior.source)


def read_parameter_file(robot: Robot, path: str | Path) -> dict[str, float]:
    """Standard parameters from a JSON file, checked against ``robot``.

    Accepted layouts: a flat object ``{name: value}``; ``{"robot": name, "parameters":
    {name: value}}`` (the twin's files); the output of ``rx90 identify --json`` when it holds
    standard parameters (``"standard": {name: value}``, ``--method consistent``, or its identified model's,
    ``"identified": {"standard": ...}``, every fit).
    Torque offsets OFFj may be absent (0). Values in SI units (kg, m, kg m, kg m^2, N m ...).
    """
    path = Path(path)
    data = read_json(path)   # ValueError naming the file (and line, column)
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a JSON object of parameter names to numbers")
    if isinstance(data.get("robot"), str) and data["robot"] != robot.name:
        raise ValueError(f"{path}: field 'robot' is {data['robot']!r}, not {robot.name!r}")
    model = data.get("model")
    if isinstance(model, dict) and ("tip" in model or "robot_file" in model):
        # Same name, other frames: a URDF robot's link frames are not a robot file's Khalil frames.
        urdf = getattr(robot, "urdf", None)
        here = (f"URDF {robot.source} with tip {urdf.tip!r}" if urdf is not None else
                f"robot file {robot.source or robot.name}")
        there = (f"URDF {model.get('robot_file')} with tip {model['tip']!r}" if model.get("tip") else
                 f"robot file {model.get('robot_file') or data.get('robot')}")
        if (model.get("tip") or None) != (urdf.tip if urdf is not None else None):
            raise ValueError(f"{path}: identified on the {there}, not on the {here}: its parameters are "
                             f"expressed in that description's frames; load the same description")
    identified = data.get("identified")
    if isinstance(data.get("standard"), dict) and data["standard"]:
        table = data["standard"]
    elif isinstance(identified, dict) and isinstance(identified.get("standard"), dict) and identified["standard"]:
        table = identified["standard"]  # a fit file's identified model (every fit, whatever its method)
    elif isinstance(data.get("parameters"), dict):
        table = data["parameters"]
    elif isinstance(data.get("parameters"), list) and "method" not in data and all(
            isinstance(p, dict) and isinstance(p.get("name"), str) and not re.fullmatch(r"[A-Z]+\d+R", p["name"])
            for p in data["parameters"]):
        # [{"name", "value"}] of standard names (no regrouped "...R" base name): checked as any table
        table = {p["name"]: p.get("value") for p in data["parameters"]}
    elif isinstance(data.get("parameters"), list):
        raise ValueError(f"{path}: holds base parameters (an identification's 'parameters' list), "
                         f"not standard parameters (a fit file written before the identified model); identify "
                         f"again: the fit file's identified model has them")
    else:
        table = data
    return _complete(robot, table, str(path))


def _complete(robot: Robot, table: Any, where: str) -> dict[str, float]:
    """Check ``table`` against robot.parameter_names; offsets OFFj default to 0 and are
    dropped when the robot has none."""
    if not isinstance(table, Mapping):
        raise ValueError(f"{where}: expected a mapping of parameter names to numbers")
    table = dict(table)
    names = list(robot.parameter_names)
    for name in list(table):
        if _is_offset(name) and name not in names:
            del table[name]
    for name in names:
        if _is_offset(name) and name not in table:
            table[name] = 0.0
    return checked_values(table, names, f"{where} (robot {robot.name!r})")


def _is_offset(name: str) -> bool:
    try:
        return split_name(name)[0] == "OFF"
    except ValueError:
        return False
