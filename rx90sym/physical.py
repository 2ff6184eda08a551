"""Is a set of standard parameters what a simulator accepts? The one check shared by the consistent
fit (after its solve, with the fit's margin) and every export (URDF, MJCF; margin 0).

Rule: every body (the ten inertial parameters of a link, ``XXj .. Mj``, or of the payload,
``XXc .. Mc``) is physical with the margin (rx90sym.rigid_body.physical_problem, one tolerance:
PHYSICAL_RTOL, rounding), and every parameter whose name starts with one of ``NONNEGATIVE``
(rotor inertia IA, Coulomb FS, viscous FV; so FSPj, FSNj, FVMj, FSMj too) is >= the margin.
At margin 0 a body whose ten parameters are all exactly 0 (massless) passes.

The margin of a consistent fit, DEFAULT_MARGIN = 1e-8, is absolute (kg m^2 along the pseudo-inertia's
spatial directions, kg along its mass, and the unit of each prefixed parameter: kg m^2, N m,
N m s/rad), not relative to the link's size, because

- what it must stay above is absolute: the interior-point solver meets the cone constraints to
  ~1e-9 in these SI units (measured without a margin: worst -8.3e-10 on links of 0.5 to 30 kg),
  up to 4e-8 when asked for a margin on a short UR10e twin, and the simulators' refusals are absolute (MuJoCo: mass >= 1e-9 kg, principal moment
  >= 1e-12 kg m^2, rx90sym.mjcf_export.MIN_MASS / MIN_INERTIA; a margin eps gives m >= eps and
  principal moments >= 2 eps);
- a margin relative to the link would need the link's size before the fit has found it (a prior
  is optional);
- it is physically nothing: 1e-8 kg m^2 is a gram spread over 3 mm, 1e-3 of the smallest
  pseudo-inertia eigenvalue of any bundled robot's nominal bodies (Panda link 2: 8.6e-7).

The fit asks the solver for ten times the margin (pseudo-inertias >= 10 eps 1, prefixed parameters
>= 10 eps; identify.estimation.consistency.fit.SOLVE_FACTOR) and checks the solution against eps,
so the solver's own error (up to 4e-8 measured) does not decide the check; when it does, the fit
re-solves with a larger margin.
"""
from __future__ import annotations

import re
from collections.abc import Mapping, Sequence

import numpy as np

from .rigid_body import RigidBody, physical_problem

__all__ = ["DEFAULT_MARGIN", "INERTIAL_FIELDS", "NONNEGATIVE", "body_indices", "nearest_physical_body",
           "nonnegative_indices", "parameter_problems"]

#: Margin of a consistent fit (module docstring): pseudo-inertias >= eps 1, prefixed parameters >= eps.
DEFAULT_MARGIN = 1e-8
#: Name prefixes of the parameters that must be >= 0 (>= the margin in a consistent fit).
NONNEGATIVE: tuple[str, ...] = ("IA", "FV", "FS")
#: The ten inertial entries of one body, in the order of eq. 4 (and of the payload XXc..Mc).
INERTIAL_FIELDS: tuple[str, ...] = ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M")

# A body is a link number or the payload suffix "c". The alternation lists two-letter fields
# first so that "MX1" is read as MX of link 1, never as M of a link called "X1".
_INERTIAL_NAME = re.compile(r"^(XX|XY|XZ|YY|YZ|ZZ|MX|MY|MZ|M)(\d+|c)$")


def body_indices(names: Sequence[str]) -> dict[str, np.ndarray]:
    """Indices of the ten inertial parameters of every body present in ``names``.

    Returns:
        ``{body: indices (10,)}`` with body ``"1"``, ``"2"``, … for links (numeric order) and
        ``"c"`` for the payload (last); indices follow :data:`INERTIAL_FIELDS`.

    Raises:
        ValueError: a body has some but not all of its ten inertial parameters (a partial body
            cannot be checked and would silently escape the constraints), or a name repeats.
    """
    position: dict[str, int] = {}
    for i, name in enumerate(names):
        if name in position:
            raise ValueError(f"parameter names: {name!r} appears twice (positions {position[name]} and {i})")
        position[name] = i
    found: dict[str, dict[str, int]] = {}
    for name, i in position.items():
        match = _INERTIAL_NAME.match(name)
        if match:
            found.setdefault(match.group(2), {})[match.group(1)] = i
    out: dict[str, np.ndarray] = {}
    for body in sorted(found, key=lambda b: (b == "c", int(b) if b.isdigit() else 0)):
        fields = found[body]
        missing = [f + body for f in INERTIAL_FIELDS if f not in fields]
        if missing:
            raise ValueError(
                f"parameter names: body {body!r} has only some inertial parameters; missing {missing}"
            )
        out[body] = np.array([fields[f] for f in INERTIAL_FIELDS], dtype=int)
    return out


def nonnegative_indices(names: Sequence[str], prefixes: Sequence[str] = NONNEGATIVE) -> np.ndarray:
    """Indices of names starting with any of ``prefixes`` (the rule of the module docstring)."""
    prefixes = tuple(prefixes)
    if not prefixes:
        return np.zeros(0, dtype=int)
    return np.array([i for i, n in enumerate(names) if n.startswith(prefixes)], dtype=int)


def body_problem(p10: np.ndarray, margin: float = 0.0) -> str | None:
    """physical_problem of the body XX..M ``p10``; at margin 0 an all-zero (massless) body passes."""
    p10 = np.asarray(p10, dtype=float)
    if margin == 0.0 and not np.any(p10):
        return None
    return physical_problem(RigidBody.from_vector(p10), margin)


def parameter_problems(names: Sequence[str], chi: np.ndarray, margin: float = 0.0,
                       nonnegative: Sequence[str] = NONNEGATIVE,
                       labels: Mapping[str, str] | None = None,
                       carried: Mapping[str, np.ndarray] | None = None) -> tuple[str, ...]:
    """What keeps ``chi`` (standard parameters named ``names``, SI) from being physical with
    ``margin`` (module docstring): one line per body ("link 3: not a physical rigid body (...)",
    the body named ``labels[body]`` when given, e.g. a URDF link) and per prefixed parameter
    below the margin; empty when physical. ``carried[body]``: XX..M of what the body carries and
    an export writes apart (a URDF link's lumped children, rx90sym.urdf_carried.carried_bodies):
    the body minus it is checked."""
    names = tuple(names)
    chi = np.asarray(chi, dtype=float)
    if chi.shape != (len(names),):
        raise ValueError(f"parameter_problems: {chi.shape[0] if chi.ndim == 1 else chi.shape} values for "
                         f"{len(names)} names")
    out = []
    for body, idx in body_indices(names).items():
        own = chi[idx] - np.asarray((carried or {}).get(body, 0.0), dtype=float)
        problem = body_problem(own, margin)
        if problem is not None:
            label = (labels or {}).get(body) or ("payload" if body == "c" else f"link {body}")
            out.append(f"{label}: not a physical rigid body ({problem})")
    for i in nonnegative_indices(names, nonnegative):
        if not chi[i] >= margin:  # NaN fails too
            out.append(f"{names[i]} = {chi[i]:.3g} < {margin:g}")
    return tuple(out)


def nearest_physical_body(body: RigidBody, margin: float = DEFAULT_MARGIN) -> RigidBody:
    """The physical body nearest to ``body`` with its mass and centre of mass (mass > 0 required).

    About the centre of mass c the pseudo-inertia is blockdiag(S, m), S = tr(I)/2 1 - I the second
    moments of the mass [kg m^2] (rx90sym.rigid_body.pseudo_inertia); keeping m and c, the nearest
    (Frobenius norm) has S's eigenvalues raised to a floor, in S's own axes: the cone of the consistent
    fit's LMIs. The floor is ``margin`` / s^2, s the smallest singular value of the translation by c
    (the pseudo-inertia about the frame's origin is T blockdiag(S, m) T^T), so that the body is physical
    with ``margin`` in the frame it is given in (physical_problem(., margin) is None; within a few
    margins of the exact nearest such body). The principal moments follow as I_a = S_b + S_c: with one
    second moment below 0 (the triangle inequality I_a + I_b < I_c broken) the largest moment is kept
    and the two others raised. A body physical with ``margin`` already is returned as it is."""
    if not body.m > margin:
        raise ValueError(f"nearest_physical_body: the mass must be > {margin:g} kg, got {body.m:g}")
    if physical_problem(body, margin) is None:
        return body
    c, inertia = body.com_inertia()
    translation = np.eye(4)
    translation[:3, 3] = c
    floor = margin / np.linalg.svd(translation, compute_uv=False)[-1] ** 2
    S = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    lam, V = np.linalg.eigh(0.5 * (S + S.T))
    S = V @ np.diag(np.maximum(lam, floor)) @ V.T
    return RigidBody.from_com(body.m, c, np.eye(3), np.trace(S) * np.eye(3) - S)
