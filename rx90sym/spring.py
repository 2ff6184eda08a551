"""Counterbalance spring on one joint (paper section II-C, DESIGN.md): a model, a table, or
(rx90sym.spring_fit / identify) a torque identified from data."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

if TYPE_CHECKING:  # for annotations only
    from .description import Robot


#: The constants of the spring model (all needed unless the spring is a table).
SPRING_CONSTANTS = ("k", "a", "b", "L0", "angle_offset")


@dataclass(frozen=True, eq=False)
class Spring:
    """Spring acting on one joint; either the default model or a table.

    Default model, torque exerted by the spring on the link about its joint axis [N m]:
    ``tau_s = -k a b sin(ts) (1 - L0 / L)``, ``L = sqrt(a^2 + b^2 - 2 a b cos ts)``,
    ``ts = q + angle_offset`` (q in Khalil angles [rad]).

    Attributes: joint (0-based index), k [N/m], a, b, L0 [m], angle_offset [rad],
    table: optional (angles [rad, Khalil], torques [N m]) replacing the model, interpolated
    linearly (extrapolation is refused at evaluation time by clipping to the table's range).
    placeholder: the constants are invented, not the maker's (the bundled RX90's spring: its
    constants are not published); every output that uses such a spring says so.
    No defaults: a robot's constants come from its robot file (the RX90's placeholder is in
    rx90.toml); a table needs none of them.
    """

    joint: int
    k: float | None = None
    a: float | None = None
    b: float | None = None
    L0: float | None = None
    angle_offset: float | None = None
    table: tuple[np.ndarray, np.ndarray] | None = field(default=None)
    placeholder: bool = False

    def __post_init__(self) -> None:
        missing = [n for n in SPRING_CONSTANTS if getattr(self, n) is None]
        if self.table is None and missing:
            raise ValueError(f"spring on joint {self.joint + 1}: give {', '.join(missing)} "
                             "(no defaults) or a table")

    def describe(self) -> dict[str, Any]:
        """JSON-ready description (joint 1-based) for outputs that use the spring."""
        out: dict[str, Any] = {"joint": self.joint + 1, "placeholder": self.placeholder}
        if self.table is not None:
            out["model"] = f"table ({len(self.table[0])} points)"
        else:
            out.update(model="k a b sin(ts) (1 - L0 / L)", k=self.k, a=self.a, b=self.b, L0=self.L0,
                       angle_offset_rad=float(self.angle_offset))
        return out

    def label(self) -> str:
        """One line for tables and logs; says 'PLACEHOLDER' when the constants are invented."""
        what = (f"table of {len(self.table[0])} points" if self.table is not None
                else f"k = {self.k:g} N/m, a = {self.a:g} m, b = {self.b:g} m, L0 = {self.L0:g} m")
        tag = " PLACEHOLDER (invented constants, not the maker's)" if self.placeholder else ""
        return f"spring on joint {self.joint + 1}: {what}{tag}"

    def torque_expression(self, angle: Any) -> Any:
        """Spring torque for a joint angle (SX or float)."""
        if self.table is not None:
            x, y = self.table
            interp = ca.interpolant("spring_table", "linear", [np.asarray(x, float)],
                                    np.asarray(y, float))
            lo, hi = float(x[0]), float(x[-1])
            return interp(ca.fmin(ca.fmax(angle, lo), hi))
        ts = angle + self.angle_offset
        L = ca.sqrt(self.a**2 + self.b**2 - 2 * self.a * self.b * ca.cos(ts))
        return -self.k * self.a * self.b * ca.sin(ts) * (1 - self.L0 / L)


def spring_torque_function(robot: Robot) -> ca.Function:
    """casadi.Function (q) -> spring torque on each joint (n,), zero without a spring."""
    q = ca.SX.sym("q", robot.n)
    tau = ca.SX.zeros(robot.n, 1)
    if robot.spring is not None:
        tau[robot.spring.joint] = robot.spring.torque_expression(q[robot.spring.joint])
    return ca.Function("spring_torque", [q], [tau], ["q"], ["tau_spring"])


def read_spring_table(path: str) -> tuple[np.ndarray, np.ndarray]:
    """Read a CSV of (angle [rad, Khalil], torque [N m]) rows, header optional."""
    try:
        data = np.genfromtxt(path, delimiter=",", comments="#", dtype=float)
    except OSError as exc:
        raise ValueError(f"{path}: cannot read spring table ({exc})") from None
    if data.ndim == 2 and np.isnan(data[0]).all():
        data = data[1:]
    if data.ndim != 2 or data.shape[1] != 2 or len(data) < 2:
        raise ValueError(f"{path}: spring table needs two columns (angle, torque) and >= 2 rows")
    bad = np.argwhere(~np.isfinite(data))
    if len(bad):
        raise ValueError(f"{path}: spring table row {bad[0, 0] + 1} is not a finite number")
    if np.any(np.diff(data[:, 0]) <= 0):
        row = int(np.argmax(np.diff(data[:, 0]) <= 0)) + 2
        raise ValueError(f"{path}: spring table angles must increase (row {row})")
    return data[:, 0].copy(), data[:, 1].copy()


@dataclass(frozen=True)
class SpringBasis:
    """A spring torque linear in its unknowns, for identifying it from data.

    ``tau_s(theta) = c0 + sum_h (C_h cos(h theta) + S_h sin(h theta))`` [N m] on joint
    ``joint`` (0-based), theta its model (Khalil) angle [rad]: a Fourier series in the joint
    angle, which represents any spring acting on that joint alone (the RX90's, whose harmonics
    decay like (a/b)^h, needs a few orders). Coefficients in N m, named SP0_j, SPCh_j, SPSh_j
    (j = joint + 1). Columns aliased with the rigid-body model (the first harmonic with the
    gravity parameters MX2R/MY2 of a horizontal joint, the constant with the offset OFFj) are
    removed when the basis is attached to an identification (identify.observation.spring_fit).
    """

    joint: int
    orders: tuple[int, ...] = (1, 2, 3, 4)
    constant: bool = True

    def __post_init__(self) -> None:
        if any(int(h) != h or h < 1 for h in self.orders) or len(set(self.orders)) != len(self.orders):
            raise ValueError(f"spring basis: orders must be distinct integers >= 1, got {self.orders}")
        if not self.orders and not self.constant:
            raise ValueError("spring basis: no function (give orders or constant=True)")

    @property
    def names(self) -> tuple[str, ...]:
        j = self.joint + 1
        out = [f"SP0_{j}"] if self.constant else []
        for h in self.orders:
            out += [f"SPC{h}_{j}", f"SPS{h}_{j}"]
        return tuple(out)

    def functions(self, theta: Any) -> np.ndarray:
        """Basis functions at joint angles theta (S,) [rad] -> (S, len(names))."""
        theta = np.asarray(theta, dtype=float).reshape(-1)
        cols = [np.ones_like(theta)] if self.constant else []
        for h in self.orders:
            cols += [np.cos(h * theta), np.sin(h * theta)]
        return np.stack(cols, axis=1)

    def torque(self, coefficients: dict[str, float], theta: Any) -> np.ndarray:
        """Spring torque [N m] at theta (S,) from coefficients name -> value (missing: 0)."""
        c = np.array([coefficients.get(name, 0.0) for name in self.names])
        return self.functions(theta) @ c


@dataclass(frozen=True)
class SpringStiffness:
    """The spring's stiffness as the only unknown, for a known geometry (a, b, L0, angle offset
    of ``spring``): ``tau_s = k f(theta)``, f the model of :class:`Spring` per unit k [N m / (N/m)].
    One coefficient, named KS_j (j = joint + 1) [N/m]."""

    spring: Spring

    def __post_init__(self) -> None:
        if self.spring.table is not None:
            raise ValueError("spring stiffness: the spring is a table, it has no geometry (a, b, L0)")

    @property
    def joint(self) -> int:
        return self.spring.joint

    @property
    def names(self) -> tuple[str, ...]:
        return (f"KS_{self.spring.joint + 1}",)

    def functions(self, theta: Any) -> np.ndarray:
        s = self.spring
        ts = np.asarray(theta, dtype=float).reshape(-1) + s.angle_offset
        L = np.sqrt(s.a**2 + s.b**2 - 2 * s.a * s.b * np.cos(ts))
        return (-s.a * s.b * np.sin(ts) * (1 - s.L0 / L))[:, None]

    def torque(self, coefficients: dict[str, float], theta: Any) -> np.ndarray:
        return self.functions(theta)[:, 0] * coefficients.get(self.names[0], 0.0)
