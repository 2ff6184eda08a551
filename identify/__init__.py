"""identify: from recorded joint positions and torques to dynamic parameters.

Recordings and their checks, derivatives and parallel filtering, the observation matrix
(eqs. 6-8), (weighted) least squares with statistics (eqs. 9-15), essential parameters,
physically consistent least squares (LMIs, cvxpy), validation, and payload identification.

The calls that do the work run numpy's and scipy's BLAS on one thread, as the ``rx90`` command
does (tall, thin least squares: a second thread costs more than it gives), and give the caller
its count back; an environment variable such as OPENBLAS_NUM_THREADS, or
``rx90sym.blas_threads(n)`` around the calls, keeps the caller's count (:mod:`rx90sym.threads`).
"""
from rx90sym.lazy import lazy_package

# Public name -> the module that defines it, by stage of the data flow (imported on first use).
_EXPORTS = {
    # io: what comes in
    "Recording": "identify.io.recordings",
    "RecordingError": "identify.io.recordings",
    "read_recording": "identify.io.recordings",
    "read_motor_recording": "identify.io.recordings",
    "read_log": "identify.io.log_blocks",
    "read_joint_files": "identify.io.joint_files",
    "write_recording": "identify.io.recordings",
    "split": "identify.io.recordings",
    # signal: filtering, resampling, pairing, delay
    "choose_cutoff": "identify.signal.filtering",
    "resample": "identify.io.resampling",
    "pair_runs": "identify.signal.pairing",
    "estimate_delay": "identify.fitting.passes",
    # observation: one processing record, W and Y (eqs. 6-8)
    "Processing": "identify.observation.processing",
    "Observation": "identify.observation.matrix",
    "observation_matrix": "identify.observation.matrix",
    "FRICTION_FORMS": "identify.observation.defaults",
    "velocity_scales": "identify.friction.scales",
    "presliding_travels": "identify.friction.travels",
    # estimation: (weighted) least squares (eqs. 9-15), essential parameters, bootstrap, consistency
    "IdentificationResult": "identify.estimation.results",
    "IdentificationError": "identify.estimation.least_squares",
    "weighted_least_squares": "identify.estimation.least_squares",
    "essential_parameters": "identify.estimation.essential",
    "segment_bootstrap_std": "identify.estimation.bootstrap",
    "consistent_fit": "identify.fitting.consistent_fit",
    "consistency_report": "identify.estimation.consistency",
    "pseudo_inertia": "identify.estimation.consistency",
    # the fit and its file; prediction and validation
    "fit": "identify.fitting.fit",
    "Fit": "identify.fitting.fit_result",
    "load_fit": "identify.fitting.fit_result",
    "fit_fleet": "identify.fitting.fleet",
    "FleetFit": "identify.fitting.fleet",
    "predict": "identify.fitting.validation",
    "validate": "identify.fitting.validation",
    "Validation": "identify.fitting.validation",
    # what the fit is used for: payloads (section IV), drive gains
    "payload": "identify.payloads.methods",
    "PayloadMonitor": "identify.monitor.payload",
    "PayloadResult": "identify.payloads.result",
    # the model at work: external torques and contacts
    "ContactMonitor": "identify.monitor.contact",
    "ContactEvent": "identify.monitor.contact",
    "monitor_log": "identify.monitor.log",
    "with_contact_thresholds": "identify.monitor.thresholds",
    "drive_gains": "identify.gains.drive_gains",
    # models out: URDF and MJCF with actuator terms
    "export_urdf": "identify.export.models",
    "export_mjcf": "identify.export.models",
    # the exported model in a simulator: rollouts against the recorded motion
    "roll_out": "identify.rollout.run",
    "roll_out_fit": "identify.rollout.run",
    "Rollout": "identify.rollout.result",
}
__all__ = list(_EXPORTS)

# Also reachable as identify.NAME (kept for existing code; import them from their modules).
_EXPORTS.update({
    "ColumnMap": "identify.io.columns",
    "parse_columns": "identify.io.columns",
    "recording_from_arrays": "identify.io.recordings",
    "DecimationPlan": "identify.signal.filtering",
    "Derivatives": "identify.signal.filtering",
    "decimate": "identify.signal.filtering",
    "decimation_factor": "identify.signal.filtering",
    "decimation_plan": "identify.signal.filtering",
    "derivatives": "identify.signal.filtering",
    "lowpass": "identify.signal.filtering",
    "DelayEstimate": "identify.estimation.delay",
    "PairedRuns": "identify.signal.pairing",
    "DEFAULT_MIN_VELOCITY": "identify.observation.processing",
    "DEFAULT_REST": "identify.observation.processing",
    "CompressedSystem": "identify.estimation.least_squares",
    "compress": "identify.estimation.least_squares",
    "EliminationStep": "identify.estimation.results",
    "ConsistentResult": "identify.fitting.consistent_fit",
    "BodyConsistency": "identify.estimation.consistency",
    "ConsistencyError": "identify.estimation.consistency",
    "ConsistencyReport": "identify.estimation.consistency",
    "ConsistentSolution": "identify.estimation.consistency",
    "consistency_margin": "identify.estimation.consistency",
    "consistent_least_squares": "identify.estimation.consistency",
    "Bootstrap": "identify.fitting.fit_result",
    "FitModel": "identify.fitting.fit_file",
    "Flag": "identify.fitting.plausibility",
    "grouping_relations": "identify.payloads.methods",
    "DriveGainsResult": "identify.gains.drive_gains",
})

lazy_package(__name__, _EXPORTS)
