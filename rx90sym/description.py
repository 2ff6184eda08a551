"""Frozen description of a serial robot (Khalil-Kleinfinger table, limits, transmission).

The description is data; its CasADi functions are built on first use and cached on the
instance (like Pinocchio's Model, the description never changes once made).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any, Iterable, Sequence

import casadi as ca
import numpy as np

from .compiled import BatchFunction, BatchWorkspace, PickledFields
from .geometry import forward_kinematics_function
from .messages import plain
from .newton_euler import inverse_dynamics_expression
from .parameters import link_parameter_names
from .spring import Spring, spring_torque_function

GRAVITY = 9.81  # m/s^2, along -z0

#: Former keyword -> its neutral name (accepted with a DeprecationWarning for one release).
_FORMER_KEYWORDS = {"staubli_offsets": "controller_offsets"}


def _renamed(old: str, new: str) -> None:
    warnings.warn(f"{old} is deprecated: use {new}", DeprecationWarning, stacklevel=3)


def _neutral(options: dict[str, Any]) -> dict[str, Any]:
    """``options`` with former keywords renamed (each with a DeprecationWarning)."""
    out = dict(options)
    for old, new in _FORMER_KEYWORDS.items():
        if old in out:
            warnings.warn(f"keyword {old} is deprecated: use {new}", DeprecationWarning, stacklevel=3)
            out[new] = out.pop(old)
    return out


def gravity_vector(gravity: Any) -> np.ndarray:
    """Gravity acceleration in frame 0 [m/s^2]: a number g means (0, 0, -g) (vertical z0), a
    3-vector is taken as is (a tilted or rotated base, e.g. a URDF root that is not frame 0)."""
    g = np.asarray(gravity, dtype=float)
    if g.ndim == 0:
        return np.array([0.0, 0.0, -float(g)])
    if g.shape != (3,) or not np.all(np.isfinite(g)):
        raise ValueError(f"gravity must be a number or a finite 3-vector, got {gravity!r}")
    return g.copy()


@dataclass(frozen=True, eq=False)
class Limits:
    """Joint limits, Khalil angles, SI units; arrays of shape (n,). Unknown limits are inf."""

    q_min: np.ndarray
    q_max: np.ndarray
    qd_max: np.ndarray
    qdd_max: np.ndarray
    tau_max: np.ndarray

    @staticmethod
    def unbounded(n: int) -> "Limits":
        inf = np.full(n, np.inf)
        return Limits(-inf, inf.copy(), inf.copy(), inf.copy(), inf.copy())


@dataclass(frozen=True)
class Coupling:
    """Coupling of two joints driven through one transmission (eqs. 16-18), 0-based indices.

    coulomb_sign: "paper" (sign(qd_b) in row a, sign(qd_a) in row b, eqs. 17-18) or "motor"
    (sign(qd_a + qd_b), the speed of motor b, on both rows).
    """

    joints: tuple[int, int]
    coulomb_sign: str = "paper"


@dataclass(frozen=True, eq=False)
class Robot(PickledFields):
    """A serial robot described by a Khalil-Kleinfinger table.

    Geometry: T(j-1, j) = Rot(x, alpha_j) Trans(x, d_j) Rot(z, theta_j) Trans(z, r_j);
    sigma_j = 0 revolute (q_j = theta_j - theta offset), 1 prismatic. Lengths in m, angles in rad.
    gravity: a number g [m/s^2] (gravity along -z0) or the gravity vector in frame 0.
    urdf: for a robot imported from a URDF, its chain (rx90sym.urdf.UrdfChain), else None.
    joint_names: the joints' names in ROS messages (robot file ``joint_names``; a URDF robot's
        are its URDF joint names, :meth:`ros_joint_names`), or () when the file gives none.
    nominal: the robot file's [nominal] table (rx90sym.nominal_table.NominalTable), else None.
    flange: 4x4 pose of the maker's tool flange frame in frame n (robot file's [flange]), else None.
    controller_rate: the controller's set-point stream rate [Hz] (robot file's [controller]
        rate_hz; a UR e-Series 500, a CB3 125), else None.
    """

    name: str
    sigma: tuple[int, ...]
    alpha: tuple[float, ...]
    d: tuple[float, ...]
    theta: tuple[float, ...]
    r: tuple[float, ...]
    limits: Limits
    d_labels: tuple[str, ...] = ()
    r_labels: tuple[str, ...] = ()
    controller_offsets: np.ndarray = field(default_factory=lambda: np.zeros(0))
    gear_ratios: np.ndarray = field(default_factory=lambda: np.zeros(0))
    Rq: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    Rt: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    spring: Spring | None = None
    coupling: Coupling | None = None
    offsets: bool = False
    asymmetric_coulomb: tuple[int, ...] = ()
    gravity: float | tuple[float, float, float] = GRAVITY  # g along -z0, or the vector in frame 0
    description: str = ""
    source: str = ""
    urdf: Any = None
    joint_names: tuple[str, ...] = ()
    nominal: Any = None
    flange: np.ndarray | None = None
    controller_rate: float | None = None  # [Hz] the controller's set-point rate ([controller] rate_hz)

    @property
    def gravity_vector(self) -> np.ndarray:
        """Gravity acceleration in frame 0 [m/s^2], shape (3,)."""
        return gravity_vector(self.gravity)

    def __post_init__(self) -> None:
        n = len(self.sigma)
        for fname in ("alpha", "d", "theta", "r"):
            if len(getattr(self, fname)) != n:
                raise ValueError(f"robot {self.name!r}: {fname} has {len(getattr(self, fname))} "
                                 f"entries, expected {n}")
        defaults = {
            "d_labels": tuple(f"D{j + 1}" for j in range(n)),
            "r_labels": tuple(f"RL{j + 1}" for j in range(n)),
            "controller_offsets": np.zeros(n),
            "gear_ratios": np.ones(n),
            "Rq": np.eye(n),
            "Rt": np.eye(n),
        }
        for key, value in defaults.items():
            current = getattr(self, key)
            if len(current) == 0:
                current = value
            if isinstance(current, np.ndarray):
                current = np.array(current, dtype=float)
                current.setflags(write=False)
            object.__setattr__(self, key, current)
        if self.coupling is not None and max(self.coupling.joints) >= n:
            raise ValueError(f"robot {self.name!r}: coupling joints {self.coupling.joints} "
                             f"outside 1..{n}")
        asym = tuple(sorted({int(j) for j in self.asymmetric_coulomb}))
        if any(not 0 <= j < n for j in asym):
            raise ValueError(f"robot {self.name!r}: asymmetric Coulomb joints "
                             f"{[j + 1 for j in asym]} outside 1..{n}")
        if asym and self.offsets:
            raise ValueError(
                f"robot {self.name!r}: asymmetric Coulomb friction (FSP/FSN) on joint(s) "
                f"{', '.join(str(j + 1) for j in asym)} and torque offsets OFF1..OFF{n} together: on moving "
                f"samples FSPj·[q̇j>0] − FSNj·[q̇j<0] and OFFj are collinear (one parameterisation per "
                f"joint); choose either the offsets or the asymmetric Coulomb form")
        object.__setattr__(self, "asymmetric_coulomb", asym)

    # ----------------------------------------------------------------- description
    def ros_joint_names(self) -> tuple[str, ...]:
        """The joints' names in ROS messages: ``joint_names``, else the URDF's joint names, else ()."""
        if self.joint_names:
            return tuple(self.joint_names)
        return tuple(self.urdf.joints) if self.urdf is not None else ()

    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.sigma)

    @cached_property
    def parameter_names(self) -> tuple[str, ...]:
        """Standard parameters: 13 per link (eq. 4), then coupling friction, asymmetric Coulomb
        friction (FSPj, FSNj per asymmetric joint), then offsets."""
        names = link_parameter_names(self.n)
        if self.coupling is not None:
            b = self.coupling.joints[1] + 1
            names += [f"FVM{b}", f"FSM{b}"]
        for j in self.asymmetric_coulomb:
            # FSj's column is then 0 (not a base parameter): FS+ and FS- replace it.
            names += [f"FSP{j + 1}", f"FSN{j + 1}"]
        if self.offsets:
            names += [f"OFF{j}" for j in range(1, self.n + 1)]
        return tuple(names)

    def parameter_index(self, names: Iterable[str]) -> list[int]:
        """Column of each named standard parameter (refuses unknown names)."""
        lookup = {p: i for i, p in enumerate(self.parameter_names)}
        out = []
        for p in names:
            if p not in lookup:
                raise KeyError(f"robot {self.name!r} has no parameter {p!r}")
            out.append(lookup[p])
        return out

    def parameter_vector(self, values: dict[str, float], strict: bool = True) -> np.ndarray:
        """Vector chi from a name -> value dict (missing names are 0 unless strict)."""
        unknown = set(values) - set(self.parameter_names)
        if unknown:
            raise KeyError(f"robot {self.name!r} has no parameter(s) {sorted(unknown)}")
        if strict:
            missing = [p for p in self.parameter_names if p not in values]
            if missing:
                raise KeyError(f"parameter(s) missing for robot {self.name!r}: {missing[:5]}...")
        return np.array([float(values.get(p, 0.0)) for p in self.parameter_names])

    def with_options(self, **changes: Any) -> "Robot":
        """A copy with some fields changed (e.g. offsets=True); caches are not carried over."""
        return replace(self, **_neutral(changes))

    # ----------------------------------------------------------------- conventions
    def to_model(self, q_controller: Any) -> np.ndarray:
        """Joint positions from the controller's convention (what a log holds) to model (Khalil)
        angles [rad], (N, n) or (n,): q_model = q_controller - controller_offsets."""
        return np.asarray(q_controller, dtype=float) - self.controller_offsets

    def to_controller(self, q: Any) -> np.ndarray:
        """Joint positions from model (Khalil) angles to the controller's convention [rad]."""
        return np.asarray(q, dtype=float) + self.controller_offsets

    # Former RX90 words, kept one release.
    @property
    def staubli_offsets(self) -> np.ndarray:
        """Deprecated: :attr:`controller_offsets`."""
        _renamed("Robot.staubli_offsets", "Robot.controller_offsets")
        return self.controller_offsets

    def to_khalil(self, q_staubli: Any) -> np.ndarray:
        """Deprecated: :meth:`to_model`."""
        _renamed("Robot.to_khalil", "Robot.to_model")
        return self.to_model(q_staubli)

    def to_staubli(self, q: Any) -> np.ndarray:
        """Deprecated: :meth:`to_controller`."""
        _renamed("Robot.to_staubli", "Robot.to_controller")
        return self.to_controller(q)

    # ----------------------------------------------------------------- symbolic model
    @cached_property
    def _symbols(self) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
        n = self.n
        return (ca.SX.sym("q", n), ca.SX.sym("qd", n), ca.SX.sym("qdd", n),
                ca.SX.sym("chi", len(self.parameter_names)))

    @cached_property
    def _tau_expression(self) -> ca.SX:
        q, qd, qdd, chi = self._symbols
        return inverse_dynamics_expression(self, q, qd, qdd, chi)

    @cached_property
    def inverse_dynamics(self) -> ca.Function:
        """The inverse dynamic model as a ``casadi.Function`` (q, qd, qdd, chi) -> tau [N m],
        spring excluded (eq. 1). Called with numbers it returns a ``casadi.DM`` column (n, 1):
        ``np.array(robot.inverse_dynamics(q, qd, qdd, chi).full()).ravel()`` gives an ndarray (n,);
        called with SX/MX it returns the symbolic expression."""
        q, qd, qdd, chi = self._symbols
        return ca.Function("inverse_dynamics", [q, qd, qdd, chi], [self._tau_expression],
                           ["q", "qd", "qdd", "chi"], ["tau"])

    @cached_property
    def regressor(self) -> ca.Function:
        """The regressor as a ``casadi.Function`` (q, qd, qdd) -> Phi (n x len(parameter_names)),
        Gamma = Phi chi (eq. 2). Called with numbers it returns a ``casadi.DM``; use
        ``.full()`` for an ndarray, or :meth:`regressor_batch` for many samples."""
        q, qd, qdd, chi = self._symbols
        phi = ca.jacobian(self._tau_expression, chi)
        return ca.Function("regressor", [q, qd, qdd], [phi], ["q", "qd", "qdd"], ["Phi"])

    @cached_property
    def spring_torque(self) -> ca.Function:
        """casadi.Function (q) -> torque exerted by the spring on each joint (n,) [N m]."""
        return spring_torque_function(self)

    @cached_property
    def forward_kinematics(self) -> ca.Function:
        """casadi.Function (q) -> (T0n 4x4, origins 3 x n of frames 1..n in frame 0 [m])."""
        return forward_kinematics_function(self)

    # ----------------------------------------------------------------- compiled batches
    @cached_property
    def _regressor_batch(self) -> BatchFunction:
        return BatchFunction(self.regressor, name=f"{self.name}_regressor")

    def regressor_batch(self, Q: Any, QD: Any, QDD: Any, out: np.ndarray | None = None) -> np.ndarray:
        """Phi on N samples at once, compiled: arrays (N, n) -> ndarray (N, n, n_params).

        out: optional preallocated (N, n, n_params) array filled in place."""
        return self._regressor_batch(Q, QD, QDD, out=out)

    def regressor_workspace(self, chunk: int = 2048) -> BatchWorkspace:
        """A reused buffer for Phi on many samples (``.evaluate`` or streamed ``.chunks``):
        repeated evaluations without a fresh (N, n, n_params) array each time."""
        return BatchWorkspace(self._regressor_batch, chunk)

    @cached_property
    def _spring_batch(self) -> BatchFunction:
        return BatchFunction(self.spring_torque, name=f"{self.name}_spring", compile=False)

    def spring_torque_batch(self, Q: Any) -> np.ndarray:
        """Spring torque on N samples: (N, n) -> (N, n, 1) [N m] (zeros without a spring: no CasADi call)."""
        if self.spring is None and np.ndim(Q) == 2 and np.shape(Q)[1] == self.n:
            return np.zeros((np.shape(Q)[0], self.n, 1))
        return self._spring_batch(Q)

    def frame_origins(self, q: Any) -> np.ndarray:
        """Origins of frames 1..n in frame 0 for one configuration: (n,) -> (n, 3) [m]."""
        return self.forward_kinematics(np.asarray(q, float))[1].full().T

    def export_c(self, directory: str, functions: Sequence[str] = ("inverse_dynamics", "regressor")) -> list[str]:
        """Write self-contained C source of the named functions (for a controller); returns paths."""
        from .compiled import export_c

        return export_c([getattr(self, f) for f in functions], directory, prefix=self.name)


def robot_from_table(rows: Sequence[Sequence[float]], name: str = "robot", **options: Any) -> Robot:
    """Robot from rows (sigma, alpha, d, theta, r) [-, rad, m, rad, m]: no limits, no coupling,
    no spring unless given in ``options`` (any Robot field)."""
    rows = [tuple(r) for r in rows]
    for i, row in enumerate(rows, 1):
        if len(row) != 5:
            raise ValueError(f"table row {i}: expected (sigma, alpha, d, theta, r), got {len(row)} values")
        if row[0] not in (0, 1):
            raise ValueError(f"table row {i}: sigma must be 0 (revolute) or 1 (prismatic), got {plain(row[0])}")
    n = len(rows)
    if n == 0:
        raise ValueError("table has no rows")
    cols = list(zip(*rows))
    options = _neutral(options)
    options.setdefault("limits", Limits.unbounded(n))
    return Robot(name=name, sigma=tuple(int(s) for s in cols[0]),
                 alpha=tuple(float(x) for x in cols[1]), d=tuple(float(x) for x in cols[2]),
                 theta=tuple(float(x) for x in cols[3]), r=tuple(float(x) for x in cols[4]),
                 **options)
