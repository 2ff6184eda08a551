"""Ordinary and weighted least squares on the joint-grouped observation matrix (paper §II-B).

The observation system is ``Y = W·χ + ρ`` (eq. 6) with the rows grouped per joint (eqs. 7–8).
The big matrix ``W`` (r × c, r ≈ 63,000 for the RX90) is touched exactly once: every joint block
``[W_i | Y_i]`` is reduced by a Householder QR to a small :class:`CompressedSystem`
``(R_i, z_i, rss_outside_i)`` with ``‖W_i·x − Y_i‖² = ‖R_i·x − z_i‖² + rss_outside_i`` for every x.
Everything downstream (per-joint noise, weighting, the solve of eq. 10, σρ of eq. 12, the
covariance of eq. 13, essential parameters, constrained least squares) works on these
(c + 1) × (c + 1) pieces.

Units: W row i carries the units of the torque of its joint per unit of each parameter, so
Y, residuals and ``residual_rms`` are in N·m (N for a prismatic joint); weights in 1/(N·m).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np


from identify.estimation.compression import (DEFAULT_CHUNK_ROWS, CompressedSystem, check_system, compress, compress_rows,
                                  stack_systems)
from identify.estimation.dependent_columns import NULL_SPACE_SHARE, RANK_RCOND, column_scaled, rank_and_null_share
from identify.estimation.results import IdentificationResult
from rx90sym.messages import plain

__all__ = [
    "fold_wls",
    "RANK_RCOND",
    "NULL_SPACE_SHARE",
    "DEFAULT_CHUNK_ROWS",
    "IdentificationError",
    "CompressedSystem",
    "compress",
    "stack_systems",
    "solve_compressed",
    "relative_std_pct",
    "solve_system",
    "joint_noise_std",
    "weighted_least_squares",
    "solve_joint_systems",
    "joint_weights",
]


class IdentificationError(ValueError):
    """The observation matrix cannot identify the parameters (rank deficient).

    Attributes:
        names: parameters not excited (or excited only in a fixed combination), most
            concerned first.
        rank: numerical rank of W.
    """

    def __init__(self, message: str, names: Sequence[str] = (), rank: int | None = None):
        super().__init__(message)
        self.names = tuple(names)
        self.rank = rank


def _check_rank(system: CompressedSystem, names: Sequence[str], rcond: float) -> None:
    """Raise IdentificationError naming the non-excited parameters if W is rank deficient."""
    rank, share = rank_and_null_share(system.R, rcond)
    c = system.columns
    if rank == c:
        return
    order = np.argsort(-share, kind="stable")
    picked = [j for j in order if share[j] >= NULL_SPACE_SHARE] or [int(order[0])]
    listed = ", ".join(f"{names[j]} ({share[j]:.2f})" for j in picked)
    raise IdentificationError(
        f"observation matrix W is rank deficient: rank {rank} < {c} parameters "
        f"(column-scaled singular values below {rcond:g} x the largest count as zero). "
        f"Parameters not excited, or excited only in a fixed combination (null-space share): "
        f"{listed}. Use a richer excitation or remove/regroup these parameters.",
        names=[names[j] for j in picked],
        rank=rank,
    )


def triangular_cond(R: np.ndarray) -> float:
    """2-norm condition number of a matrix from its triangular factor R (same singular values)."""
    s = np.linalg.svd(R, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


# --------------------------------------------------------------------------- solve and statistics


def solve_compressed(system: CompressedSystem) -> tuple[np.ndarray, np.ndarray, float]:
    """Least-squares solution and its statistics from a full-rank compressed system.

    Returns:
        x: (c,) ``R⁻¹·z`` (eq. 10).
        covariance: (c, c) ``σρ²·(WᵀW)⁻¹ = σρ²·R⁻¹·R⁻ᵀ`` (eq. 13), WᵀW never formed.
        sigma_rho: ``√(‖Y − W·x‖² / (r − c))`` (eq. 12), units of Y.
    """
    import scipy.linalg as sla  # imported when solving, not when a command starts
    r, c = system.rows, system.columns
    if r <= c:
        raise ValueError(f"need more equations than parameters for eq. 12: r = {r}, c = {c}")
    x = sla.solve_triangular(system.R, system.z, check_finite=False)
    r_inv = sla.solve_triangular(system.R, np.eye(c), check_finite=False)
    sigma2 = system.rss(x) / (r - c)  # eq. 12 (rss(x) = rss_outside up to rounding)
    return x, sigma2 * (r_inv @ r_inv.T), float(np.sqrt(sigma2))


def relative_std_pct(values: np.ndarray, std: np.ndarray) -> np.ndarray:
    """100·σ/|x| (eq. 15); inf where the estimate is exactly 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = 100.0 * std / np.abs(values)
    return np.where(values == 0.0, np.inf, rel)


def solve_system(
    system: CompressedSystem,
    names: Sequence[str],
    *,
    joint_systems: Sequence[CompressedSystem] = (),
    weights: np.ndarray | None = None,
    method: str = "ols",
    history: tuple = (),
    rcond: float = RANK_RCOND,
) -> IdentificationResult:
    """Solve an (already weighted) compressed system and gather the statistics of eqs. 10–15.

    Args:
        system: compressed weighted system (the one solved; σρ, cond and covariance refer to it).
        names: (c,) parameter names.
        joint_systems: unweighted per-joint compressed systems, for residual RMS per joint
            (N·m) and cond of the unweighted W; when empty these are NaN.
        weights: per-joint weights used to build ``system`` (1/(N·m)); ones when None.
        method: label stored in the result ("ols", "wls", "essential", ...).
        history: elimination steps (essential parameters).
        rcond: rank tolerance, see :data:`RANK_RCOND`.

    Raises:
        IdentificationError: W rank deficient (message names the non-excited parameters).
    """
    names = tuple(names)
    if len(names) != system.columns:
        raise ValueError(f"{len(names)} names for {system.columns} columns of W")
    _check_rank(system, names, rcond)
    x, cov, sigma_rho = solve_compressed(system)
    std = np.sqrt(np.diag(cov))  # eq. 14
    n = len(joint_systems)
    if n:
        residual_rms = np.array([np.sqrt(s.rss(x) / s.rows) if s.rows else np.nan for s in joint_systems])
        cond_unweighted = triangular_cond(stack_systems(joint_systems).R)
    else:
        residual_rms, cond_unweighted = np.full(0, np.nan), float("nan")
    return IdentificationResult(
        names=names,
        values=x,
        std=std,
        rel_std_pct=relative_std_pct(x, std),
        sigma_rho=sigma_rho,
        cond=triangular_cond(system.R),
        cond_unweighted=cond_unweighted,
        residual_rms=residual_rms,
        weights=np.ones(n) if weights is None else np.asarray(weights, dtype=float),
        rows=system.rows,
        method=method,
        covariance=cov,
        system=system,
        joint_systems=tuple(joint_systems),
        history=tuple(history),
    )


def joint_noise_std(joint_system: CompressedSystem, joint: int = 0, rcond: float = RANK_RCOND) -> float:
    """Standard deviation of the residual of one joint's own least-squares fit (eq. 8 system).

    The paper weights joint i by the inverse of the standard deviation of the residual of the
    system (8) of that joint alone. A joint block rarely excites every parameter (the last joint
    does not see the first link's friction), so the block's own fit uses its numerical rank c_i
    (column-scaled, tolerance ``rcond``) and the minimum-norm solution:
    ``σ_i² = ‖Y_i − W_i·x̂_i‖² / (r_i − c_i)``. This is the unbiased estimate of the noise
    variance of that block whatever its rank, and equals the paper's ``r_i − c`` when the block
    is full rank.

    Args:
        joint_system: unweighted compressed system of the joint's rows.
        joint: joint index, for error messages only.

    Returns:
        σ_i in N·m.
    """
    R, z = joint_system.R, joint_system.z
    u, s, _ = np.linalg.svd(column_scaled(R))
    rank = int(np.sum(s > rcond * s[0])) if s.size and s[0] > 0 else 0
    dof = joint_system.rows - rank
    if dof <= 0:
        raise ValueError(
            f"joint {joint}: {joint_system.rows} equations for a block of rank {rank}; "
            f"need more rows than its rank to estimate the residual standard deviation"
        )
    outside = u[:, rank:].T @ z  # part of z outside the block's column space
    return float(np.sqrt((joint_system.rss_outside + outside @ outside) / dof))


# --------------------------------------------------------------------------- input checks


def _check_joint(joint: np.ndarray, rows: int) -> np.ndarray:
    joint = np.asarray(joint)
    if joint.shape != (rows,):
        raise ValueError(f"joint must have shape ({rows},) to match the rows of W, got {joint.shape}")
    if rows == 0:
        raise ValueError("W has no rows")
    if not np.issubdtype(joint.dtype, np.integer):
        as_int = joint.astype(int)
        bad = np.flatnonzero(as_int != joint)
        if bad.size:
            raise ValueError(f"joint must hold integer joint indices; row {bad[0]} holds {plain(joint[bad[0]])}")
        joint = as_int
    if joint.min() < 0:
        row = int(np.argmin(joint))
        raise ValueError(f"joint indices must be >= 0; row {row} holds {joint[row]}")
    counts = np.bincount(joint)
    empty = np.flatnonzero(counts == 0)
    if empty.size:
        raise ValueError(f"joint {empty[0] + 1} (index {empty[0]}) has no rows (joint indices must cover "
                         f"0..{counts.size - 1})")
    return joint


def _check_names(names: Sequence[str], c: int) -> tuple[str, ...]:
    names = tuple(str(n) for n in names)
    if len(names) != c:
        raise ValueError(f"{len(names)} names for {c} columns of W")
    seen: set[str] = set()
    for j, name in enumerate(names):
        if name in seen:
            raise ValueError(f"duplicate parameter name {name!r} at column {j}")
        seen.add(name)
    return names


# --------------------------------------------------------------------------- entry point


def weighted_least_squares(
    W: np.ndarray,
    Y: np.ndarray,
    joint: np.ndarray,
    names: Sequence[str],
    weighted: bool = True,
    *,
    rcond: float = RANK_RCOND,
    chunk_rows: int = DEFAULT_CHUNK_ROWS,
) -> IdentificationResult:
    """Identify the base parameters by (weighted) least squares (paper §II-B, eqs. 6–15).

    Procedure: compress each joint block once; ordinary LS on the stacked system (rank check,
    eq. 10); for WLS, weight joint i by ``1/σ_i`` with σ_i from the joint's own block fit
    (:func:`joint_noise_std`), then solve the weighted stacked system by QR (eq. 10) and compute
    σρ (eq. 12, on the weighted system), the covariance (eq. 13), σ (eq. 14) and σ % (eq. 15).

    Args:
        W: (r, c) observation matrix of the base parameters, rows of all joints (eqs. 7–8).
        Y: (r,) torques, N·m.
        joint: (r,) joint index 0..n−1 of each row; every joint must have rows.
        names: (c,) parameter names.
        weighted: False gives plain OLS (method "ols", weights 1).
        rcond: rank tolerance, see :data:`RANK_RCOND`.
        chunk_rows: rows per QR chunk, see :func:`compress`.

    Returns:
        IdentificationResult with method "wls" or "ols"; ``system`` is the weighted compressed
        system that was solved, ``joint_systems`` the unweighted per-joint ones.

    Raises:
        IdentificationError: W rank deficient; the message names the non-excited parameters.
        ValueError: inconsistent shapes, non-finite data, bad joint indices or names.
    """
    W, Y = check_system(W, Y)
    names = _check_names(names, W.shape[1])
    joint = _check_joint(joint, W.shape[0])
    if W.shape[0] <= W.shape[1]:
        raise ValueError(f"need more equations than parameters: r = {W.shape[0]}, c = {W.shape[1]}")
    order = np.argsort(joint, kind="stable")
    bounds = np.cumsum(np.bincount(joint))[:-1]
    blocks = [
        compress_rows(W, Y, rows, chunk_rows) for rows in np.split(order, bounds)
    ]
    return solve_joint_systems(blocks, names, weighted, rcond=rcond)


def solve_joint_systems(blocks: Sequence[CompressedSystem], names: Sequence[str], weighted: bool = True, *,
                        rcond: float = RANK_RCOND, weights: np.ndarray | None = None) -> IdentificationResult:
    """:func:`weighted_least_squares` from the joints' compressed systems (eqs. 9-15), wherever they
    come from: the QR of a whole W, or the block-by-block QR of a long log
    (:class:`identify.estimation.incremental_qr.JointFactors`). The per-joint residual of each
    joint's own fit, hence its weight, follows from its system alone (:func:`joint_noise_std`). A joint
    without rows (its torque left out of a fit) weighs nothing: weight 0, residual RMS NaN. ``weights``:
    eq. 11's weights already found (:func:`joint_weights`, e.g. on more columns), used as they are."""
    names = tuple(names)
    live = [i for i, b in enumerate(blocks) if b.rows]
    if not live:
        raise ValueError("no joint has rows")
    if sum(b.rows for b in blocks) <= len(names):
        raise ValueError(f"need more equations than parameters: r = {sum(b.rows for b in blocks)}, c = {len(names)}")
    unweighted = stack_systems(blocks)
    _check_rank(unweighted, names, rcond)
    if not weighted:
        ones = np.array([1.0 if b.rows else 0.0 for b in blocks])
        return solve_system(unweighted, names, joint_systems=blocks, weights=ones, method="ols", rcond=rcond)
    weights = joint_weights(blocks, rcond) if weights is None else np.asarray(weights, dtype=float)
    system = stack_systems(blocks, weights)
    return solve_system(system, names, joint_systems=blocks, weights=weights, method="wls", rcond=rcond)


def joint_weights(blocks: Sequence[CompressedSystem], rcond: float = RANK_RCOND) -> np.ndarray:
    """Eq. 11's weights 1/σ_j [1/(N·m)] of the joints' compressed systems (:func:`joint_noise_std`, each
    joint's own fit whatever the rank of the whole: a search that needs only the weights never stops on
    columns the rows cannot separate); 0 for a joint without rows."""
    sigma = np.array([joint_noise_std(b, i, rcond) if b.rows else np.inf for i, b in enumerate(blocks)])
    if np.any(sigma <= 0.0):
        i = int(np.flatnonzero(sigma <= 0.0)[0])
        raise ValueError(f"joint {i}: its own least-squares residual is zero, so its weight 1/σ is infinite; use weighted=False")
    return 1.0 / sigma


def fold_wls(factors: dict[tuple[int, int], tuple[np.ndarray, int]], held: int, n: int) -> np.ndarray | None:
    """WLS (each joint weighted by 1 / its residual standard deviation, as the fit does) on every
    block but ``held``, from the compressed blocks; None when a joint has too few rows. A joint without
    rows in any block (its torque left out of the fit) is not fitted."""
    systems = []
    fitted = {jj for (_, jj) in factors}
    for j in range(n):
        if j not in fitted:
            continue
        parts = [f for (b, jj), f in factors.items() if jj == j and b != held]
        if not parts:
            return None
        stacked = np.vstack([R for R, _ in parts])  # the same norms as the rows it compresses
        rows = sum(count for _, count in parts)
        c = stacked.shape[1] - 1
        # The joint's own columns only (its rows hold no parameter of the links before it): the same
        # residual, and rank threshold (rows > columns), from a smaller SVD.
        live = np.flatnonzero(np.any(stacked[:, :c] != 0.0, axis=0))
        x, *_ = np.linalg.lstsq(stacked[:, live], stacked[:, c], rcond=None)
        resid = np.linalg.norm(stacked[:, live] @ x - stacked[:, c])
        if rows <= c or resid == 0:
            return None
        systems.append(stacked / (resid / np.sqrt(rows - c)))  # sigma_j as in eq. 12, per joint
    R = np.vstack(systems)
    c = R.shape[1] - 1
    beta, *_ = np.linalg.lstsq(R[:, :c], R[:, c], rcond=None)
    return beta
