"""rx90sym: symbolic dynamic model of serial robots (Khalil-Kleinfinger) in CasADi.

Public API: robot descriptions and files, the inverse dynamic model and its regressor,
base parameters, the Pinocchio bridge, the simulated robot (``rx90sym.twin``) and the
bundled real TX40 record (``rx90sym.datasets.tx40()``).
"""
__version__ = "0.1.0"

from .base_parameters import BaseParameters, base_parameters
from .description import Coupling, Limits, Robot, robot_from_table
from .parameters import LINK_PARAMETERS, PAYLOAD_NAMES
from .pinocchio_bridge import pinocchio_model
from .robot_file import RobotFileError, bundled_robots, load_robot
from .nominal import nominal_parameters
from .spring import Spring
from .urdf import UrdfChain, load_urdf, urdf_parameters
from .urdf_export import write_urdf
from .mjcf_export import write_mjcf
from .urdf_tree import UrdfError
from .payloads import add_payload, bundled_payloads, load_payload, payload_regressor_columns
from . import datasets, twin
from .twin import default_parameters

__all__ = [
    "__version__",
    "BaseParameters", "base_parameters",
    "Coupling", "Limits", "Robot", "robot_from_table", "LINK_PARAMETERS", "PAYLOAD_NAMES",
    "RobotFileError", "bundled_robots", "load_robot", "Spring", "bundled_payloads",
    "load_payload", "twin", "datasets", "add_payload", "payload_regressor_columns", "default_parameters",
    "pinocchio_model", "nominal_parameters", "UrdfChain", "UrdfError", "load_urdf", "urdf_parameters",
    "write_urdf", "write_mjcf",
]
