"""The spring from data: its torque identified with the other parameters.

The spring's torque is linear in its unknowns (rx90sym.spring.SpringBasis: a Fourier series in
the joint angle; SpringStiffness: k for a known geometry), so it enters the model as extra
columns: tau_motor = Phi_b beta - tau_s(q) (eqs. 1-2 with Gamma_s unknown). Columns that the
rigid-body model already spans are removed (:func:`spring_base`): on the RX90 the first harmonic
of theta2 equals the gravity columns of MX2R/MY2, so those parameters then hold the spring's
first harmonic too (grouped, like a regrouped parameter). The fit gives each coefficient its
sigma (eq. 14); :func:`spring_torque` gives the identified torque with its sigma band.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, Sequence

import numpy as np

import rx90sym
from rx90sym.spring import SpringBasis, SpringStiffness

SpringModel = SpringBasis | SpringStiffness


@dataclass(frozen=True, eq=False)
class BaseWithSpring:
    """Base parameters plus the spring's kept coefficients; usable as ``base`` of
    identify.fit / predict / validate with ``spring=False`` (the measured torque is then
    the motor torque alone, the spring being part of the model).

    base: the rigid-body base parameters; model: the spring's basis; kept: names of the
    coefficients identified; grouped: names left out because the base parameters span them.
    """

    base: Any
    model: SpringModel
    kept: tuple[str, ...]
    grouped: tuple[str, ...]

    @cached_property
    def names(self) -> tuple[str, ...]:
        return tuple(self.base.names) + self.kept

    @property
    def nb(self) -> int:
        return len(self.names)

    @cached_property
    def _columns(self) -> list[int]:
        return [self.model.names.index(name) for name in self.kept]

    def spring_columns(self, Q: Any) -> np.ndarray:
        """(S, n, len(kept)): -f_k(q_joint) in the spring joint's row (tau_motor = ... - tau_s)."""
        Q = np.asarray(Q, dtype=float)
        out = np.zeros((Q.shape[0], Q.shape[1], len(self.kept)))
        out[:, self.model.joint, :] = -self.model.functions(Q[:, self.model.joint])[:, self._columns]
        return out

    def regressor_batch(self, Q: Any, QD: Any, QDD: Any, out: np.ndarray | None = None) -> np.ndarray:
        """[Phi_b, spring columns] on N samples: (N, n, nb)."""
        full = np.concatenate([self.base.regressor_batch(Q, QD, QDD), self.spring_columns(Q)], axis=2)
        if out is not None:
            out[...] = full
            return out
        return full


def spring_base(robot: rx90sym.Robot, model: SpringModel, base: Any = None, samples: int = 200,
                seed: int = 0, tol: float = 1e-8) -> BaseWithSpring:
    """Attach a spring model to the base parameters, leaving out (grouping) every coefficient
    whose column the rigid-body columns and the already kept ones span, on ``samples`` random
    states (seeded): relative residual of its projection below ``tol``."""
    if not 0 <= model.joint < robot.n:
        raise ValueError(f"spring joint {model.joint + 1} is not a joint of robot {robot.name!r} (1..{robot.n})")
    if robot.sigma[model.joint] != 0:
        raise ValueError(f"spring joint {model.joint + 1} is prismatic: the spring bases take an angle")
    base = base if base is not None else rx90sym.base_parameters(robot)
    rng = np.random.default_rng(seed)
    Q = rng.uniform(-np.pi, np.pi, (samples, robot.n))
    QD, QDD = rng.normal(0, 2, (samples, robot.n)), rng.normal(0, 5, (samples, robot.n))
    W = base.regressor_batch(Q, QD, QDD).reshape(samples * robot.n, -1)
    everything = BaseWithSpring(base, model, tuple(model.names), ())
    S = everything.spring_columns(Q).reshape(samples * robot.n, -1)
    basis, _ = np.linalg.qr(W / np.maximum(np.linalg.norm(W, axis=0), 1e-300))
    kept, grouped = [], []
    for k, name in enumerate(model.names):
        col = S[:, k] / np.linalg.norm(S[:, k])
        residual = col - basis @ (basis.T @ col)
        if np.linalg.norm(residual) < tol:
            grouped.append(name)
            continue
        kept.append(name)
        basis = np.hstack([basis, (residual / np.linalg.norm(residual))[:, None]])
    if not kept:
        raise ValueError(f"spring on joint {model.joint + 1}: every coefficient {model.names} is spanned "
                         f"by the rigid-body model; nothing to identify")
    return BaseWithSpring(base, model, tuple(kept), tuple(grouped))


def spring_torque(result: Any, sb: BaseWithSpring, theta: Any) -> tuple[np.ndarray, np.ndarray]:
    """Identified spring torque at joint angles theta (S,) [rad] and its standard deviation
    [N m] from the covariance of the fit (eq. 14), grouped coefficients counted as 0."""
    theta = np.asarray(theta, dtype=float).reshape(-1)
    names = list(result.names)
    idx = [names.index(name) for name in sb.kept]
    F = sb.model.functions(theta)[:, sb._columns]
    tau = F @ np.asarray(result.values)[idx]
    cov = np.asarray(result.covariance)[np.ix_(idx, idx)]
    return tau, np.sqrt(np.maximum(np.einsum("ik,kl,il->i", F, cov, F), 0.0))


def spring_summary(robot: rx90sym.Robot, sb: BaseWithSpring | None, res: Any, recs: Sequence[Any]) -> tuple[dict, str]:
    """JSON entry and printed lines describing the spring the identification used."""
    if sb is None:
        if robot.spring is None:
            return {"mode": "none"}, "spring: none"
        return {"mode": "given", **robot.spring.describe()}, robot.spring.label()
    values = dict(zip(res.names, res.values))
    stds = dict(zip(res.names, res.std))
    coefficients = {n: {"value": float(values[n]), "std": float(stds[n])} for n in sb.kept}
    j = sb.model.joint
    angles = np.concatenate([r.q[:, j] for r in recs])
    grid = np.linspace(angles.min(), angles.max(), 41)
    tau, sigma = spring_torque(res, sb, grid)
    entry = {"mode": "identified", "joint": j + 1, "model": type(sb.model).__name__,
             "coefficients": coefficients, "grouped": list(sb.grouped),
             "grouped_note": "spanned by the rigid-body model: their part of the spring torque is "
                             "held by the base parameters (e.g. the first harmonic by MX2R/MY2)",
             "torque_on_visited_range": {"angle_rad": grid.tolist(), "torque": tau.tolist(),
                                         "std": sigma.tolist()}}
    lines = [f"spring on joint {j + 1}, identified ({type(sb.model).__name__}; grouped with the "
             f"rigid-body parameters: {', '.join(sb.grouped) or 'none'})"]
    lines += [f"  {n:10s} {c['value']:12.5g} +- {c['std']:.3g}" for n, c in coefficients.items()]
    lines.append(f"  torque on the visited range [{grid[0]:.3g}, {grid[-1]:.3g}] rad: max sigma "
                 f"{sigma.max():.3g} N m (without the grouped terms)")
    return entry, "\n".join(lines)


def __getattr__(name: str) -> Any:
    # The former name, too close to rx90sym.spring.SpringBasis: kept one release.
    if name == "SpringBase":
        import warnings

        warnings.warn("identify.observation.spring_fit.SpringBase is deprecated: use BaseWithSpring",
                      DeprecationWarning, stacklevel=2)
        return BaseWithSpring
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
