"""Believable bodies: what the data cannot see is taken from a prior (the robot's nominal parameters).

The data fix the base parameters beta = K chi; the standard parameters chi are not unique (K has a
null space). The consistent fit with a prior (:func:`prior_fit`) has two stages:

1. the physically consistent least squares (:func:`consistent_least_squares`) under the prior's
   physical bounds (below): the best fit of the data, cost ``c1``;
2. among the physical chi whose fit costs at most ``c1 + sigma_rho^2`` (the weighted residual
   variance: the base parameters move by at most one eq.-13 standard deviation, 1 sigma along
   any direction), the one closest to the prior in the scaled norm
   ``sum_i ((chi_i - prior_i) / s_i)^2``. Without the bounds binding, chi's components in the
   null space of ``K S`` (the directions the data cannot see, in scaled units) are exactly the
   prior's (minimum-norm solution). The scales s_i are the prior's uncertainty, per link from
   the prior body: 10 % of m0 for M, 20 % of m0 * l for first moments, 100 % of m0 * l^2 for
   inertias (l: the prior's radius of gyration, at least 5 cm), 100 % of the prior's IA for IA
   (``uncertainty``: makers publish masses and centres of mass, inertias are derived), 1 for
   the rest (friction, offsets: seen by the data).

Physical bounds (both stages), from the prior:

- every link's pseudo-inertia positive semidefinite (as without a prior);
- density realisable on a bounding ellipsoid of the link (Wensing, Kim, Slotine 2017):
  ``tr(J P) >= 0`` with P the ellipsoid's quadric, which with J >= 0 puts the centre of mass
  (and the whole mass distribution's second moments) inside it. The ellipsoid: the uniform solid
  ellipsoid with the prior body's mass, centre of mass and inertia (semi-axes sqrt(5 lambda_i),
  lambda_i the principal second moments per unit mass), scaled by ``ellipsoid_scale`` (2) and at
  least ``min_semi_axis`` (5 cm) per axis. A guess of the link's extent from its prior, not a CAD
  envelope;
- masses above ``mass_floor`` (2 %) of the prior's link mass (and 1e-3 kg);
- rotor inertias within ``rotor_ratio`` (5x) of the prior's (when the prior's is > 0).
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import cvxpy as cp
import numpy as np

from rx90sym.rigid_body import RigidBody

from identify.estimation.consistency.lmi import body_indices, nonnegative_indices, pseudo_inertia

__all__ = ["Ellipsoid", "PhysicalPrior", "bodies_table", "nominal_prior", "prior_constraints", "prior_scales"]

MIN_MASS = 1e-3  # kg: MuJoCo and every simulator refuse near-massless moving bodies
# Relative uncertainty of the prior per kind (the scales s_i): makers publish masses and centres
# of mass (10 %, 20 % of m l); inertias and rotor inertias are derived (100 %).
DEFAULT_UNCERTAINTY = {"M": 0.1, "MX": 0.2, "XX": 1.0, "IA": 1.0}


@dataclass(frozen=True)
class Ellipsoid:
    """{x : (x - centre)^T A (x - centre) <= 1} in the link's frame [m]."""

    centre: np.ndarray
    A: np.ndarray

    def quadric(self) -> np.ndarray:
        """P (4x4) with tr(J P) = integral of 1 - (x - c)^T A (x - c) over the mass (J: pseudo-inertia)."""
        c, A = self.centre, self.A
        P = np.zeros((4, 4))
        P[:3, :3] = -A
        P[:3, 3] = P[3, :3] = A @ c
        P[3, 3] = 1.0 - c @ A @ c
        return P

    def contains(self, x: np.ndarray) -> bool:
        d = np.asarray(x, dtype=float) - self.centre
        return bool(d @ self.A @ d <= 1.0 + 1e-9)


@dataclass(frozen=True)
class PhysicalPrior:
    """The prior standard parameters (name -> value, SI) and the bounds derived from them.

    source: where the values come from (shown in every output); ellipsoid_scale, min_semi_axis
    [m], mass_floor (fraction of the prior mass), rotor_ratio: module docstring."""

    values: Mapping[str, float]
    source: str
    ellipsoid_scale: float = 2.0
    min_semi_axis: float = 0.05
    mass_floor: float = 0.02
    rotor_ratio: float = 5.0
    uncertainty: Mapping[str, float] = field(default_factory=lambda: dict(DEFAULT_UNCERTAINTY))

    def body(self, link: str) -> RigidBody:
        return RigidBody.from_vector(np.array([self.values[f"{p}{link}"] for p in
                                               ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")]))

    def ellipsoid(self, link: str) -> Ellipsoid:
        """The link's bounding ellipsoid (module docstring), in frame j."""
        body = self.body(link)
        c, I = body.com_inertia()
        second = 0.5 * np.trace(I) * np.eye(3) - I            # integral of x x^T dm about the CoG
        lam, V = np.linalg.eigh(second / body.m)
        semi = np.maximum(self.ellipsoid_scale * np.sqrt(5.0 * np.maximum(lam, 0.0)), self.min_semi_axis)
        return Ellipsoid(c, V @ np.diag(semi ** -2.0) @ V.T)

    def links(self, names: Sequence[str]) -> list[str]:
        """The link bodies of ``names`` that the prior describes with a positive mass."""
        return [b for b in body_indices(names) if b.isdigit() and self.values.get(f"M{b}", 0.0) > 0]


def nominal_prior(robot, source=None, say=None) -> "PhysicalPrior | None":
    """The prior of a consistent fit by default (``rx90 identify --method consistent`` and
    ``identify.fit(..., method="consistent")`` alike): ``source`` (a JSON parameter file or a
    mapping) or the robot's nominal parameters (its URDF inertials, else its robot file's
    [nominal] table); None, said through ``say`` (default: stderr), when the robot has none."""
    import sys

    import rx90sym

    say = say or (lambda line: print(line, file=sys.stderr))
    values = rx90sym.nominal_parameters(robot, source)
    if values is None:
        say(f"robot {robot.name!r} has no nominal parameters: the split of what the data cannot see is "
            f"arbitrary (give --prior FILE, or physical_prior=)")
        return None
    label = (source if isinstance(source, str) else "given parameters" if source is not None else
             f"[nominal] of {robot.source}" if robot.urdf is None else f"URDF inertials of {robot.source}")
    return PhysicalPrior(values, str(label))


def prior_scales(names: Sequence[str], prior: PhysicalPrior) -> np.ndarray:
    """s_i of the scaled distance to the prior (module docstring)."""
    s = np.ones(len(names))
    index = {n: i for i, n in enumerate(names)}
    for link in prior.links(names):
        body = prior.body(link)
        _, I = body.com_inertia()
        gyration = max(float(np.sqrt(np.trace(I) / (2 * body.m))), 0.05)
        u = prior.uncertainty
        for kind, scale in (("M", u["M"] * body.m), *((k, u["MX"] * body.m * gyration) for k in ("MX", "MY", "MZ"))):
            s[index[f"{kind}{link}"]] = scale
        for kind in ("XX", "XY", "XZ", "YY", "YZ", "ZZ"):
            s[index[f"{kind}{link}"]] = u["XX"] * body.m * gyration ** 2
        ia = prior.values.get(f"IA{link}", 0.0)
        if f"IA{link}" in index and ia > 0:
            s[index[f"IA{link}"]] = u["IA"] * ia
    return s


def prior_constraints(chi: cp.Variable, names: Sequence[str], prior: PhysicalPrior) -> list[cp.Constraint]:
    """The prior's physical bounds on the decision variable (module docstring)."""
    bodies = body_indices(names)
    out: list[cp.Constraint] = []
    for link in prior.links(names):
        idx = bodies[link]
        out.append(cp.trace(pseudo_inertia(chi[idx]) @ prior.ellipsoid(link).quadric()) >= 0)
        out.append(chi[idx[9]] >= max(prior.mass_floor * prior.values[f"M{link}"], MIN_MASS))
    for i in nonnegative_indices(names, ("IA",)):
        ia = prior.values.get(names[i], 0.0)
        if ia > 0:
            out += [chi[i] >= ia / prior.rotor_ratio, chi[i] <= ia * prior.rotor_ratio]
    return out


def bodies_table(n: int, standard: Mapping[str, float], prior: PhysicalPrior | None) -> str:
    """Per link: mass, centre of mass (frame j) and principal inertias at it, beside the prior's,
    and whether the centre of mass lies in the prior's bounding ellipsoid."""
    head = f"{'link':<5}{'mass kg':>9}{'prior':>9}   {'CoG m (frame j)':<26}{'prior CoG':<26}{'in ellipsoid':<13}" \
           f"principal inertias at CoG kg m^2 (prior)"
    lines = [head]
    for j in range(1, n + 1):
        body = RigidBody.from_vector(np.array([standard[f"{p}{j}"] for p in
                                               ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")]))
        c, I = body.com_inertia() if body.m > 0 else (np.full(3, np.nan), np.full((3, 3), np.nan))
        cells = [f"{j:<5}{body.m:9.3f}"]
        if prior is not None and str(j) in prior.links(list(standard)):
            pb = prior.body(str(j))
            pc, pI = pb.com_inertia()
            inside = "yes" if prior.ellipsoid(str(j)).contains(c) else "NO"
            cells += [f"{pb.m:9.3f}   {_vec(c):<26}{_vec(pc):<26}{inside:<13}"
                      f"{_vec(np.linalg.eigvalsh(I), '.3g')} ({_vec(np.linalg.eigvalsh(pI), '.3g')})"]
        else:
            cells += [f"{'—':>9}   {_vec(c):<26}{'—':<26}{'—':<13}{_vec(np.linalg.eigvalsh(I), '.3g')}"]
        lines.append("".join(cells))
    return "\n".join(lines)


def _vec(x: np.ndarray, fmt: str = "+.3f") -> str:
    return "[" + " ".join(f"{v:{fmt}}" for v in x) + "]"
