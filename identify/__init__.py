"""identify: from recorded joint positions and torques to dynamic parameters.

Recordings and their checks, derivatives and parallel filtering, the observation matrix
(eqs. 6-8), (weighted) least squares with statistics (eqs. 9-15), essential parameters,
physically consistent least squares (LMIs, cvxpy), validation, and payload identification.
"""
<<<<<<< HEAD
from identify.estimation.consistency import (BodyConsistency, ConsistencyError, ConsistencyReport, ConsistentSolution,
                          consistency_margin, consistency_report, consistent_least_squares,
                          pseudo_inertia)
from identify.estimation.bootstrap import segment_bootstrap_std
from identify.signal.delay import DelayEstimate, estimate_delay
from identify.drive_gains import DriveGainsResult, drive_gains
from identify.estimation.essential import essential_parameters
from identify.fit_file import FitModel
from identify.fitting import Bootstrap, Fit, fit, load_fit
from identify.fleet import FleetFit, fit_fleet
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
=======
from rx90sym.lazy import lazy_package

# Public name -> the module that defines it (imported on first use: a fast start).
_EXPORTS = {
    "BodyConsistency": "identify.estimation.consistency",
    "ConsistencyError": "identify.estimation.consistency",
    "ConsistencyReport": "identify.estimation.consistency",
    "ConsistentSolution": "identify.estimation.consistency",
    "consistency_margin": "identify.estimation.consistency",
    "consistency_report": "identify.estimation.consistency",
    "consistent_least_squares": "identify.estimation.consistency",
    "pseudo_inertia": "identify.estimation.consistency",
    "segment_bootstrap_std": "identify.estimation.bootstrap",
    "DelayEstimate": "identify.signal.delay",
    "estimate_delay": "identify.signal.delay",
    "DriveGainsResult": "identify.drive_gains",
    "drive_gains": "identify.drive_gains",
    "essential_parameters": "identify.estimation.essential",
    "FitModel": "identify.fit_file",
    "Bootstrap": "identify.fitting",
    "Fit": "identify.fitting",
    "fit": "identify.fitting",
    "load_fit": "identify.fitting",
    "Processing": "identify.observation.processing",
    "DecimationPlan": "identify.signal.filtering",
    "Derivatives": "identify.signal.filtering",
    "choose_cutoff": "identify.signal.filtering",
    "decimate": "identify.signal.filtering",
    "decimation_factor": "identify.signal.filtering",
    "decimation_plan": "identify.signal.filtering",
    "derivatives": "identify.signal.filtering",
    "lowpass": "identify.signal.filtering",
    "ConsistentResult": "identify.estimation.consistent_fit",
    "consistent_fit": "identify.estimation.consistent_fit",
    "identify": "identify.identification",
    "Validation": "identify.validation",
    "predict": "identify.validation",
    "validate": "identify.validation",
    "ColumnMap": "identify.io.columns",
    "parse_columns": "identify.io.columns",
    "read_log": "identify.io.logs",
    "resample": "identify.signal.resampling",
    "CompressedSystem": "identify.estimation.least_squares",
    "IdentificationError": "identify.estimation.least_squares",
    "compress": "identify.estimation.least_squares",
    "weighted_least_squares": "identify.estimation.least_squares",
    "DEFAULT_MIN_VELOCITY": "identify.observation.matrix",
    "DEFAULT_REST": "identify.observation.matrix",
    "Observation": "identify.observation.matrix",
    "observation_matrix": "identify.observation.matrix",
    "fit_recordings": "identify.real_fit",
    "PairedRuns": "identify.signal.pairing",
    "pair_runs": "identify.signal.pairing",
    "PayloadMonitor": "identify.payload",
    "PayloadResult": "identify.payload",
    "grouping_relations": "identify.payload",
    "payload": "identify.payload",
    "Recording": "identify.io.recordings",
    "RecordingError": "identify.io.recordings",
    "read_motor_recording": "identify.io.recordings",
    "read_recording": "identify.io.recordings",
    "recording_from_arrays": "identify.io.recordings",
    "split": "identify.io.recordings",
    "write_recording": "identify.io.recordings",
    "EliminationStep": "identify.estimation.results",
    "IdentificationResult": "identify.estimation.results",
}
>>>>>>> main

__all__ = [
    "BodyConsistency", "consistency_margin", "ConsistencyError", "ConsistencyReport", "ConsistentSolution", "consistency_report",
    "consistent_least_squares", "pseudo_inertia", "essential_parameters", "Derivatives",
    "choose_cutoff", "decimate", "decimation_factor", "derivatives", "lowpass",
    "ConsistentResult", "Validation", "consistent_fit", "identify", "predict", "validate", "CompressedSystem",
    "IdentificationError", "compress", "ColumnMap", "parse_columns", "read_log", "resample", "weighted_least_squares", "Observation",
    "observation_matrix", "Recording", "RecordingError", "read_motor_recording",
    "read_recording", "recording_from_arrays", "split", "write_recording", "EliminationStep",
    "IdentificationResult", "DecimationPlan", "decimation_plan", "DelayEstimate", "estimate_delay",
    "segment_bootstrap_std", "FitModel", "Fit", "fit", "load_fit", "FleetFit", "fit_fleet", "Processing", "Bootstrap", "fit_recordings", "DEFAULT_MIN_VELOCITY", "DEFAULT_REST",
    "PayloadMonitor", "PayloadResult", "grouping_relations", "payload",
    "DriveGainsResult", "drive_gains", "PairedRuns", "pair_runs",
]

lazy_package(__name__, _EXPORTS)
