"""excitation: optimal excitation trajectories for dynamic identification.

Robot level (rx90sym.Robot)::

    traj = excitation.optimise(robot, duration=20.0, harmonics=5, seed=0, chi_nominal="default")
    traj.cond; t, q, qd, qdd = traj.sample(rate=250.0); traj.save("traj.csv"); traj.save_json("traj.json")
    base = excitation.random_trajectory(robot, 20.0, 5, seed=0)

Criteria (objective.py): "sigma" (default with nominal parameters), "cond", "cond-nominal",
"cond-columns", "logdet"; ``complement=`` recordings (sequential design); ``collision=``
collision_model(robot, obstacles) (link capsules, boxes); ``client=`` a Dask client
(dask_client(workers=N) or an existing scheduler); optimise_payload for the ten payload
parameters. Generic level (any CasADi model): ExcitationModel + FourierSeries / ViaPointSpline +
optimise_model / random_feasible; condition_number for any samples. See docs/excitation.md.
"""
from . import envelope
from .api import collision_model, make_objective, optimise, optimise_payload, random_trajectory, safe_model
from .envelope import Envelope, summary_lines as envelope_lines
from .collision import Box, CollisionModel
from .constraints import LimitReport, Margins, check_limits
from .criterion import condition_number, observation_matrix
from .export import read_trajectory
from .fourier import FourierSeries
from .model import ExcitationModel, JointLimits, model_from_robot
from .multistart import dask_client, optimise_model
from .objective import (DEFAULT_CRITERION, FALLBACK_CRITERION, OBJECTIVES, Objective,
                        reference_magnitudes)
from .optimiser import OptimiserOptions
from .plotting import plot_limit_usage, plot_trajectory
from .random_trajectory import random_feasible
from .trajectory import SolveInfo, Trajectory
from .via_points import ViaPointSpline

__all__ = [
    "optimise", "random_trajectory", "condition_number", "observation_matrix",
    "FourierSeries", "ViaPointSpline", "Trajectory", "SolveInfo", "OptimiserOptions", "Margins",
    "LimitReport", "check_limits", "read_trajectory", "ExcitationModel", "JointLimits", "model_from_robot",
    "optimise_model", "random_feasible", "plot_trajectory", "plot_limit_usage",
    "collision_model", "optimise_payload", "Envelope", "envelope", "envelope_lines", "safe_model", "Box", "CollisionModel", "DEFAULT_CRITERION", "FALLBACK_CRITERION", "make_objective", "dask_client", "OBJECTIVES", "Objective", "reference_magnitudes",
]
