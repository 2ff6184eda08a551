"""Counterbalance spring of axis 2 (paper section II-C, DESIGN.md)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np


@dataclass(frozen=True, eq=False)
class Spring:
    """Spring acting on one joint; either the default model or a table.

    Default model, torque exerted by the spring on the link about its joint axis [N m]:
    ``tau_s = -k a b sin(ts) (1 - L0 / L)``, ``L = sqrt(a^2 + b^2 - 2 a b cos ts)``,
    ``ts = q + angle_offset`` (q in Khalil angles [rad]).

    Attributes: joint (0-based index), k [N/m], a, b, L0 [m], angle_offset [rad],
    table: optional (angles [rad, Khalil], torques [N m]) replacing the model, interpolated
    linearly (extrapolation is refused at evaluation time by clipping to the table's range).
    """

    joint: int = 1
    k: float = 4000.0
    a: float = 0.10
    b: float = 0.30
    L0: float = 0.05
    angle_offset: float = np.pi / 2
    table: tuple[np.ndarray, np.ndarray] | None = field(default=None)

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


def spring_torque_function(robot: Any) -> ca.Function:
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
