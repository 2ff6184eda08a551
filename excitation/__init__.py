"""excitation: optimal excitation trajectories for dynamic identification.

Robot level (rx90sym.Robot)::

    traj = excitation.optimise(robot, duration=20.0, harmonics=5, seed=0)  # envelope, torque limits: as rx90 excite
    traj.cond; t, q, qd, qdd = traj.sample(rate=250.0); traj.save("traj.csv"); traj.save_json("traj.json")
    base = excitation.random_trajectory(robot, 20.0, 5, seed=0)

Criteria (objective.py): "sigma" (default with nominal parameters), "cond", "cond-nominal",
"cond-columns", "logdet"; ``complement=`` recordings (sequential design); ``collision=``
collision_model(robot, obstacles) (link capsules, boxes); ``client=`` a Dask client
(dask_client(workers=N) or an existing scheduler); optimise_payload for the ten payload
parameters. Generic level (any CasADi model): ExcitationModel + FourierSeries / ViaPointSpline +
optimise_model / random_feasible; condition_number for any samples. See docs/excitation.md.
"""
from rx90sym.lazy import lazy_package

# Public name -> the module that defines it (imported on first use: a fast start).
_EXPORTS = {
    "collision_model": "excitation.api",
    "make_objective": "excitation.api",
    "optimise": "excitation.api",
    "optimise_payload": "excitation.api",
    "random_trajectory": "excitation.api",
    "safe_model": "excitation.api",
    "Envelope": "excitation.envelope",
    "envelope_lines": "excitation.envelope_description:summary_lines",
    "Box": "excitation.collision",
    "CollisionModel": "excitation.collision",
    "LimitReport": "excitation.constraints",
    "Margins": "excitation.constraints",
    "check_limits": "excitation.constraints",
    "condition_number": "excitation.criterion",
    "observation_matrix": "excitation.criterion",  # deprecated: stacked_regressor
    "stacked_regressor": "excitation.criterion",
    "read_trajectory": "excitation.export",
    "FourierSeries": "excitation.fourier",
    "ExcitationModel": "excitation.model",
    "JointLimits": "excitation.model",
    "model_from_robot": "excitation.model",
    "dask_client": "excitation.multistart",
    "optimise_model": "excitation.multistart",
    "DEFAULT_CRITERION": "excitation.defaults",
    "FALLBACK_CRITERION": "excitation.defaults",
    "OBJECTIVES": "excitation.defaults",
    "Objective": "excitation.objective",
    "reference_magnitudes": "excitation.objective",
    "OptimiserOptions": "excitation.options",
    "plot_limit_usage": "excitation.plotting",
    "plot_trajectory": "excitation.plotting",
    "random_feasible": "excitation.random_trajectory",
    "SolveInfo": "excitation.trajectory",
    "Trajectory": "excitation.trajectory",
    "ViaPointSpline": "excitation.via_points",
}
_SUBMODULES = ("envelope",)

__all__ = [
    "optimise", "random_trajectory", "condition_number", "stacked_regressor", "observation_matrix",
    "FourierSeries", "ViaPointSpline", "Trajectory", "SolveInfo", "OptimiserOptions", "Margins",
    "LimitReport", "check_limits", "read_trajectory", "ExcitationModel", "JointLimits", "model_from_robot",
    "optimise_model", "random_feasible", "plot_trajectory", "plot_limit_usage",
    "collision_model", "optimise_payload", "Envelope", "envelope", "envelope_lines", "safe_model", "Box", "CollisionModel", "DEFAULT_CRITERION", "FALLBACK_CRITERION", "make_objective", "dask_client", "OBJECTIVES", "Objective", "reference_magnitudes",
]

lazy_package(__name__, _EXPORTS, _SUBMODULES)
