"""Excitation criteria on the base-parameter observation matrix W (eqs. 6-8).

W stacks the base regressor Phi_b(q, qd, qdd) (n x nb) over the samples of a trajectory; the
criterion is its condition number cond(W) = sqrt(lambda_max / lambda_min) of G = W^T W.

Why a surrogate: cond is not differentiable where the extreme eigenvalues of G are multiple, and
at a minimiser of cond they typically are (the optimum pushes several eigenvalues together), so a
smooth NLP solver such as IPOPT stalls or zig-zags on it. We minimise instead

    f_p(G) = (1/p) log tr(Gh^p) + (1/p) log tr(Gh^-p),   Gh = G nb / tr(G)   (scale-free)

the log of ||lambda||_p ||1/lambda||_p. It is analytic wherever G > 0, its exact derivatives come
from CasADi (matrix products, one linear solve), and it brackets the true criterion:

    2 log cond(W) <= f_p(G) <= 2 log cond(W) + (2/p) log nb,

so the equivalent condition number exp(f_p/2) overestimates cond(W) by at most nb^(1/p) (a factor
1.28 for p = 16 and 54 base parameters). Minimising it also lifts the whole lower spectrum, not only
the smallest eigenvalue, which makes the result less sensitive to the sampling.

The optimiser runs a continuation in p (default 4 then 16): small p is smoother and moves a random
start quickly, large p is tighter. The log-determinant (D-optimality) in its scale-free form
f_0(G) = log(tr(G)/nb) - log det(G)/nb = log(arithmetic / geometric mean of the eigenvalues),
the p -> 0 end of the same family, is available as a first stage (p = 0); on the RX90 it did not
improve the final cond and cost 60 % more time, so it is not in the default schedule. The other
criteria (scaled cond, D-optimality, predicted relative sigma) are in objective.py.

Friction: Coulomb columns hold sign(qd); their derivative is zero and their jumps make the criterion
piecewise, so during optimisation each FS column is replaced by tanh(v / eps) where v is the matching
FV column (the same velocity: qd_j for FSj, the coupled speeds for FSM6). The reported cond always
uses the true sign on the fine grid.
"""
from __future__ import annotations

import warnings
from typing import Any, Sequence

import casadi as ca
import numpy as np

from .kernels import evaluate_samples, symbols_like

# --------------------------------------------------------------------------- numeric (reporting)
def stacked_regressor(base_regressor: Any, q: Any, qd: Any, qdd: Any) -> np.ndarray:
    """W (n N, nb): Phi_b rows stacked per joint (eqs. 7-8) at exact samples (N, n) in rad, rad/s,
    rad/s^2 (a planned motion; identify.observation_matrix builds W from recordings).

    ``base_regressor`` is a casadi.Function (q, qd, qdd) -> Phi_b (n x nb), evaluated with a serial
    map, or a batch callable (Q, QD, QDD) -> ndarray (N, n, nb) such as ``bp.regressor_batch``.
    """
    q, qd, qdd = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (q, qd, qdd))
    if not (q.shape == qd.shape == qdd.shape):
        raise ValueError(f"observation matrix: q, qd, qdd shapes differ: {q.shape}, {qd.shape}, {qdd.shape}")
    phi = regressor_samples(base_regressor, q, qd, qdd)  # (N, n, nb)
    return np.concatenate([phi[:, j, :] for j in range(phi.shape[1])], axis=0)



def observation_matrix(base_regressor: Any, q: Any, qd: Any, qdd: Any) -> np.ndarray:
    """Deprecated name of :func:`stacked_regressor` (identify.observation_matrix is the one from
    recordings)."""
    import warnings

    warnings.warn("excitation.observation_matrix is deprecated: use excitation.stacked_regressor",
                  DeprecationWarning, stacklevel=2)
    return stacked_regressor(base_regressor, q, qd, qdd)


def regressor_samples(base_regressor: Any, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """Phi_b at every sample: (N, n, nb)."""
    if isinstance(base_regressor, ca.Function):
        return evaluate_samples(base_regressor, q, qd, qdd)
    return np.asarray(base_regressor(q, qd, qdd), dtype=float)


def condition_number(base_regressor: Any, t: Any, q: Any, qd: Any, qdd: Any) -> float:
    """cond(W) of the unscaled, unweighted base observation matrix on the given samples.

    t (N,) [s] must increase strictly (it only guards against passing a wrong array); q, qd, qdd
    (N, n) in Khalil angles [rad, rad/s, rad/s^2]. Returns inf when W is rank deficient.
    """
    t = np.asarray(t, dtype=float)
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if t.ndim != 1 or t.size != q.shape[0]:
        raise ValueError(f"condition number: t has {t.size} samples but q has {q.shape[0]}")
    if np.any(np.diff(t) <= 0.0):
        raise ValueError("condition number: t must increase strictly")
    sv = np.linalg.svd(stacked_regressor(base_regressor, q, qd, qdd), compute_uv=False)
    return float(sv[0] / sv[-1]) if sv[-1] > 0.0 else float("inf")


# --------------------------------------------------------------------------- smooth friction columns
def friction_pairs(names: Sequence[str]) -> list[tuple[int, int]]:
    """(FS column, FV column) pairs by name: FSj with FVj, FSM6 with FVM6, ..."""
    index = {name: i for i, name in enumerate(names)}
    return [(i, index["FV" + name[2:]]) for i, name in enumerate(names)
            if name.startswith("FS") and "FV" + name[2:] in index]


def smooth_friction_regressor(regressor: ca.Function, names: Sequence[str] | None,
                              eps: float, seed: int = 0) -> ca.Function:
    """Regressor with each Coulomb column sign(v) replaced by tanh(v / eps), eps [rad/s].

    The pairing (FS column = sign of FV column) is checked on a few random states; a pair that
    does not follow it is left exact, with a warning.
    """
    if eps <= 0.0:
        raise ValueError(f"smooth friction: eps must be > 0 rad/s, got {eps}")
    pairs = friction_pairs(names) if names is not None else []
    if not pairs:
        return regressor
    rng = np.random.default_rng(seed)
    n = regressor.size1_in(0)
    checks = [np.asarray(regressor(rng.uniform(-2, 2, n), rng.uniform(-2, 2, n), rng.uniform(-2, 2, n)))
              for _ in range(3)]
    good = []
    for fs, fv in pairs:
        if all(np.allclose(phi[:, fs], np.sign(phi[:, fv])) for phi in checks):
            good.append((fs, fv))
        else:
            # e.g. the coupling's "motor" form: FSM6 = sign(qd5 + qd6), FVM6 = qd6 / qd5 per row
            warnings.warn(f"smooth friction: column {names[fs]} is not sign({names[fv]}) (a coupling's 'motor' "
                          f"Coulomb form?): that column stays exact (not smoothed) in the criterion; the "
                          f"limits are not affected")
    sym = symbols_like(regressor)
    phi = regressor(*sym)
    for fs, fv in good:
        phi[:, fs] = ca.tanh(phi[:, fv] / eps)
    return ca.Function(f"{regressor.name()}_smooth", list(sym), [phi], ["q", "qd", "qdd"], ["Phi"])


# --------------------------------------------------------------------------- symbolic criteria
def gram_expression(regressor: ca.Function, q: ca.MX, qd: ca.MX, qdd: ca.MX) -> ca.MX:
    """G = W^T W / N (nb x nb) for MX samples (n x N): per-sample information matrix."""
    sym = symbols_like(regressor)
    phi_t = ca.Function("phi_t", list(sym), [regressor(*sym).T])
    n_samples = q.shape[1]
    wt = phi_t.map(n_samples, "serial")(q, qd, qdd)  # (nb, n N) = W^T
    return ca.mtimes(wt, wt.T) / n_samples


def log_cond_surrogate(g: Any, p: int) -> Any:
    """f_p(G) >= 2 log cond(W) for G (nb x nb, MX or DM); p a power of two (1, 2, 4, ...)."""
    if p < 1 or (p & (p - 1)) != 0:
        raise ValueError(f"cond surrogate: p must be a power of two >= 1, got {p}")
    nb = g.shape[0]
    g_hat = g * (nb / ca.trace(g))
    a = g_hat
    a_inv = ca.solve(g_hat, ca.DM.eye(nb))
    for _ in range(int(np.log2(p))):  # repeated squaring: G^p in log2(p) products
        a = ca.mtimes(a, a)
        a_inv = ca.mtimes(a_inv, a_inv)
    return (ca.log(ca.trace(a)) + ca.log(ca.trace(a_inv))) / p


def log_am_gm(g: Any) -> Any:
    """f_0(G) = log(tr(G)/nb) - log det(G)/nb >= 0: scale-free log-determinant (warm start)."""
    nb = g.shape[0]
    g_hat = g * (nb / ca.trace(g))  # normalise first so det cannot overflow
    return -ca.log(ca.det(g_hat)) / nb
