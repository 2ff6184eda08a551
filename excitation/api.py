"""Robot-level entry points: fetch regressor, dynamics and limits from an rx90sym Robot, then call
the generic functions (multistart.optimise_model, random_trajectory.random_feasible)."""
from __future__ import annotations

import dataclasses
import sys
from typing import Any, Sequence, TextIO

import numpy as np

import rx90sym

from .collision import Box, CollisionModel, arm_capsules, without_pairs_touching_at
from .envelope import Envelope
from .complement import prior_information
from .fourier import FourierSeries
from .model import ExcitationModel, model_from_robot
from .multistart import optimise_model
from .defaults import DEFAULT_CRITERION, FALLBACK_CRITERION
from .objective import Objective, reference_magnitudes
from .options import OptimiserOptions
from .payload_design import payload_model, payload_objective
from .random_trajectory import random_feasible
from .trajectory import Trajectory
from .via_points import ViaPointSpline

NOISE_FRACTION = 0.01  # default expected torque noise: 1 % of each joint's torque limit
#: The value of an argument that takes ``rx90 excite``'s default (resolved for the robot at hand).
DEFAULT = "default"
#: Multi-start starts, as ``rx90 excite --starts`` (tests/test_defaults.py checks they agree).
DEFAULT_STARTS = 2
#: What no envelope leaves unchecked (said whenever a motion is planned without one).
NO_ENVELOPE = ("warning: no safety envelope (envelope=None): the motion is NOT checked for height above the "
               "mounting plane, Cartesian speed or narrowed joint ranges, and self-collision only if a collision "
               "model is given; only the joint limits{floor} are")


def nominal_warning(robot: rx90sym.Robot) -> str:
    """What planning without nominal parameters leaves unchecked (the library and ``rx90 excite`` say it alike)."""
    return (f"warning: robot {robot.name!r} has no nominal parameters: the trajectory is NOT "
            f"checked against the torque limits (pass --params FILE, or chi_nominal=)")


def resolve_nominal(robot: rx90sym.Robot, chi_nominal: Any, stream: TextIO = sys.stderr) -> np.ndarray | None:
    """The standard parameters the torque limits use: ``"default"`` -> the robot's nominal ones
    (None, said on ``stream``, when it has none); None -> None, said; an array -> itself."""
    if isinstance(chi_nominal, str):
        if chi_nominal != DEFAULT:
            raise ValueError(f"chi_nominal: expected {DEFAULT!r}, None or a parameter vector, got {chi_nominal!r}")
        params = rx90sym.nominal_parameters(robot)
        chi_nominal = None if params is None else robot.parameter_vector(params)
    if chi_nominal is None:
        print(nominal_warning(robot), file=stream)
        return None
    return np.asarray(chi_nominal, dtype=float)


def resolve_envelope(robot: rx90sym.Robot, envelope: Envelope | str | None, stream: TextIO = sys.stderr,
                     z_min: float | None = None) -> Envelope | None:
    """The envelope to apply: ``"default"`` -> ``Envelope()`` with the URDF acceleration default
    when the robot comes from a URDF (as ``rx90 excite`` without options); None -> None, said on
    ``stream``."""
    if isinstance(envelope, str):
        if envelope != DEFAULT:
            raise ValueError(f"envelope: expected {DEFAULT!r}, None or an Envelope, got {envelope!r}")
        from rx90sym.urdf import default_acceleration

        return Envelope(urdf_acceleration=default_acceleration(robot))
    if envelope is None:
        print(NO_ENVELOPE.format(floor="" if z_min is None else " and the floor z_min"), file=stream)
    return envelope


def default_noise(limits: Any) -> np.ndarray:
    """Expected torque noise per joint [N m] when none is given: NOISE_FRACTION of the torque
    limit (1 where the limit is unknown). Only the ratios between joints matter to the criteria,
    except when a prior information matrix is added."""
    tau = np.asarray(limits.tau_max, dtype=float)
    return np.where(np.isfinite(tau), NOISE_FRACTION * tau, 1.0)


def make_objective(model: ExcitationModel, criterion: str = "cond", *, nominal_base: Any = None,
                   noise_std: Any = None, select: Sequence[str] | None = None,
                   prior: np.ndarray | None = None, rate: float = 250.0) -> Objective:
    """The Objective of ``criterion`` for a model: reference magnitudes from the nominal base
    parameters ``nominal_base`` (nb,) (needed by "cond-nominal" and "sigma"), noise_std (n,) [N m]
    (default :func:`default_noise`), select: base parameter names "sigma" judges (None: all),
    prior (nb, nb): information already gathered (see complement.py)."""
    names = model.names or tuple(f"p{i + 1}" for i in range(model.n_base))
    reference = None if nominal_base is None else reference_magnitudes(nominal_base, names)
    selection = None
    if select is not None:
        unknown = [s for s in select if s not in names]
        if unknown:
            raise ValueError(f"criterion: unknown base parameter(s) {', '.join(unknown)}; "
                             f"known: {', '.join(names)}")
        selection = tuple(names.index(s) for s in select)
    noise = default_noise(model.limits) if noise_std is None else np.asarray(noise_std, dtype=float)
    if criterion == "cond" and noise_std is None and prior is None:
        noise = None  # the raw cond(W): the historical criterion, unweighted
    return Objective(criterion, noise, reference, selection, prior, rate)


def optimise(robot: rx90sym.Robot, duration: float = 20.0, harmonics: int = 5, seed: int = 0, *,
             chi_nominal: Any = DEFAULT, starts: int = DEFAULT_STARTS, time_budget: float | None = None,
             z_min: float | None = None, tool_point: Sequence[float] = (0.0, 0.0, 0.0),
             via_points: int | None = None, base: Any = None,
             options: OptimiserOptions | None = None, criterion: str | None = None,
             noise_std: Any = None, select: Sequence[str] | None = None,
             complement: Sequence[tuple[np.ndarray, ...]] = (), client: Any = None,
             collision: CollisionModel | None = None, envelope: Envelope | str | None = DEFAULT,
             progress: bool | TextIO = True) -> Trajectory:
    """Optimal excitation trajectory for ``robot``, safe by default: the defaults are ``rx90 excite``'s.

    envelope: the safety envelope (envelope.Envelope(): heights above the mounting plane,
    experiment limits, Cartesian speeds, the robot's own capsules, a centre pose inside it);
    "default": ``Envelope()`` as ``rx90 excite`` builds it without options; None: no envelope,
    said on stderr (only joint limits and ``z_min`` are then checked). With an envelope
    ``collision`` defaults to :func:`collision_model` and ``z_min`` is the envelope's floor; the
    trajectory's ``envelope`` describes what was applied.

    duration [s], harmonics: Fourier series with base frequency 2 pi / duration. via_points: if
    given, optimise that many equally spaced via points (quintic spline) instead.
    chi_nominal: standard parameters for the torque limits (and the reference magnitudes of the
    criteria); "default": the robot's nominal parameters (``rx90sym.nominal_parameters``: URDF
    inertials, else the robot file's [nominal] table; none known: no torque limits, said on
    stderr); None: no torque limits, said on stderr.
    z_min [m]: floor height for the wrist centre and ``tool_point`` [m, last frame] (None: no
    Cartesian limit). starts, seed: multi-start settings (same seed, same result); time_budget
    [s]: optional wall-clock budget. base: precomputed ``rx90sym.base_parameters(robot)``.
    criterion, noise_std, select: see :func:`make_objective`; criterion None: DEFAULT_CRITERION
    with nominal parameters, else FALLBACK_CRITERION (the criterion in ``options`` is replaced). complement: motions (t, q, qd, qdd) already recorded, whose information the new
    trajectory adds to (sequential design, complement.py). client: a dask.distributed.Client for
    the starts. collision: capsules and obstacle boxes to keep apart (see collision.py and
    :func:`collision_model`). See OptimiserOptions.
    """
    base = base if base is not None else rx90sym.base_parameters(robot)
    options = options or OptimiserOptions()
    stream = progress if hasattr(progress, "write") else sys.stderr
    chi_nominal = resolve_nominal(robot, chi_nominal, stream)
    envelope = resolve_envelope(robot, envelope, stream, z_min)
    described = None
    if envelope is not None:
        model, described = safe_model(robot, chi_nominal, base, envelope, collision, options.margins)
    else:
        model = dataclasses.replace(model_from_robot(robot, chi_nominal, base, z_min, tool_point),
                                    collision=collision)
    if criterion is None:
        criterion = DEFAULT_CRITERION if chi_nominal is not None else FALLBACK_CRITERION
    nominal = None
    if chi_nominal is not None:
        nominal = base.beta(chi_nominal)
    objective = make_objective(model, criterion, nominal_base=nominal, noise_std=noise_std,
                               select=select, rate=options.cond_rate)
    if complement:
        if objective.noise_std is None:  # raw cond: the old and new rows still need one scale
            objective = dataclasses.replace(objective, noise_std=default_noise(model.limits))
        objective = dataclasses.replace(objective, prior=prior_information(base.regressor, complement, objective))
    options = dataclasses.replace(options, criterion=objective)
    form = (FourierSeries(duration, harmonics) if via_points is None
            else ViaPointSpline.uniform(duration, via_points))
    traj = optimise_model(model, form, seed=seed, starts=starts, time_budget=time_budget,
                          options=options, progress=progress, client=client)
    return traj if described is None else dataclasses.replace(traj, envelope=described)


def safe_model(robot: rx90sym.Robot, chi_nominal: Any, base: Any, envelope: Envelope,
               collision: CollisionModel | None = None, margins: Any = None
               ) -> tuple[ExcitationModel, dict[str, Any]]:
    """The ExcitationModel of ``robot`` inside ``envelope`` (see envelope.py) and the envelope's
    description; collision: capsules and boxes (default :func:`collision_model`: the robot's own
    capsules, no boxes). Raises ValueError when no pose lies inside the envelope or a given centre
    pose breaks it."""
    from .constraints import Margins
    from .envelope import envelope_model
    from .envelope_description import describe_robot
    from .robot_geometry import arm_geometry

    geometry = arm_geometry(robot)
    collision = collision if collision is not None else collision_model(robot)
    model = envelope_model(model_from_robot(robot, chi_nominal, base), robot, envelope, geometry,
                           collision, margins or Margins())
    return model, describe_robot(envelope, geometry, model, robot)


def random_trajectory(robot: rx90sym.Robot, duration: float = 20.0, harmonics: int = 5, seed: int = 0, *,
                      chi_nominal: Any = None, z_min: float | None = None,
                      tool_point: Sequence[float] = (0.0, 0.0, 0.0), base: Any = None,
                      options: OptimiserOptions | None = None,
                      collision: CollisionModel | None = None) -> Trajectory:
    """Random feasible Fourier trajectory (the comparison baseline), scaled until limits hold."""
    model = dataclasses.replace(model_from_robot(robot, chi_nominal, base, z_min, tool_point),
                                collision=collision)
    return random_feasible(model, FourierSeries(duration, harmonics), seed, options)


def collision_model(robot: rx90sym.Robot, obstacles: Sequence[Box | str] = (), self_collision: bool = True,
                    radii: Sequence[float] | None = None,
                    tool_point: Sequence[float] = (0.0, 0.0, 0.1)) -> CollisionModel:
    """Link capsules of ``robot`` kept apart and out of the obstacle boxes (Box or
    'xmin,ymin,zmin,xmax,ymax,zmax' [m], frame 0): the robot's own capsules (robot file
    [[capsules]], URDF <collision>, robot_geometry.py) unless ``radii`` [m] are given; else the
    segments between frame origins (collision.DEFAULT_RADII)."""
    boxes = tuple(b if isinstance(b, Box) else Box.parse(b) for b in obstacles)
    from .robot_geometry import arm_geometry, capsule_set

    geometry = arm_geometry(robot)
    if geometry.capsules and radii is None:  # the robot's own capsules (robot file or URDF)
        return CollisionModel(capsule_set(robot, geometry), boxes, self_collision)
    capsules = arm_capsules(robot, tool_point, radii=radii)
    if self_collision:
        lim = robot.limits
        with np.errstate(invalid="ignore"):  # a joint without position limits: inf - inf
            centre = np.where(np.isfinite(lim.q_min + lim.q_max), 0.5 * (lim.q_min + lim.q_max), 0.0)
        # Default capsules between frame origins do not describe an arm with offsets (a UR's
        # wrist, a Panda): dropping only the pairs touching at the centre still left every motion
        # in contact on the UR10e. Self-collision is then not checked (reported by `ignored`).
        every = radii is None
        capsules = without_pairs_touching_at(capsules, centre, every=every)
        self_collision = not (every and capsules.ignored)
    return CollisionModel(capsules, boxes, self_collision)


def optimise_payload(robot: rx90sym.Robot, duration: float = 10.0, via_points: int | None = 10,
                     harmonics: int = 3, seed: int = 0, *, chi_nominal: Any = None,
                     payload: Any = "tables_4", noise_std: Any = None, starts: int = 4,
                     time_budget: float | None = None, z_min: float | None = None, base: Any = None,
                     options: OptimiserOptions | None = None, client: Any = None,
                     collision: CollisionModel | None = None, envelope: Envelope | None = None,
                     progress: bool | TextIO = True) -> Trajectory:
    """A short motion for the ten payload parameters (criterion "sigma" on Wc, eq. 21).

    via_points (default 10, the paper's conclusion) or, with via_points None, a Fourier series of
    ``harmonics``. payload: a typical payload (name, path or mapping of XXc..Mc) for the reference
    magnitudes and the torque limits. See payload_design.py and :func:`optimise`.
    """
    base = base if base is not None else rx90sym.base_parameters(robot)
    model = dataclasses.replace(payload_model(robot, base, chi_nominal, payload, z_min), collision=collision)
    described = None
    if envelope is not None:  # the same envelope as optimise (see safe_model)
        from .envelope import envelope_model
        from .envelope_description import describe_robot
        from .robot_geometry import arm_geometry

        geometry = arm_geometry(robot)
        collision = collision if collision is not None else collision_model(robot)
        model = envelope_model(dataclasses.replace(model, heights=None, z_min=None), robot, envelope,
                               geometry, collision)
        described = describe_robot(envelope, geometry, model, robot)
    noise = default_noise(model.limits) if noise_std is None else np.asarray(noise_std, dtype=float)
    # Short, fast motions press on the torque limits: imposed from the start (20 Hz grid), since
    # the lazy repairs of optimiser.py failed on the RX90 at 10 s.
    options = options or OptimiserOptions(torque_rate=20.0)
    options = dataclasses.replace(options, criterion=payload_objective(payload, noise, options.cond_rate))
    form = (FourierSeries(duration, harmonics) if via_points is None
            else ViaPointSpline.uniform(duration, via_points))
    traj = optimise_model(model, form, seed=seed, starts=starts, time_budget=time_budget,
                          options=options, progress=progress, client=client)
    return traj if described is None else dataclasses.replace(traj, envelope=described)
