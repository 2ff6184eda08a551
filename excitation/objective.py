"""What an excitation trajectory should identify: the criterion on the weighted information matrix.

The information matrix of a trajectory for the base parameters is (eqs. 7-8, 15)

    G = (rate T / N) sum_k Phi_b(t_k)^T S^-2 Phi_b(t_k)  +  G_prior,     S = diag(noise_std),

the WLS normal matrix W^T Sigma^-1 W of the trajectory sampled at ``rate`` (so its inverse is the
predicted covariance of the base parameters), estimated on N grid samples, plus the information of
recordings already made (sequential design, :mod:`excitation.complement`). Criteria to minimise:

- "cond": cond(W) of the raw matrix (f_p surrogate, see criterion.py); noise and prior ignored
  unless given (the historical default).
- "cond-nominal": cond of W R, columns scaled by the reference magnitudes R = diag(ref)
  (``reference``: |nominal| with a group floor, see :func:`reference_magnitudes`): cond of the
  matrix whose columns are the torque contributions of the nominal parameters.
- "cond-columns": cond of W D with D = diag(G)^-1/2 (unit columns: each column's own torque
  contribution weighs alike).
- "logdet": D-optimality, -log det(G) / nb (column scaling only shifts it by a constant).
- "sigma": mean over the selected parameters of log(sigma_i^2 / ref_i^2), sigma_i^2 = (G^-1)_ii:
  the geometric mean of the predicted relative variances (eq. 15), e.g. of the wrist or of the
  payload parameters.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Sequence

import casadi as ca
import numpy as np

from .criterion import gram_expression, log_am_gm, log_cond_surrogate
from .defaults import OBJECTIVES
from .kernels import gram

GROUPS = ("inertial, links 1-3", "inertial, wrist 4-6", "friction FV/FS", "coupling FVM6/FSM6")


def parameter_group(name: str) -> str:
    """Group of a base parameter of a 6-joint arm: links 1-3, wrist, friction, coupling."""
    if name in ("FVM6", "FSM6"):
        return GROUPS[3]
    if name.startswith(("FV", "FS")) or name.startswith("OFF"):
        return GROUPS[2]
    digits = [c for c in name if c.isdigit()]
    link = int(digits[-1]) if digits else 0
    return GROUPS[0] if link <= 3 else GROUPS[1]


def reference_magnitudes(values: Any, names: Sequence[str], floor: float = 0.1,
                         groups: Sequence[str] | None = None) -> np.ndarray:
    """ref_i = max(|value_i|, floor * max over i's group of |value|) (nb,): the denominator of a
    relative sigma that does not blow up on near-zero nominal values (1 for an all-zero group).
    groups: each parameter's group (default :func:`parameter_group` of its name)."""
    values = np.abs(np.asarray(values, dtype=float).reshape(-1))
    if values.size != len(names):
        raise ValueError(f"reference magnitudes: {values.size} values for {len(names)} names")
    groups = np.array([parameter_group(n) for n in names] if groups is None else list(groups))
    out = np.empty_like(values)
    for g in set(groups):
        mask = groups == g
        top = float(np.max(values[mask]))
        out[mask] = np.maximum(values[mask], floor * top) if top > 0.0 else 1.0
    return out


@dataclass(frozen=True, eq=False)
class Objective:
    """A criterion and the data it needs (arrays in base-parameter order).

    name: one of OBJECTIVES. noise_std (n,) [N m]: expected torque noise per joint (None: 1).
    reference (nb,): magnitudes for "cond-nominal" and "sigma" (see :func:`reference_magnitudes`).
    selection: indices of the parameters "sigma" judges (None: all). prior (nb, nb): information
    already gathered (same noise units). rate [Hz]: the sampling rate the information is counted at.
    """

    name: str = "cond"
    noise_std: np.ndarray | None = None
    reference: np.ndarray | None = None
    selection: tuple[int, ...] | None = None
    prior: np.ndarray | None = None
    rate: float = 250.0

    def __post_init__(self) -> None:
        if self.name not in OBJECTIVES:
            raise ValueError(f"criterion must be one of {', '.join(OBJECTIVES)}, got {self.name!r}")
        for field_name in ("noise_std", "reference", "prior"):
            value = getattr(self, field_name)
            if value is not None:
                a = np.array(value, dtype=float)
                if not np.all(np.isfinite(a)):
                    raise ValueError(f"criterion: {field_name} holds non-finite values")
                if field_name != "prior" and np.any(a <= 0.0):
                    raise ValueError(f"criterion: {field_name} must be > 0")
                a.setflags(write=False)
                object.__setattr__(self, field_name, a)
        if self.name in ("cond-nominal", "sigma") and self.reference is None:
            raise ValueError(f"criterion {self.name!r} needs reference magnitudes (nominal parameters)")
        if self.selection is not None:
            object.__setattr__(self, "selection", tuple(int(i) for i in self.selection))
            if not self.selection:
                raise ValueError("criterion: the selection of parameters is empty")

    # ----------------------------------------------------------------- information
    def row_weights(self, n: int) -> np.ndarray:
        """1 / noise_std (n,)."""
        if self.noise_std is None:
            return np.ones(n)
        if self.noise_std.size != n:
            raise ValueError(f"criterion: noise_std has {self.noise_std.size} entries for {n} joints")
        return 1.0 / self.noise_std

    def information(self, mean_info: Any, duration: float) -> Any:
        """G from the grid mean of Phi_k^T S^-2 Phi_k (MX or ndarray), duration [s]."""
        g = mean_info * (self.rate * duration)
        if self.prior is not None:
            g = g + (ca.DM(self.prior) if isinstance(mean_info, (ca.MX, ca.SX, ca.DM)) else self.prior)
        return g

    # ----------------------------------------------------------------- symbolic (IPOPT)
    def expression(self, g: Any, p: int) -> Any:
        """Smooth quantity to minimise for information matrix g (stage p of the cond surrogate)."""
        nb = g.shape[0]
        if self.name == "logdet":
            scale = ca.trace(g) / nb
            return -ca.log(ca.det(g / scale)) / nb - ca.log(scale)
        if self.name == "sigma":
            ref = self.reference
            sel = list(self.selection) if self.selection is not None else list(range(nb))
            scale = ca.trace(g) / nb  # keep the solve well scaled
            cov = ca.solve(g / scale, ca.DM.eye(nb)[:, sel])  # (nb, k): columns of G^-1 * scale
            var = ca.vertcat(*[cov[i, k] for k, i in enumerate(sel)]) / scale
            return ca.sum1(ca.log(var / ca.DM(ref[sel] ** 2))) / len(sel)
        g = self._scaled(g)
        return log_am_gm(g) if p == 0 else log_cond_surrogate(g, p)

    def _scaled(self, g: Any) -> Any:
        if self.name == "cond-nominal":
            r = ca.DM(self.reference)
            return g * ca.mtimes(r, r.T)
        if self.name == "cond-columns":
            d = 1.0 / ca.sqrt(ca.diag(g))
            return g * ca.mtimes(d, d.T)
        return g

    # ----------------------------------------------------------------- numeric (scores)
    def value(self, g: np.ndarray) -> float:
        """The exact criterion for a numeric information matrix: cond of the scaled matrix
        (sqrt of the eigenvalue ratio), -log det / nb, or the mean log relative variance."""
        g = np.asarray(g, dtype=float)
        if self.name.startswith("cond"):
            lam = np.linalg.eigvalsh(np.asarray(self._scaled(ca.DM(g))))
            return float(np.sqrt(lam[-1] / lam[0])) if lam[0] > 0.0 else float("inf")
        if self.name == "logdet":
            sign, logdet = np.linalg.slogdet(g)
            return -logdet / g.shape[0] if sign > 0 else float("inf")
        return float(np.mean(np.log(self.predicted_variance(g) / self.reference ** 2)[self._sel(g)]))

    def _sel(self, g: np.ndarray) -> list[int]:
        return list(self.selection) if self.selection is not None else list(range(g.shape[0]))

    @staticmethod
    def predicted_variance(g: np.ndarray) -> np.ndarray:
        """diag(G^-1) (nb,): predicted variances of the base parameters (inf if singular)."""
        try:
            return np.diag(np.linalg.inv(g)).copy()
        except np.linalg.LinAlgError:
            return np.full(g.shape[0], np.inf)

    def describe(self) -> dict[str, Any]:
        """JSON-ready description."""
        return {"name": self.name, "rate_hz": self.rate,
                "noise_std_nm": None if self.noise_std is None else self.noise_std.tolist(),
                "selection": None if self.selection is None else list(self.selection),
                "prior": self.prior is not None}


def numeric_information(phi: np.ndarray, objective: Objective, duration: float) -> np.ndarray:
    """G (nb, nb) from regressor samples phi (N, n, nb) (see :class:`Objective`)."""
    w = (phi * objective.row_weights(phi.shape[1])[None, :, None]).reshape(-1, phi.shape[2])
    mean_info = gram(w) / phi.shape[0]  # BLAS on one thread: a tenth of einsum's time
    return np.asarray(objective.information(mean_info, duration))


def criterion_function(regressor: ca.Function, samples: Callable[[ca.MX], tuple[ca.MX, ca.MX, ca.MX]],
                       n_free: int, objective: Objective | str = "cond", p: int = 16,
                       duration: float = 1.0) -> ca.Function:
    """casadi.Function x -> criterion (exact derivatives), with samples(x) giving (q, qd, qdd) as
    (n x N) MX over ``duration`` [s]."""
    objective = Objective(objective) if isinstance(objective, str) else objective
    x = ca.MX.sym("x", n_free)
    weights = ca.DM(objective.row_weights(regressor.size1_out(0)))
    sym = regressor.mx_in()
    weighted = ca.Function("weighted", sym, [ca.mtimes(ca.diag(weights), regressor(*sym))])
    g = objective.information(gram_expression(weighted, *samples(x)), duration)
    return ca.Function("criterion", [x], [objective.expression(g, p)])
