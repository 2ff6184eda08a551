"""Incremental QR of the per-joint least-squares systems (TSQR), block after block (eqs. 7-10).

A long log's observation matrix is never held: each block's rows of joint i, ``[W_i | Y_i | Y'...]``
(extra right-hand sides, e.g. the torques shifted by each lag of the delay search), are reduced to
their triangular factor, and the factor of everything so far is updated by the QR of the two
factors stacked, ``R ← qr([R; R_block])`` (tall-skinny QR). ``RᵀR`` is the Gram matrix of all the
rows seen, so every least-squares quantity of the paper (eqs. 9-15) follows from R exactly as from
the whole matrix: :meth:`JointFactors.system` returns the :class:`CompressedSystem` of one
right-hand side, the input of :func:`identify.estimation.least_squares.solve_joint_systems`.
Memory: n factors of p × p doubles (p = parameters + right-hand sides), whatever the log's length.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from identify.estimation.compression import CompressedSystem, _from_augmented_rows, _qr_r, _split_augmented

__all__ = ["JointFactors"]


class JointFactors:
    """Triangular factors of ``[W_i | Y_i | …]`` for every joint i, updated by blocks of rows.

    Args:
        joints: number of joint blocks n.
        columns: parameters c (the first c columns of every row are W's).
        rhs: right-hand sides after them (the first is the fit's Y).
    """

    def __init__(self, joints: int, columns: int, rhs: int = 1) -> None:
        self.columns, self.width = int(columns), int(columns) + int(rhs)
        self.R = [np.zeros((self.width, self.width)) for _ in range(joints)]
        self.rows = np.zeros(joints, dtype=int)

    @staticmethod
    def block_factor(rows: np.ndarray) -> np.ndarray:
        """Triangular factor (p, p) of one block's rows (m, p) (zeros when m = 0)."""
        return _qr_r(np.array(rows, dtype=float, order="F", copy=True))

    def add_factor(self, joint: int, factor: np.ndarray, count: int) -> None:
        """Fold in a block's factor (from :meth:`block_factor`, here or on another machine) of ``count`` rows."""
        if count == 0:
            return
        self.R[joint] = _qr_r(np.vstack([self.R[joint], factor]))  # TSQR: qr([R; R_block])
        self.rows[joint] += int(count)

    def add(self, joint: int, rows: np.ndarray) -> None:
        """Fold in rows (m, p) of joint ``joint``."""
        self.add_factor(joint, self.block_factor(rows), rows.shape[0])

    def subset(self, columns: Sequence[int]) -> "JointFactors":
        """The factors of the parameters ``columns`` only (their order kept; every right-hand side kept)."""
        out = JointFactors(len(self.R), len(columns), self.width - self.columns)
        keep = list(columns) + list(range(self.columns, self.width))
        out.R = [_qr_r(np.array(R[:, keep], order="F")) for R in self.R]  # RᵀR of the kept columns
        out.rows = self.rows.copy()
        return out

    def system(self, joint: int, rhs: int = 0) -> CompressedSystem:
        """The compressed system ``‖W_i·x − Y‖²`` of joint ``joint`` for right-hand side ``rhs``."""
        c = self.columns
        R = self.R[joint]
        if rhs == 0:  # the leading block of a triangular factor is the factor of the leading columns
            return _split_augmented(R[:c + 1, :c + 1], c, int(self.rows[joint]))
        keep = list(range(c)) + [c + rhs]
        return _from_augmented_rows(R[:, keep], int(self.rows[joint]))

    def systems(self, rhs: int = 0) -> list[CompressedSystem]:
        """:meth:`system` of every joint."""
        return [self.system(j, rhs) for j in range(len(self.R))]


def stacked_rows(Phi: np.ndarray, Ys: Sequence[np.ndarray], joint: int, mask: np.ndarray | None = None) -> np.ndarray:
    """Rows ``[W_i | Y_i | …]`` of joint ``joint`` from a block's regressor (S, n, c) and torques (S, n) each."""
    cols = [Phi[:, joint, :]] + [Y[:, joint, None] for Y in Ys]
    rows = np.concatenate(cols, axis=1)
    return rows if mask is None else rows[mask]
