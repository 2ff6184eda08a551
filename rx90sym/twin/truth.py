"""The RX90 twin's true parameters (kept apart from every robot's nominal table) and parameter vectors."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

from ..parameters import checked_values

if TYPE_CHECKING:  # for annotations only
    from ..description import Robot


# --------------------------------------------------------------------------- true parameters
def default_parameters(robot: Robot, path: str | Path | None = None) -> dict[str, float]:
    """True standard parameters of the twin, name -> value [SI].

    Without ``path``: for the bundled RX90 file the twin's physically consistent set reproducing
    Table 3 (made by scripts/make_rx90_params.py; NOT the file's [nominal] table), otherwise the
    robot's nominal parameters (rx90sym.nominal_parameters: URDF inertials or the robot file's
    [nominal] table); a robot with none is refused. With ``path``: a JSON parameter file (see
    rx90sym.nominal.read_parameter_file).
    """
    from ..nominal import nominal_parameters, read_parameter_file, twin_parameter_file

    twin_file = twin_parameter_file(robot) if path is None else None
    values = read_parameter_file(robot, twin_file) if twin_file is not None else nominal_parameters(robot, path)
    if values is None:
        raise ValueError(f"no default parameters for robot {robot.name!r} ({robot.source or 'built in code'}): "
                         f"it has neither a [nominal] table nor URDF inertials; pass a parameter file "
                         f"(JSON name -> value, or the JSON of 'rx90 identify --method consistent')")
    return values


def _checked_parameters(robot: Robot, table: Any, where: str) -> dict[str, float]:
    if not isinstance(table, dict):
        raise ValueError(f"{where}: field 'parameters' must map names to numbers")
    return checked_values(table, robot.parameter_names, f"{where} (robot {robot.name!r})")


def check_simulable(robot: Robot) -> None:
    """Raise ValueError naming every moving link when the description's own bodies (the twin's truth
    by default) are not physical rigid bodies: a simulator cannot move them (one message)."""
    from ..description_prior import simulation_refusal
    from ..nominal import twin_parameter_file

    if twin_parameter_file(robot) is None:
        refusal = simulation_refusal(robot)
        if refusal:
            raise ValueError(f"{refusal}; give the twin physical parameters (params=: a mapping, a vector or a "
                             f"parameter file, e.g. the JSON of rx90 identify --method consistent)")


def parameter_vector(robot: Robot, params: Mapping[str, float] | Any | None) -> np.ndarray:
    """chi (n_params,) from None (the default set: the description's bodies must be physical,
    :func:`check_simulable`), a name -> value mapping or a vector."""
    if params is None:
        check_simulable(robot)
        return robot.parameter_vector(default_parameters(robot))
    if isinstance(params, Mapping):
        return robot.parameter_vector(_checked_parameters(robot, dict(params), "params"))
    chi = np.asarray(params, dtype=float)
    if chi.shape != (len(robot.parameter_names),) or not np.all(np.isfinite(chi)):
        raise ValueError(f"params: expected {len(robot.parameter_names)} finite standard "
                         f"parameters of robot {robot.name!r}, got shape {chi.shape}")
    return chi.copy()
