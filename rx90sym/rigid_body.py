"""Inertial parameters of one rigid body in numbers: frame changes, lumping, physical checks.

A body is (m, h, J): mass [kg], first moment h = m c [kg m] and inertia J about the frame
origin [kg m^2], all in one frame's axes -- the form of the standard parameters (eq. 4), in
which bodies rigidly joined simply add once expressed in the same frame.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class RigidBody:
    """m [kg], h (3,) [kg m], J (3, 3) about the frame origin [kg m^2]."""

    m: float
    h: np.ndarray
    J: np.ndarray

    @staticmethod
    def zero() -> "RigidBody":
        return RigidBody(0.0, np.zeros(3), np.zeros((3, 3)))

    @staticmethod
    def from_com(m: float, com: np.ndarray, R: np.ndarray, I_com: np.ndarray) -> "RigidBody":
        """Body of mass m with centre of mass ``com`` and inertia ``I_com`` about it, given in
        axes rotated by R (a URDF <inertial>: origin xyz = com, rpy -> R)."""
        c = np.asarray(com, float)
        J = R @ np.asarray(I_com, float) @ R.T + m * (c @ c * np.eye(3) - np.outer(c, c))
        return RigidBody(float(m), m * c, 0.5 * (J + J.T))

    @staticmethod
    def from_vector(p: np.ndarray) -> "RigidBody":
        """From XX XY XZ YY YZ ZZ MX MY MZ M (the first ten standard parameters of a link)."""
        XX, XY, XZ, YY, YZ, ZZ, MX, MY, MZ, M = (float(x) for x in p[:10])
        return RigidBody(M, np.array([MX, MY, MZ]),
                         np.array([[XX, XY, XZ], [XY, YY, YZ], [XZ, YZ, ZZ]]))

    def vector(self) -> np.ndarray:
        """XX XY XZ YY YZ ZZ MX MY MZ M, in INERTIAL order."""
        J, h = self.J, self.h
        return np.array([J[0, 0], J[0, 1], J[0, 2], J[1, 1], J[1, 2], J[2, 2], h[0], h[1], h[2], self.m])

    def __add__(self, other: "RigidBody") -> "RigidBody":
        return RigidBody(self.m + other.m, self.h + other.h, self.J + other.J)

    def __sub__(self, other: "RigidBody") -> "RigidBody":
        return RigidBody(self.m - other.m, self.h - other.h, self.J - other.J)

    def expressed_in_parent(self, R: np.ndarray, p: np.ndarray) -> "RigidBody":
        """The body given in frame B, expressed in frame A where (R, p) is the pose of B in A.

        J_A = R J R^T - m [p]x^2 - ([p]x [Rh]x + [Rh]x [p]x) (parallel axes with first moments),
        h_A = m p + R h.
        """
        P = _skew(p)
        Rh = R @ self.h
        H = _skew(Rh)
        J = R @ self.J @ R.T - self.m * P @ P - (P @ H + H @ P)
        return RigidBody(self.m, self.m * np.asarray(p, float) + Rh, 0.5 * (J + J.T))

    def expressed_in_child(self, R: np.ndarray, p: np.ndarray) -> "RigidBody":
        """The body given in frame A, expressed in frame B where (R, p) is the pose of B in A."""
        return self.expressed_in_parent(R.T, -R.T @ np.asarray(p, float))

    def com_inertia(self) -> tuple[np.ndarray, np.ndarray]:
        """(centre of mass, inertia about it in the frame's axes); the mass must be > 0."""
        c = self.h / self.m
        I = self.J - self.m * (c @ c * np.eye(3) - np.outer(c, c))
        return c, 0.5 * (I + I.T)


def _skew(v: np.ndarray) -> np.ndarray:
    x, y, z = (float(a) for a in v)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


#: The one tolerance of every physical check (physical_problem: a consistent fit after its solve,
#: every export, a URDF's or a robot file's bodies): rounding only, relative to the body's size
#: (1e-12 of its pseudo-inertia's largest eigenvalue, ~1e4 times the rounding of a frame change).
#: A consistent fit's margin (rx90sym.physical.DEFAULT_MARGIN) is what keeps solver error out.
PHYSICAL_RTOL = 1e-12


def pseudo_inertia(body: RigidBody) -> np.ndarray:
    """4x4 pseudo-inertia [[S, h], [h^T, m]], S = tr(J)/2 1 - J = the integral of x x^T dm
    (Wensing, Kim & Slotine 2017, eq. 11): positive semidefinite iff the body is physical."""
    out = np.empty((4, 4))
    out[:3, :3] = 0.5 * np.trace(body.J) * np.eye(3) - body.J
    out[:3, 3] = out[3, :3] = body.h
    out[3, 3] = body.m
    return out


def physical_problem(body: RigidBody, margin: float = 0.0) -> str | None:
    """Why the body is not a physical rigid body with ``margin`` (None if it is).

    Physical with margin eps: the pseudo-inertia's smallest eigenvalue is >= eps (kg m^2 along the
    spatial directions, kg along the mass: m >= eps, the second moment of the mass about the centre
    of mass >= eps in every direction, so every principal moment of inertia and every triangle
    slack I_a + I_b - I_c >= 2 eps), within PHYSICAL_RTOL. margin 0: mass > 0, principal moments
    >= 0 obeying the triangle inequalities. The reason is given in those classical words."""
    if not (np.isfinite(body.m) and np.all(np.isfinite(body.h)) and np.all(np.isfinite(body.J))):
        return "non-finite inertial parameters"
    lam = np.linalg.eigvalsh(pseudo_inertia(body))
    if lam[0] >= margin - PHYSICAL_RTOL * max(abs(lam[0]), abs(lam[-1])) and body.m > 0:
        return None
    detail = f"pseudo-inertia eigenvalue {lam[0]:.3g}" + (f" < margin {margin:.3g}" if margin else "")
    if body.m <= 0:
        return f"mass {body.m:g} kg is not > 0"
    _, I = body.com_inertia()
    a, b, c = np.linalg.eigvalsh(I)
    if a < 0:
        return f"a principal moment of inertia about the centre of mass is negative ({a:g} kg m^2; {detail})"
    if a + b < c:
        return (f"principal moments {a:.4g}, {b:.4g}, {c:.4g} kg m^2 break the triangle inequality "
                f"({a:.4g} + {b:.4g} < {c:.4g}: no mass distribution has them)")
    return f"{detail} (mass {body.m:g} kg, principal moments {a:g}, {b:g}, {c:g} kg m^2)"
