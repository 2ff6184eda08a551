"""QR compression of a least-squares system (the big W touched once, paper eqs. 9-10).

Every joint block ``[W_i | Y_i]`` is reduced by a Householder QR to a small
:class:`CompressedSystem` ``(R, z, rss_outside)`` with ``‖W·x − Y‖² = ‖R·x − z‖² + rss_outside``
for every x. Weighted LS, essential parameters, the consistent fit and the payload methods all
work on these (c + 1) × (c + 1) pieces.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from rx90sym.recording import frozen_array

__all__ = ["DEFAULT_CHUNK_ROWS", "CompressedSystem", "block_factors", "check_system", "compress", "compress_rows",
           "stack_systems"]

#: Rows per QR chunk in :func:`compress`: bounds the working copy to about 15 MB for c = 54.
DEFAULT_CHUNK_ROWS = 32_768



@dataclass(frozen=True)
class CompressedSystem:
    """QR-compressed least-squares system ``min ‖W·x − y‖²`` (eqs. 9–10).

    Attributes:
        R: (c, c) upper triangular factor of W (units of W).
        z: (c,) ``Qᵀ·y`` (units of y).
        rss_outside: ``‖y‖² − ‖z‖²`` ≥ 0, the part of ‖y‖² no x can fit (units of y²);
            obtained as the squared last pivot of the QR of ``[W | y]`` (no cancellation).
        rows: number of equations r of the original system.

    For every x: ``‖W·x − y‖² = ‖R·x − z‖² + rss_outside``.
    """

    R: np.ndarray
    z: np.ndarray
    rss_outside: float
    rows: int

    def __post_init__(self) -> None:
        R = frozen_array(self.R)
        z = frozen_array(self.z)
        if R.ndim != 2 or R.shape[0] != R.shape[1]:
            raise ValueError(f"CompressedSystem.R must be square, got shape {R.shape}")
        if z.shape != (R.shape[0],):
            raise ValueError(f"CompressedSystem.z must have shape ({R.shape[0]},), got {z.shape}")
        if not (np.isfinite(self.rss_outside) and self.rss_outside >= 0.0):
            raise ValueError(f"CompressedSystem.rss_outside must be finite and >= 0, got {self.rss_outside}")
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "z", z)
        object.__setattr__(self, "rss_outside", float(self.rss_outside))
        object.__setattr__(self, "rows", int(self.rows))

    @property
    def columns(self) -> int:
        """Number of parameters c."""
        return self.R.shape[1]

    def rss(self, x: np.ndarray) -> float:
        """Residual sum of squares ``‖W·x − y‖²`` of the original system (units of y²)."""
        d = self.R @ np.asarray(x, dtype=float) - self.z
        return float(d @ d) + self.rss_outside

    def augmented(self) -> np.ndarray:
        """(c+1, c+1) matrix ``[[R, z], [0, √rss_outside]]``, the compressed ``[W | y]``."""
        c = self.columns
        a = np.zeros((c + 1, c + 1))
        a[:c, :c] = self.R
        a[:c, c] = self.z
        a[c, c] = np.sqrt(self.rss_outside)
        return a

    def scaled(self, weight: float) -> "CompressedSystem":
        """The system of ``weight·W, weight·y`` (a row weight, eq. 8 weighting)."""
        w = float(weight)
        return CompressedSystem(w * self.R, w * self.z, w * w * self.rss_outside, self.rows)

    def select(self, columns: Sequence[int]) -> "CompressedSystem":
        """The system restricted to some columns: ``‖W[:, k]·x − y‖²`` without the raw data.

        Uses ``‖W[:, k]·x − y‖² = ‖R[:, k]·x − z‖² + rss_outside`` and one small QR.
        """
        k = np.asarray(columns, dtype=int)
        if k.ndim != 1 or np.any((k < 0) | (k >= self.columns)) or np.unique(k).size != k.size:
            raise ValueError(f"select: columns must be distinct indices in 0..{self.columns - 1}, got {k.tolist()}")
        a = self.augmented()
        return _from_augmented_rows(np.column_stack([a[:, k], a[:, -1]]), self.rows)


def _from_augmented_rows(a: np.ndarray, rows: int) -> CompressedSystem:
    """QR of a stacked augmented matrix ``[A | b]`` (m, c+1) into a CompressedSystem."""
    c = a.shape[1] - 1
    r_aug = _qr_r(a)
    return _split_augmented(r_aug, c, rows)


def _qr_r(a: np.ndarray) -> np.ndarray:
    """Upper triangular factor of an (m, p) matrix, padded with zero rows to (p, p).

    Calls LAPACK dgeqrf directly (blocked, optimal workspace) and may overwrite ``a``:
    scipy.linalg.qr(mode="r") would also copy the whole m × p factor through triu.
    """
    import scipy.linalg as sla  # imported when solving, not when a command starts
    m, p = a.shape
    if m == 0:
        return np.zeros((p, p))
    a = np.asfortranarray(a, dtype=float)
    lwork = max(int(sla.lapack.dgeqrf_lwork(m, p)[0]), p, 1)
    qr, _, _, info = sla.lapack.dgeqrf(a, lwork=lwork, overwrite_a=1)
    if info != 0:
        raise RuntimeError(f"LAPACK dgeqrf failed (info = {info})")
    r = np.triu(qr[: min(m, p)])
    if r.shape[0] < p:
        r = np.vstack([r, np.zeros((p - r.shape[0], p))])
    return r


def _split_augmented(r_aug: np.ndarray, c: int, rows: int) -> CompressedSystem:
    # r_aug = [[R, z], [0, ρ]] with |ρ| = residual norm, so rss_outside = ρ² (computed without
    # the cancellation of ‖y‖² − ‖z‖²).
    return CompressedSystem(
        R=np.triu(r_aug[:c, :c]),
        z=r_aug[:c, c],
        rss_outside=float(r_aug[c, c] ** 2),
        rows=rows,
    )


def compress_rows(W: np.ndarray, Y: np.ndarray, rows: np.ndarray, chunk_rows: int) -> CompressedSystem:
    """Compress the equations ``rows`` (sorted int indices) of ``[W | Y]`` in row chunks."""
    c = W.shape[1]
    contiguous = rows.size > 0 and rows[-1] - rows[0] + 1 == rows.size
    factors = []
    for start in range(0, rows.size, chunk_rows):
        stop = min(start + chunk_rows, rows.size)
        sel = slice(rows[start], rows[stop - 1] + 1) if contiguous else rows[start:stop]
        aug = np.empty((stop - start, c + 1), order="F")
        aug[:, :c] = W[sel]
        aug[:, c] = Y[sel]
        factors.append(_qr_r(aug))
    if not factors:
        return _split_augmented(np.zeros((c + 1, c + 1)), c, 0)
    r_aug = factors[0] if len(factors) == 1 else _qr_r(np.vstack(factors))  # QR of the stacked R's
    return _split_augmented(r_aug, c, int(rows.size))


def check_system(W: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    W = np.asarray(W, dtype=float)
    Y = np.asarray(Y, dtype=float)
    if W.ndim != 2:
        raise ValueError(f"W must be a 2-D (r, c) array, got shape {W.shape}")
    if Y.shape != (W.shape[0],):
        raise ValueError(f"Y must have shape ({W.shape[0]},) to match the rows of W, got {Y.shape}")
    bad = ~np.isfinite(W)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise ValueError(f"W has {int(bad.sum())} non-finite entries; first at row {row}, column {col}")
    bad_y = np.flatnonzero(~np.isfinite(Y))
    if bad_y.size:
        raise ValueError(f"Y has {bad_y.size} non-finite entries; first at row {bad_y[0]}")
    return W, Y


def compress(W: np.ndarray, Y: np.ndarray, chunk_rows: int = DEFAULT_CHUNK_ROWS) -> CompressedSystem:
    """Reduce ``min ‖W·x − Y‖²`` to ``(R, z = Qᵀ·Y, rss_outside)`` by an economy QR (eq. 10).

    Args:
        W: (r, c) observation matrix (eq. 6).
        Y: (r,) measured torques, N·m.
        chunk_rows: rows per QR; taller matrices are processed chunk by chunk and the R factors
            of the chunks stacked and factorised again, so memory stays O(chunk_rows·c).

    Returns:
        A :class:`CompressedSystem` with ``‖W·x − Y‖² = ‖R·x − z‖² + rss_outside`` for all x.
    """
    W, Y = check_system(W, Y)
    if chunk_rows < 1:
        raise ValueError(f"chunk_rows must be >= 1, got {chunk_rows}")
    return compress_rows(W, Y, np.arange(W.shape[0]), chunk_rows)


def stack_systems(systems: Sequence[CompressedSystem], weights: Sequence[float] | None = None) -> CompressedSystem:
    """Compressed system of the row-stacked (optionally row-weighted) original systems (eq. 7).

    ``‖diag(w)·(W·x − Y)‖² = Σ_i w_i²·(‖R_i·x − z_i‖² + rss_outside_i)``.
    """
    if not systems:
        raise ValueError("stack_systems needs at least one system")
    c = systems[0].columns
    if any(s.columns != c for s in systems):
        raise ValueError(f"stack_systems: systems have different column counts {[s.columns for s in systems]}")
    w = np.ones(len(systems)) if weights is None else np.asarray(weights, dtype=float)
    if w.shape != (len(systems),):
        raise ValueError(f"stack_systems: {len(systems)} systems but weights of shape {w.shape}")
    stacked = np.vstack([wi * s.augmented() for wi, s in zip(w, systems)])
    return _from_augmented_rows(stacked, sum(s.rows for s in systems))


# --------------------------------------------------------------------------- rank and null space


def block_factors(W: np.ndarray, Y: np.ndarray, joint: np.ndarray, ids: np.ndarray, blocks: Sequence[int],
                  n: int) -> dict[tuple[int, int], tuple[np.ndarray, int]]:
    """(block, joint) -> (the triangular factor of [W | Y] over the rows of that block (``ids``) and
    joint, their number), for the ``blocks`` listed: what :func:`identify.estimation.least_squares.fold_wls` solves from."""
    # The rows grouped by (block, joint) with one stable sort (each group keeps its order), not a mask per group.
    key = np.asarray(ids) * n + joint
    order = np.argsort(key, kind="stable")
    edges = np.searchsorted(key[order], [[b * n + j, b * n + j + 1] for b in blocks for j in range(n)])
    out = {}
    for bj, (lo, hi) in zip([(b, j) for b in blocks for j in range(n)], edges):
        if hi > lo:
            rows = order[lo:hi]
            out[bj] = (np.linalg.qr(np.column_stack([W[rows], Y[rows]]), mode="r"), int(hi - lo))
    return out
