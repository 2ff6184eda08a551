"""identify: from recorded joint positions and torques to dynamic parameters.

Recordings and their checks, derivatives and parallel filtering, the observation matrix
(eqs. 6-8), (weighted) least squares with statistics (eqs. 9-15), essential parameters,
physically consistent least squares (LMIs, cvxpy), validation, and payload identification.
"""
from .consistency import (BodyConsistency, ConsistencyError, ConsistencyReport, ConsistentSolution,
                          consistency_margin, consistency_report, consistent_least_squares,
                          pseudo_inertia)
from .bootstrap import segment_bootstrap_std
from .delay import DelayEstimate, estimate_delay
from .drive_gains import DriveGainsResult, drive_gains
from .essential import essential_parameters
from .fit_model import FitModel
from .filtering import (DecimationPlan, Derivatives, choose_cutoff, decimate, decimation_factor,
                        decimation_plan, derivatives, lowpass)
from .identification import ConsistentResult, Validation, consistent_fit, identify, predict, validate
from .log_columns import ColumnMap, parse_columns
from .logs import read_log
from .resampling import resample
from .least_squares import CompressedSystem, IdentificationError, compress, weighted_least_squares
from .observation import DEFAULT_MIN_VELOCITY, DEFAULT_REST, Observation, observation_matrix
from .real_fit import Fit, fit_recordings
from .pairing import PairedRuns, pair_runs
from .payload import PayloadMonitor, PayloadResult, grouping_relations, payload
from .recordings import (Recording, RecordingError, read_motor_recording, read_recording,
                         recording_from_arrays, split, write_recording)
from .results import EliminationStep, IdentificationResult

__all__ = [
    "BodyConsistency", "consistency_margin", "ConsistencyError", "ConsistencyReport", "ConsistentSolution", "consistency_report",
    "consistent_least_squares", "pseudo_inertia", "essential_parameters", "Derivatives",
    "choose_cutoff", "decimate", "decimation_factor", "derivatives", "lowpass",
    "ConsistentResult", "Validation", "consistent_fit", "identify", "predict", "validate", "CompressedSystem",
    "IdentificationError", "compress", "ColumnMap", "parse_columns", "read_log", "resample", "weighted_least_squares", "Observation",
    "observation_matrix", "Recording", "RecordingError", "read_motor_recording",
    "read_recording", "recording_from_arrays", "split", "write_recording", "EliminationStep",
    "IdentificationResult", "DecimationPlan", "decimation_plan", "DelayEstimate", "estimate_delay",
    "segment_bootstrap_std", "FitModel", "Fit", "fit_recordings", "DEFAULT_MIN_VELOCITY", "DEFAULT_REST",
    "PayloadMonitor", "PayloadResult", "grouping_relations", "payload",
    "DriveGainsResult", "drive_gains", "PairedRuns", "pair_runs",
]
