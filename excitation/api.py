"""Robot-level entry points: fetch regressor, dynamics and limits from an rx90sym Robot, then call
the generic functions (optimiser.optimise_model, random_trajectory.random_feasible)."""
from __future__ import annotations

from typing import Any, Sequence, TextIO

from .fourier import FourierSeries
from .model import model_from_robot
from .optimiser import OptimiserOptions, optimise_model
from .random_trajectory import random_feasible
from .trajectory import Trajectory
from .via_points import ViaPointSpline


def optimise(robot: Any, duration: float = 20.0, harmonics: int = 5, seed: int = 0, *,
             chi_nominal: Any = None, starts: int = 4, time_budget: float = 300.0,
             z_min: float | None = None, tool_point: Sequence[float] = (0.0, 0.0, 0.0),
             via_points: int | None = None, base: Any = None,
             options: OptimiserOptions | None = None,
             progress: bool | TextIO = True) -> Trajectory:
    """Optimal excitation trajectory for ``robot`` (an rx90sym.Robot).

    duration [s], harmonics: Fourier series with base frequency 2 pi / duration. via_points: if
    given, optimise that many equally spaced via points (quintic spline) instead.
    chi_nominal: standard parameters for the torque limits, "default" for the robot's bundled
    nominal set, None to skip torque limits.
    z_min [m]: floor height for the wrist centre and ``tool_point`` [m, last frame] (None: no
    Cartesian limit). starts, seed, time_budget [s]: multi-start settings. base: precomputed
    ``rx90sym.base_parameters(robot)``. See OptimiserOptions for grids, margins and criterion.
    """
    model = model_from_robot(robot, chi_nominal, base, z_min, tool_point)
    form = (FourierSeries(duration, harmonics) if via_points is None
            else ViaPointSpline.uniform(duration, via_points))
    return optimise_model(model, form, seed=seed, starts=starts, time_budget=time_budget,
                          options=options, progress=progress)


def random_trajectory(robot: Any, duration: float = 20.0, harmonics: int = 5, seed: int = 0, *,
                      chi_nominal: Any = None, z_min: float | None = None,
                      tool_point: Sequence[float] = (0.0, 0.0, 0.0), base: Any = None,
                      options: OptimiserOptions | None = None) -> Trajectory:
    """Random feasible Fourier trajectory (the comparison baseline), scaled until limits hold."""
    model = model_from_robot(robot, chi_nominal, base, z_min, tool_point)
    return random_feasible(model, FourierSeries(duration, harmonics), seed, options)
