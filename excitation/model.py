"""What the excitation optimiser needs to know about a robot, as plain CasADi functions and arrays.

Everything downstream (criterion, constraints, optimiser) takes an :class:`ExcitationModel`, so it
works for any model, including toy ones in tests. :func:`model_from_robot` is the thin bridge to an
``rx90sym.Robot``: base regressor, nominal inverse dynamics plus spring, forward kinematics, limits.
"""
from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Sequence

import casadi as ca
import numpy as np

if TYPE_CHECKING:  # for annotations only
    import rx90sym


def renamed_offsets(cls: type) -> type:
    """Class decorator: the dataclass ``cls`` takes its former keyword ``staubli_offsets`` (a
    DeprecationWarning, kept one release) for ``controller_offsets`` and reads it back likewise."""
    init = cls.__init__

    @functools.wraps(init)
    def __init__(self: Any, *args: Any, **kwargs: Any) -> None:
        if "staubli_offsets" in kwargs:
            warnings.warn(f"{cls.__name__}(staubli_offsets=...) is deprecated: use controller_offsets",
                          DeprecationWarning, stacklevel=2)
            kwargs["controller_offsets"] = kwargs.pop("staubli_offsets")
        init(self, *args, **kwargs)

    def staubli_offsets(self: Any) -> np.ndarray:
        """Deprecated: :attr:`controller_offsets`."""
        warnings.warn(f"{cls.__name__}.staubli_offsets is deprecated: use controller_offsets",
                      DeprecationWarning, stacklevel=2)
        return self.controller_offsets

    cls.__init__ = __init__
    cls.staubli_offsets = property(staubli_offsets)
    return cls


@dataclass(frozen=True, eq=False)
class JointLimits:
    """Joint limits in Khalil angles, SI, arrays (n,); np.inf where unknown.

    q_min, q_max [rad]; qd_max [rad/s]; qdd_max [rad/s^2]; tau_max [N m] (joint side, motor torque
    after the spring, so |IDM - spring| <= tau_max).
    """

    q_min: np.ndarray
    q_max: np.ndarray
    qd_max: np.ndarray
    qdd_max: np.ndarray
    tau_max: np.ndarray

    def __post_init__(self) -> None:
        arrays = {}
        for name in ("q_min", "q_max", "qd_max", "qdd_max", "tau_max"):
            a = np.array(getattr(self, name), dtype=float).reshape(-1)
            a.setflags(write=False)
            arrays[name] = a
            object.__setattr__(self, name, a)
        n = arrays["q_min"].size
        for name, a in arrays.items():
            if a.size != n:
                raise ValueError(f"limits: {name} has {a.size} entries, expected {n}")
            if np.any(np.isnan(a)):
                raise ValueError(f"limits: {name} contains NaN")
        for name in ("qd_max", "qdd_max", "tau_max"):
            bad = np.flatnonzero(arrays[name] <= 0.0)
            if bad.size:
                raise ValueError(f"limits: {name} of joint {bad[0] + 1} must be > 0, "
                                 f"got {arrays[name][bad[0]]}")
        bad = np.flatnonzero(arrays["q_max"] <= arrays["q_min"])
        if bad.size:
            j = bad[0]
            raise ValueError(f"limits: joint {j + 1} has q_max {arrays['q_max'][j]} <= "
                             f"q_min {arrays['q_min'][j]}")

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.q_min.size

    @staticmethod
    def from_any(limits: Any) -> "JointLimits":
        """From any object with q_min, q_max, qd_max, qdd_max, tau_max (e.g. rx90sym.Limits)."""
        return JointLimits(limits.q_min, limits.q_max, limits.qd_max, limits.qdd_max, limits.tau_max)


@renamed_offsets
@dataclass(frozen=True, eq=False)
class ExcitationModel:
    """A robot as the excitation optimiser sees it.

    regressor: casadi.Function (q, qd, qdd) -> Phi_b (n x nb), the base regressor (true sign).
    names: base parameter names (used to pair FSx with FVx for the smooth friction surrogate).
    torque: casadi.Function (q, qd, qdd) -> motor torque (n,) [N m], or None (no torque limits).
    heights: casadi.Function (q) -> (k,) heights [m] of points that must stay above z_min, or None.
    controller_offsets: q_controller = q_model + controller_offsets [rad], for exports.
    collision: a collision.CollisionModel (self-collision of link capsules, obstacle boxes), or None.
    speeds: casadi.Function (q, qd) -> (k,) squared Cartesian speeds [m^2/s^2] of points that must
    stay below speed_max [m/s], or None. centre: the pose [rad] random starts are drawn about
    (None: the centre of the joint ranges); point_names: names of the heights' points then the
    speeds' points (messages). See envelope.py.
    """

    regressor: ca.Function
    limits: JointLimits
    names: tuple[str, ...] | None = None
    torque: ca.Function | None = None
    heights: ca.Function | None = None
    z_min: float | None = None
    controller_offsets: np.ndarray = field(default_factory=lambda: np.zeros(0))
    name: str = "robot"
    collision: Any = None  # excitation.collision.CollisionModel: capsules and obstacle boxes
    speeds: ca.Function | None = None
    speed_max: float | None = None
    centre: np.ndarray | None = None
    point_names: tuple[tuple[str, ...], tuple[str, ...]] = ((), ())

    def __post_init__(self) -> None:
        n = self.limits.n
        if self.regressor.size1_in(0) != n or self.regressor.size1_out(0) != n:
            raise ValueError(f"model {self.name!r}: regressor is for {self.regressor.size1_in(0)} "
                             f"joints, limits for {n}")
        if self.names is not None and len(self.names) != self.regressor.size2_out(0):
            raise ValueError(f"model {self.name!r}: {len(self.names)} names for "
                             f"{self.regressor.size2_out(0)} regressor columns")
        offsets = np.zeros(n) if len(self.controller_offsets) == 0 else np.asarray(self.controller_offsets, float)
        if offsets.shape != (n,):
            raise ValueError(f"model {self.name!r}: controller_offsets must have {n} entries")
        offsets.setflags(write=False)
        object.__setattr__(self, "controller_offsets", offsets)
        if (self.z_min is None) != (self.heights is None):
            raise ValueError(f"model {self.name!r}: give both heights and z_min, or neither")
        if (self.speed_max is None) != (self.speeds is None):
            raise ValueError(f"model {self.name!r}: give both speeds and speed_max, or neither")
        if self.centre is not None:
            centre = np.array(self.centre, dtype=float).reshape(-1)
            if centre.shape != (n,):
                raise ValueError(f"model {self.name!r}: centre must have {n} entries")
            centre.setflags(write=False)
            object.__setattr__(self, "centre", centre)

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.limits.n

    @property
    def n_base(self) -> int:
        """Number of base parameters (regressor columns)."""
        return self.regressor.size2_out(0)


def model_from_robot(robot: rx90sym.Robot, chi_nominal: Any = None, base: Any = None,
                     z_min: float | None = None,
                     tool_point: Sequence[float] = (0.0, 0.0, 0.0)) -> ExcitationModel:
    """ExcitationModel of an ``rx90sym.Robot``.

    base: ``rx90sym.base_parameters(robot)`` result (computed when None): its ``regressor`` and
    ``names`` are used. chi_nominal: standard parameters (robot.parameter_names order) for the
    torque limits, "default" for the robot's bundled set (rx90sym.twin.default_parameters), or
    None to skip torque limits. z_min [m]: floor height; the wrist centre (origin
    of frame n) and the tool point ``tool_point`` [m, frame n] must stay above it.
    """
    if base is None:
        import rx90sym  # imported here: excitation works on generic models without rx90sym

        base = rx90sym.base_parameters(robot)
    limits = JointLimits.from_any(robot.limits)
    n = limits.n
    q, qd, qdd = ca.SX.sym("q", n), ca.SX.sym("qd", n), ca.SX.sym("qdd", n)
    torque = None
    if isinstance(chi_nominal, str):
        if chi_nominal != "default":
            raise ValueError(f"chi_nominal must be a parameter vector, None or 'default', got {chi_nominal!r}")
        from rx90sym import default_parameters  # the robot's bundled nominal parameters

        chi_nominal = robot.parameter_vector(default_parameters(robot))
    if chi_nominal is not None:
        chi = np.asarray(chi_nominal, dtype=float).reshape(-1)
        n_params = robot.inverse_dynamics.size1_in(3)
        if chi.size != n_params:
            raise ValueError(f"chi_nominal has {chi.size} values, robot {robot.name!r} has "
                             f"{n_params} standard parameters")
        tau = robot.inverse_dynamics(q, qd, qdd, chi)
        spring = getattr(robot, "spring_torque", None)
        if spring is not None:
            tau = tau - spring(q)  # the spring helps the motor: motor torque = IDM - spring
        torque = ca.Function("motor_torque", [q, qd, qdd], [tau], ["q", "qd", "qdd"], ["tau"])
    heights = None
    if z_min is not None:
        fk = robot.forward_kinematics(q)
        t0n = fk[0] if isinstance(fk, (tuple, list)) else fk
        tool = ca.mtimes(t0n, ca.DM([*tool_point, 1.0]))
        heights = ca.Function("heights", [q], [ca.vertcat(t0n[2, 3], tool[2])], ["q"], ["z"])
    names = tuple(base.names) if getattr(base, "names", None) is not None else None
    return ExcitationModel(regressor=base.regressor, limits=limits, names=names, torque=torque,
                           heights=heights, z_min=None if z_min is None else float(z_min),
                           controller_offsets=np.asarray(getattr(robot, "controller_offsets", np.zeros(n))),
                           name=getattr(robot, "name", "robot"))

