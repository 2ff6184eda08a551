"""rx90sym: symbolic dynamic model of serial robots (Khalil-Kleinfinger) in CasADi.

Public API: robot descriptions and files, the inverse dynamic model and its regressor,
base parameters, the Pinocchio bridge, the simulated robot (``rx90sym.twin``) and the
bundled real TX40 record (``rx90sym.datasets.tx40()``).
"""
__version__ = "0.1.0"
from rx90sym.lazy import lazy_package

# Public name -> the module that defines it (imported on first use: a fast start).
_EXPORTS = {
    "BaseParameters": "rx90sym.base_parameters",
    "base_parameters": "rx90sym.base_parameters",
    "Coupling": "rx90sym.description",
    "Limits": "rx90sym.description",
    "Robot": "rx90sym.description",
    "robot_from_table": "rx90sym.description",
    "LINK_PARAMETERS": "rx90sym.parameters",
    "PAYLOAD_NAMES": "rx90sym.parameters",
    "pinocchio_model": "rx90sym.pinocchio_bridge",
    "RobotFileError": "rx90sym.robot_file",
    "bundled_robots": "rx90sym.robot_file",
    "load_robot": "rx90sym.robot_file",
    "nominal_parameters": "rx90sym.nominal",
    "Spring": "rx90sym.spring",
    "UrdfChain": "rx90sym.urdf",
    "load_urdf": "rx90sym.urdf",
    "urdf_parameters": "rx90sym.urdf",
    "write_urdf": "rx90sym.urdf_export",
    "write_mjcf": "rx90sym.mjcf_export",
    "UrdfError": "rx90sym.urdf_tree",
    "add_payload": "rx90sym.payloads",
    "bundled_payloads": "rx90sym.payloads",
    "FlangePayload": "rx90sym.flange_payload",
    "flange_payload": "rx90sym.flange_payload",
    "ur_script": "rx90sym.flange_payload",
    "franka_load": "rx90sym.flange_payload",
    "load_payload": "rx90sym.payloads",
    "payload_regressor_columns": "rx90sym.payloads",
    "default_parameters": "rx90sym.twin",
    "momentum_regressors": "rx90sym.momentum",
    "base_momentum_regressors": "rx90sym.momentum",
    "blas_threads": "rx90sym.threads",
}
_SUBMODULES = ('datasets', 'twin')

__all__ = [
    "__version__",
    "BaseParameters", "base_parameters",
    "Coupling", "Limits", "Robot", "robot_from_table", "LINK_PARAMETERS", "PAYLOAD_NAMES",
    "RobotFileError", "bundled_robots", "load_robot", "Spring", "bundled_payloads",
    "load_payload", "FlangePayload", "flange_payload", "ur_script", "franka_load", "twin", "datasets", "add_payload", "payload_regressor_columns", "default_parameters",
    "pinocchio_model", "nominal_parameters", "UrdfChain", "UrdfError", "load_urdf", "urdf_parameters",
    "write_urdf", "write_mjcf", "momentum_regressors", "base_momentum_regressors",
    "blas_threads",
]

lazy_package(__name__, _EXPORTS, _SUBMODULES)
