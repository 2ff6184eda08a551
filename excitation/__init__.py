"""excitation: optimal excitation trajectories for dynamic identification.

Robot level (rx90sym.Robot)::

    traj = excitation.optimise(robot, duration=20.0, harmonics=5, seed=0)
    traj.cond; t, q, qd, qdd = traj.sample(rate=250.0); traj.save("traj.csv"); traj.save_json("traj.json")
    base = excitation.random_trajectory(robot, 20.0, 5, seed=0)

Generic level (any CasADi model): ExcitationModel + FourierSeries / ViaPointSpline +
optimise_model / random_feasible; condition_number for any samples.
"""
from .api import optimise, random_trajectory
from .constraints import LimitReport, Margins, check_limits
from .criterion import condition_number, observation_matrix
from .fourier import FourierSeries
from .model import ExcitationModel, JointLimits, model_from_robot
from .optimiser import OptimiserOptions, optimise_model
from .plotting import plot_limit_usage, plot_trajectory
from .random_trajectory import random_feasible
from .trajectory import SolveInfo, Trajectory
from .via_points import ViaPointSpline

__all__ = [
    "optimise", "random_trajectory", "condition_number", "observation_matrix",
    "FourierSeries", "ViaPointSpline", "Trajectory", "SolveInfo", "OptimiserOptions", "Margins",
    "LimitReport", "check_limits", "ExcitationModel", "JointLimits", "model_from_robot",
    "optimise_model", "random_feasible", "plot_trajectory", "plot_limit_usage",
]
