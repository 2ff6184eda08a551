"""Khalil-Kleinfinger geometry: frame transforms and the forward geometric model."""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import casadi as ca

if TYPE_CHECKING:  # for annotations only
    from .description import Robot


def exact_trig(angle: Any) -> tuple[Any, Any]:
    """(cos, sin) of an angle; numeric angles that are multiples of pi/2 give exact 0 and +-1.

    Exact zeros matter: they keep the symbolic model sparse and make the regrouping rules see
    "axis parallel / perpendicular" structurally instead of as 6e-17.
    """
    if isinstance(angle, (int, float)):
        c, s = math.cos(angle), math.sin(angle)
        return _snap(c), _snap(s)
    return ca.cos(angle), ca.sin(angle)


def _snap(x: float) -> float:
    for v in (0.0, 1.0, -1.0):
        if abs(x - v) < 1e-12:
            return v
    return x


def rot_x(c: Any, s: Any) -> ca.SX:
    return ca.SX(ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, c, -s), ca.horzcat(0, s, c)))


def rot_z(c: Any, s: Any) -> ca.SX:
    return ca.SX(ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1)))


def joint_transform(alpha: Any, d: Any, theta: Any, r: Any) -> tuple[ca.SX, ca.SX]:
    """Rotation and origin of frame j in frame j-1.

    T = Rot(x, alpha) Trans(x, d) Rot(z, theta) Trans(z, r), so
    R = Rx(alpha) Rz(theta) and P = (d, -sin(alpha) r, cos(alpha) r).
    """
    ca_, sa = exact_trig(alpha)
    ct, st = exact_trig(theta)
    R = ca.mtimes(rot_x(ca_, sa), rot_z(ct, st))
    P = ca.SX(ca.vertcat(d, -sa * r, ca_ * r))
    return R, P


def joint_variables(robot: Robot, q: ca.SX) -> list[tuple[Any, Any]]:
    """(theta_j, r_j) of each joint for joint positions q (revolute: theta, prismatic: r)."""
    out = []
    for j in range(robot.n):
        if robot.sigma[j] == 0:
            out.append((robot.theta[j] + q[j], robot.r[j]))
        else:
            out.append((robot.theta[j], robot.r[j] + q[j]))
    return out


def frame_transforms(robot: Robot, q: ca.SX) -> list[tuple[ca.SX, ca.SX]]:
    """(R_j, P_j) of frame j in frame j-1 for j = 1..n."""
    return [
        joint_transform(robot.alpha[j], robot.d[j], th, rr)
        for j, (th, rr) in enumerate(joint_variables(robot, q))
    ]


def forward_kinematics_function(robot: Robot) -> ca.Function:
    """casadi.Function (q) -> (T0n 4x4, origins 3 x n of frames 1..n in frame 0)."""
    q = ca.SX.sym("q", robot.n)
    R = ca.SX.eye(3)
    p = ca.SX.zeros(3, 1)
    origins = []
    for Rj, Pj in frame_transforms(robot, q):
        p = p + ca.mtimes(R, Pj)
        R = ca.mtimes(R, Rj)
        origins.append(p)
    T = ca.vertcat(ca.horzcat(R, p), ca.horzcat(ca.SX.zeros(1, 3), ca.SX(1)))
    return ca.Function("forward_kinematics", [q], [T, ca.horzcat(*origins)], ["q"], ["T", "origins"])
