"""The drive gains' instrumental-variable fit (IDIM-IV) on sums folded block by block.

Each motion is in the form ``G(I) k − X θ = Kn`` per sample (joint on axis 1): I the filtered
currents, X the other unknowns' columns, Kn the known-mass column times Mc minus the spring torque.
Joint j's row is a = [Rt[j, free]·I_free, −X_j], y = Kn_j − Σ_m Rt[j, m] I_m k_fixed,m. The
instruments replace the currents by those the model predicts, P = (Rt diag(k))⁻¹ (X θ + Kn): every
row of Z is then linear in v = [X, Kn] of its sample, z = L_j(k, θ) v. So the sums

    F_j = Σ v vᵀ,   H_j = Σ v [a, y]ᵀ      (over joint j's kept rows)

and the triangular factor of [a | y] per joint (:class:`identify.estimation.incremental_qr.JointFactors`)
give ZᵀA, Zᵀy and ZᵀZ for any (k, θ): the iterations run on them without another pass over the
data, and a long log's rows are never held. Memory: n (n(c_X + 1))² doubles for F (the global method
on a 6-joint arm: 8 MB). The segment bootstrap, whose instruments are the final ones, takes one more
pass (:meth:`GainSums.bootstrap_rows`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from identify.estimation.incremental_qr import JointFactors
from identify.estimation.least_squares import solve_joint_systems, stack_systems, triangular_cond
from identify.estimation.results import IdentificationResult

__all__ = ["GainRows", "GainSums", "IV_ITERATIONS", "IV_TOLERANCE", "iv_fit"]

# Instrumental-variable iterations: at most this many, until no unknown moves by more than
# IV_TOLERANCE of its sigma (the twin's weak motor 6 needs ~8; the others 2).
IV_ITERATIONS = 30
IV_TOLERANCE = 1e-3


@dataclass(frozen=True, eq=False)
class GainRows:
    """One block of a motion in the form G(I) k − X θ = Kn: I (S, n) filtered currents (same-motion:
    loaded minus empty), X (S, n, c_X), Kn (S, n), keep (S, n) the rows fitted, first: the index of its
    first sample among every motion's (the bootstrap's blocks)."""

    I: np.ndarray
    X: np.ndarray
    Kn: np.ndarray
    keep: np.ndarray
    first: int


class GainSums:
    """The sums of the module docstring, folded block by block.

    Rt: (n, n) motor-to-joint torque map; free: the motors whose gain is identified; k_fixed: (n,) the
    fixed gains (0 where free); columns: c_X.
    """

    def __init__(self, Rt: np.ndarray, free: Sequence[int], k_fixed: np.ndarray, columns: int) -> None:
        self.Rt, self.free, self.k_fixed = np.asarray(Rt, dtype=float), list(free), np.asarray(k_fixed, dtype=float)
        n = self.Rt.shape[0]
        self.cx = int(columns)
        self.ca = len(self.free) + self.cx
        width = n * (self.cx + 1)
        self.factors = JointFactors(n, self.ca)
        self.F = np.zeros((n, width, width))
        self.H = np.zeros((n, width, self.ca + 1))

    def rows(self, b: GainRows, j: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(kept sample indices, A_j, y_j) of joint j in block ``b``."""
        idx = np.flatnonzero(b.keep[:, j])
        I, Rt = b.I[idx], self.Rt[j]
        A = np.concatenate([I[:, self.free] * Rt[self.free], -b.X[idx, j, :]], axis=1)
        return idx, A, b.Kn[idx, j] - I @ (Rt * self.k_fixed)

    def add(self, b: GainRows) -> None:
        V = np.concatenate([b.X, b.Kn[:, :, None]], axis=2).reshape(b.I.shape[0], -1)
        done: dict[bytes, np.ndarray] = {}  # joints of one mask share F's sum
        for j in range(self.Rt.shape[0]):
            idx, A, y = self.rows(b, j)
            if idx.size == 0:
                continue
            Ay = np.column_stack([A, y])
            self.factors.add(j, Ay)
            key = b.keep[:, j].tobytes()
            if key not in done:
                done[key] = V[idx].T @ V[idx]
            self.F[j] += done[key]
            self.H[j] += V[idx].T @ Ay

    def instruments(self, k: np.ndarray, theta: np.ndarray, j: int) -> np.ndarray:
        """L_j (c_A, n (c_X + 1)): z = L_j v for gains ``k`` (all motors) and the other unknowns ``theta``."""
        n = self.Rt.shape[0]
        Ginv = np.linalg.inv(self.Rt @ np.diag(k))
        L = np.zeros((self.ca, n * (self.cx + 1)))
        L[:len(self.free)] = np.kron(self.Rt[j, self.free][:, None] * Ginv[self.free, :], np.r_[theta, 1.0][None, :])
        at = j * (self.cx + 1)
        L[len(self.free):, at:at + self.cx] = -np.eye(self.cx)
        return L

    def bootstrap_rows(self, b: GainRows, instruments: tuple[np.ndarray, np.ndarray] | None, j: int
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(kept sample indices, A_j, y_j, Z_j) of joint j in block ``b`` with the instruments of
        ``instruments`` = (k, θ) (None: Z = A, plain least squares)."""
        idx, A, y = self.rows(b, j)
        if instruments is None:
            return idx, A, y, A
        V = np.concatenate([b.X[idx], b.Kn[idx, :, None]], axis=2).reshape(idx.size, -1)
        return idx, A, y, V @ self.instruments(*instruments, j).T


def _joint_sigma(rss: np.ndarray, rows: np.ndarray, c: int) -> np.ndarray:
    """σ_j of each joint's residual, the degrees of freedom shared over all rows."""
    sigma = np.sqrt(rss / rows / (1.0 - c / rows.sum()))
    if np.any(sigma <= 0):
        raise ValueError(f"joint {int(np.argmin(sigma)) + 1}: the gain fit leaves no residual; cannot weight it")
    return sigma


def iv_fit(sums: GainSums, names: Sequence[str], method: str, iterations: int = IV_ITERATIONS
           ) -> tuple[IdentificationResult, tuple[np.ndarray, np.ndarray] | None]:
    """WLS, then instrumental variables with the model's predicted currents (IDIM-IV).

    The currents are regressors here, so their noise biases plain LS toward zero gains (errors in
    variables: 5-8 % on the twin's realistic runs); the currents predicted by the current estimate,
    i = (Rt diag(k))⁻¹ (X θ + Kn), are free of that noise and serve as instruments. Iterated until no
    unknown moves by more than IV_TOLERANCE of its σ (at most ``iterations`` times). Each joint's rows
    are weighted by 1/σ of its residual (the usual per-joint block fit, eqs. 12-13, fails: a joint whose
    rows carry no known-mass term has a homogeneous block). Returns the fit and the instruments of its
    covariance, (k, θ) (None: the least-squares fit's own columns).
    """
    systems = sums.factors.systems(0)
    ols = solve_joint_systems(systems, names, weighted=False)  # the rank check names the unknowns
    rows = np.array([s.rows for s in systems], dtype=float)
    total, c, n_f = int(rows.sum()), len(names), len(sums.free)
    AtA = [s.R.T @ s.R for s in systems]
    rss = lambda x: np.array([s.rss(x) for s in systems])  # noqa: E731
    x = ols.values
    sigma = _joint_sigma(rss(x), rows, c)
    instruments, ZtA, ZtZ = None, None, None
    w2 = 1.0 / sigma**2
    ZtA = ZtZ = sum(w * G for w, G in zip(w2, AtA))

    for _ in range(iterations):
        k = sums.k_fixed.copy()
        k[sums.free] = x[:n_f]
        if np.any(k == 0):
            raise ValueError("drive gains: a gain came out as 0; the runs do not excite it")
        L = [sums.instruments(k, x[n_f:], j) for j in range(len(systems))]
        x_new = np.linalg.solve(sum(w * Lj @ Hj[:, :c] for w, Lj, Hj in zip(w2, L, sums.H)),
                                sum(w * Lj @ Hj[:, c] for w, Lj, Hj in zip(w2, L, sums.H)))
        sigma = _joint_sigma(rss(x_new), rows, c)
        w2 = 1.0 / sigma**2
        ZtA = sum(w * Lj @ Hj[:, :c] for w, Lj, Hj in zip(w2, L, sums.H))
        ZtZ = sum(w * Lj @ Fj @ Lj.T for w, Lj, Fj in zip(w2, L, sums.F))
        cov = _covariance(ZtA, ZtZ, float(w2 @ rss(x_new)), total, c)
        step = np.max(np.abs(x_new - x) / np.sqrt(np.diag(cov)))
        x, instruments = x_new, (k, x[n_f:])
        if step < IV_TOLERANCE:
            break
    cov = _covariance(ZtA, ZtZ, float(w2 @ rss(x)), total, c)
    std = np.sqrt(np.diag(cov))                                                   # eq. 14
    sigma_rho = float(np.sqrt(w2 @ rss(x) / (total - c)))                          # eq. 12
    cond = triangular_cond(stack_systems(systems, 1.0 / sigma).R)
    return IdentificationResult(tuple(names), x, std, 100 * std / np.abs(x), sigma_rho, cond, ols.cond_unweighted,
                                np.sqrt(rss(x) / rows), 1.0 / sigma, total, f"drive-gains-{method}-iv", cov), instruments


def _covariance(ZtA: np.ndarray, ZtZ: np.ndarray, weighted_rss: float, total: int, c: int) -> np.ndarray:
    """Eq. 13 in the IV form, σρ² (ZᵀA)⁻¹ ZᵀZ (AᵀZ)⁻¹ on the weighted rows."""
    ZAinv = np.linalg.inv(ZtA)
    return weighted_rss / (total - c) * ZAinv @ ZtZ @ ZAinv.T
