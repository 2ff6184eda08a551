"""identify: from recorded joint positions and torques to dynamic parameters.

Recordings and their checks, derivatives and parallel filtering, the observation matrix
(eqs. 6-8), (weighted) least squares with statistics (eqs. 9-15), essential parameters,
physically consistent least squares (LMIs, cvxpy), validation, and payload identification.
"""
from identify.estimation.consistency import (BodyConsistency, ConsistencyError, ConsistencyReport, ConsistentSolution,
                          consistency_margin, consistency_report, consistent_least_squares,
                          pseudo_inertia)
from identify.estimation.bootstrap import segment_bootstrap_std
from identify.signal.delay import DelayEstimate, estimate_delay
from identify.drive_gains import DriveGainsResult, drive_gains
from identify.estimation.essential import essential_parameters
from identify.fit_file import FitModel
from identify.fitting import Bootstrap, Fit, fit, load_fit
from identify.observation.processing import Processing
from identify.signal.filtering import (DecimationPlan, Derivatives, choose_cutoff, decimate, decimation_factor,
                        decimation_plan, derivatives, lowpass)
from identify.estimation.consistent_fit import ConsistentResult, consistent_fit
from identify.identification import identify  # deprecated: fit
from identify.validation import Validation, predict, validate
from identify.io.columns import ColumnMap, parse_columns
from identify.io.logs import read_log
from identify.signal.resampling import resample
from identify.estimation.least_squares import CompressedSystem, IdentificationError, compress, weighted_least_squares
from identify.observation.matrix import DEFAULT_MIN_VELOCITY, DEFAULT_REST, Observation, observation_matrix
from identify.real_fit import fit_recordings  # deprecated: fit
from identify.signal.pairing import PairedRuns, pair_runs
from identify.payload import PayloadMonitor, PayloadResult, grouping_relations, payload
from identify.io.recordings import (Recording, RecordingError, read_motor_recording, read_recording,
                         recording_from_arrays, split, write_recording)
from identify.estimation.results import EliminationStep, IdentificationResult

__all__ = [
    "BodyConsistency", "consistency_margin", "ConsistencyError", "ConsistencyReport", "ConsistentSolution", "consistency_report",
    "consistent_least_squares", "pseudo_inertia", "essential_parameters", "Derivatives",
    "choose_cutoff", "decimate", "decimation_factor", "derivatives", "lowpass",
    "ConsistentResult", "Validation", "consistent_fit", "identify", "predict", "validate", "CompressedSystem",
    "IdentificationError", "compress", "ColumnMap", "parse_columns", "read_log", "resample", "weighted_least_squares", "Observation",
    "observation_matrix", "Recording", "RecordingError", "read_motor_recording",
    "read_recording", "recording_from_arrays", "split", "write_recording", "EliminationStep",
    "IdentificationResult", "DecimationPlan", "decimation_plan", "DelayEstimate", "estimate_delay",
    "segment_bootstrap_std", "FitModel", "Fit", "fit", "load_fit", "Processing", "Bootstrap", "fit_recordings", "DEFAULT_MIN_VELOCITY", "DEFAULT_REST",
    "PayloadMonitor", "PayloadResult", "grouping_relations", "payload",
    "DriveGainsResult", "drive_gains", "PairedRuns", "pair_runs",
]
