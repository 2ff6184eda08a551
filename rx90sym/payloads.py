"""Payloads carried by the last link (paper section IV, Tables 4-5).

A payload is ten inertial parameters in frame n about its origin, named ``XXc XYc XZc YYc YZc
ZZc MXc MYc MZc Mc`` (kg m^2, kg m, kg). They add to link n's ``XX..M`` (eq. 21: the payload
columns Wc of the observation matrix are link n's ten inertial columns).
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

from .files import read_json
from .parameters import INERTIAL, PAYLOAD_NAMES, checked_values
from .urdf import payload_matrix

if TYPE_CHECKING:  # for annotations only
    from .description import Robot

PAYLOADS_FILE = Path(__file__).parent / "data" / "payloads.json"

Payload = Mapping[str, float]


def bundled_payloads() -> list[str]:
    """Names of the payloads shipped with the package ("tables_4", "tables_5")."""
    return sorted(read_json(PAYLOADS_FILE).get("payloads", {}))


def load_payload(name_or_path: str | Path) -> dict[str, float]:
    """Payload parameters by bundled name ("tables_4": 4.275 kg, "tables_5": 7.025 kg) or from a
    JSON file: either ``{"parameters": {"XXc": ..., ...}}`` or the flat ``{"XXc": ..., ...}``.

    Returns a dict with exactly the ten names of PAYLOAD_NAMES [kg m^2, kg m, kg]. Raises
    ValueError naming the file and the field when a name is missing, unknown or not finite.
    """
    path = Path(name_or_path)
    if path.suffix.lower() == ".json" or path.exists():
        if not path.exists():
            raise ValueError(f"{path}: payload file not found")
        data = read_json(path)
        table = data.get("parameters", data) if isinstance(data, dict) else data
        return validate_payload(table, str(path))
    payloads = read_json(PAYLOADS_FILE).get("payloads", {})
    if str(name_or_path) not in payloads:
        raise ValueError(f"unknown payload {str(name_or_path)!r}: not a file and not one of the "
                         f"bundled payloads {sorted(payloads)}")
    return validate_payload(payloads[str(name_or_path)].get("parameters"),
                            f"{PAYLOADS_FILE}: payloads.{name_or_path}")


def validate_payload(table: Any, where: str = "payload") -> dict[str, float]:
    """The ten payload parameters of ``table`` as floats, checked (all present, none unknown,
    finite, mass >= 0); ``where`` names the source in error messages."""
    out = checked_values(table, PAYLOAD_NAMES, where, "field")
    if out["Mc"] < 0:
        raise ValueError(f"{where}: field 'Mc' (mass) must be >= 0, got {out['Mc']}")
    return out


def as_payload(payload: str | Path | Payload) -> dict[str, float]:
    """A payload given by name, path or mapping, validated."""
    if isinstance(payload, Mapping):
        return validate_payload(payload)
    return load_payload(payload)


def payload_regressor_columns(robot: Robot) -> np.ndarray:
    """Columns of the standard regressor that form Wc (eq. 21): link n's XX..M, in
    PAYLOAD_NAMES order, so that W chi + Wc chi_c = W (chi + chi_c placed on link n)."""
    return np.array(robot.parameter_index([f"{p}{robot.n}" for p in INERTIAL]))


def add_payload(robot: Robot, chi: Any, payload: str | Path | Payload) -> np.ndarray:
    """Standard parameter vector of the robot carrying ``payload`` (merged into link n) [SI].

    The payload is given in frame n, or in the tip link frame for a robot loaded from a URDF."""
    chi = np.array(chi, dtype=float)
    if chi.shape != (len(robot.parameter_names),):
        raise ValueError(f"chi: expected {len(robot.parameter_names)} standard parameters of robot "
                         f"{robot.name!r}, got shape {chi.shape}")
    values = as_payload(payload)
    chi[payload_regressor_columns(robot)] += payload_matrix(robot) @ np.array([values[p] for p in PAYLOAD_NAMES])
    return chi

