"""rx90sym: symbolic dynamic model of serial robots (Khalil-Kleinfinger) in CasADi.

Public API: robot descriptions and files, the inverse dynamic model and its regressor,
base parameters, the Pinocchio bridge and the simulated robot (``rx90sym.twin``).
"""
from .base_parameters import BaseParameters, base_parameters
from .description import Coupling, Limits, Robot, robot_from_table
from .parameters import LINK_PARAMETERS, PAYLOAD_NAMES
from .pinocchio_bridge import pinocchio_model
from .robot_file import RobotFileError, bundled_robots, load_robot
from .spring import Spring
from .payloads import add_payload, bundled_payloads, load_payload, payload_regressor_columns
from . import twin
from .twin import default_parameters

__all__ = [
    "BaseParameters", "base_parameters",
    "Coupling", "Limits", "Robot", "robot_from_table", "LINK_PARAMETERS", "PAYLOAD_NAMES",
    "RobotFileError", "bundled_robots", "load_robot", "Spring", "bundled_payloads",
    "load_payload", "twin", "add_payload", "payload_regressor_columns", "default_parameters",
    "pinocchio_model",
]
