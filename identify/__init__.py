"""identify: from recorded joint positions and torques to dynamic parameters.

Recordings and their checks, derivatives and parallel filtering, the observation matrix
(eqs. 6-8), (weighted) least squares with statistics (eqs. 9-15), essential parameters,
physically consistent least squares (LMIs, cvxpy), validation, and payload identification.
"""
from .consistency import (BodyConsistency, ConsistencyError, ConsistencyReport, ConsistentSolution,
                          consistency_margin, consistency_report, consistent_least_squares,
                          pseudo_inertia)
from .essential import essential_parameters
from .filtering import Derivatives, choose_cutoff, decimate, decimation_factor, derivatives, lowpass
from .identification import ConsistentResult, Validation, consistent_fit, identify, predict, validate
from .least_squares import CompressedSystem, IdentificationError, compress, weighted_least_squares
from .observation import Observation, observation_matrix
from .payload import PayloadMonitor, PayloadResult, grouping_relations, payload
from .recordings import (Recording, RecordingError, read_motor_recording, read_recording,
                         recording_from_arrays, split, write_recording)
from .results import EliminationStep, IdentificationResult

__all__ = [
    "BodyConsistency", "consistency_margin", "ConsistencyError", "ConsistencyReport", "ConsistentSolution", "consistency_report",
    "consistent_least_squares", "pseudo_inertia", "essential_parameters", "Derivatives",
    "choose_cutoff", "decimate", "decimation_factor", "derivatives", "lowpass",
    "ConsistentResult", "Validation", "consistent_fit", "identify", "predict", "validate", "CompressedSystem",
    "IdentificationError", "compress", "weighted_least_squares", "Observation",
    "observation_matrix", "Recording", "RecordingError", "read_motor_recording",
    "read_recording", "recording_from_arrays", "split", "write_recording", "EliminationStep",
    "IdentificationResult", "PayloadMonitor", "PayloadResult", "grouping_relations", "payload",
]
