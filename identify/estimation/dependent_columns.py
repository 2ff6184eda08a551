"""Columns of W the fitted rows cannot separate: the rank of W, and what a fit does with such columns.

The rank is judged on the column-scaled W (every column scaled to unit norm, so that the parameters'
units do not matter) with the tolerance :data:`RANK_RCOND`. A column's share of the null space (the
norm of its row in an orthonormal basis of it) names the columns concerned: 1 for a column that is
zero, 0.71 for one of two proportional columns.

:func:`weighted_least_squares` on a W given refuses a rank-deficient one
(:class:`~identify.estimation.least_squares.IdentificationError`). A fit of recordings never stops on
its own rows (:func:`reduce_columns`):

- a column that is 0 on every fitted row (the Coulomb term of a joint that never moves; the columns
  of a joint whose torque is left out of the fit that no other joint's rows see) is **left out**:
  nothing estimates it, a prediction counts it as 0;
- columns in a fixed combination (a joint that moves one way only: its Coulomb column sign(q̇) is +1
  or -1 on every row, its offset's column 1) are **merged**: the later ones in the order of the names
  are left out and each column kept holds its own parameter plus the combination of those it absorbs
  (``FS5`` holds ``FS5 + OFF5``; ``FS5 - OFF5`` when the joint moves the negative way).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

__all__ = ["RANK_RCOND", "NULL_SPACE_SHARE", "ColumnReduction", "Merged", "column_scaled", "rank_and_null_share",
           "reduce_columns"]

#: Rank tolerance: a singular value of the column-scaled W (every column scaled to unit norm,
#: so that the units of the parameters do not matter) below RANK_RCOND × the largest one counts
#: as zero. 1e-10 is far above rounding (≈ 1e-16·√r) and far below any usable identification
#: (a scaled condition number of 1e10 already makes eq. 13 meaningless in double precision).
RANK_RCOND = 1e-10

#: A parameter is named in a rank-deficiency error when the norm of its row in an orthonormal
#: basis of the null space of the column-scaled W is at least this share (1 = its column is zero,
#: 0.71 = one of two proportional columns). The row norm does not depend on the basis chosen.
NULL_SPACE_SHARE = 0.1

#: A coefficient of a merged column below this share of the column kept (both scaled to unit norm) is
#: rounding, not part of what the column kept holds.
NEGLIGIBLE = 1e-8


def column_scaled(R: np.ndarray) -> np.ndarray:
    """R with every column scaled to unit norm (columns at rounding level set to zero)."""
    norms = np.linalg.norm(R, axis=0)
    top = norms.max() if norms.size else 0.0
    zero = norms <= top * np.finfo(float).eps
    return np.where(zero, 0.0, R / np.where(zero, 1.0, norms))


def rank_and_null_share(R: np.ndarray, rcond: float = RANK_RCOND) -> tuple[int, np.ndarray]:
    """Numerical rank of the column-scaled R and each column's share of the null space (0..1)."""
    _, s, vt = np.linalg.svd(column_scaled(R))
    rank = int(np.sum(s > rcond * s[0])) if s.size and s[0] > 0 else 0
    share = np.linalg.norm(vt[rank:].T, axis=1)
    return rank, share


@dataclass(frozen=True)
class Merged:
    """A column kept that holds others: its estimate is ``name`` + sum of coefficient x each absorbed
    column's parameter (``absorbed``: (name, coefficient), coefficients in the parameters' own units)."""

    name: str
    absorbed: tuple[tuple[str, float], ...]

    def holds(self) -> str:
        """What the column's estimate holds, e.g. ``FS5 + OFF5`` or ``FS5 - 0.5·OFF5``."""
        out = self.name
        for other, a in self.absorbed:
            sign = "-" if a < 0 else "+"
            size = abs(a)
            out += f" {sign} {other}" if abs(size - 1.0) <= 1e-6 else f" {sign} {size:.4g}·{other}"
        return out


@dataclass(frozen=True)
class ColumnReduction:
    """The columns a fit keeps: ``names`` (every column), ``kept`` (indices, in order), ``zero`` (the
    columns 0 on every fitted row, left out), ``merged`` (the columns kept that hold others; the others
    left out)."""

    names: tuple[str, ...]
    kept: tuple[int, ...]
    zero: tuple[str, ...] = ()
    merged: tuple[Merged, ...] = ()

    @property
    def full(self) -> bool:
        """Whether every column is kept as it is."""
        return len(self.kept) == len(self.names)

    @property
    def kept_names(self) -> tuple[str, ...]:
        return tuple(self.names[k] for k in self.kept)

    @property
    def absorbed(self) -> tuple[str, ...]:
        """The columns left out because a column kept holds them."""
        return tuple(name for m in self.merged for name, _ in m.absorbed)

    def holds(self) -> dict[str, str]:
        """{column kept: what its estimate holds} for the merged columns."""
        return {m.name: m.holds() for m in self.merged}

    def to_json(self) -> dict:
        return {"left_out": list(self.zero), "merged": {m.name: m.holds() for m in self.merged}}


def reduce_columns(R: np.ndarray, names: Sequence[str], rcond: float = RANK_RCOND,
                   also: Sequence[np.ndarray] = ()) -> ColumnReduction:
    """The columns of the triangular factor ``R`` of W (c x c, unweighted: ``stack_systems(...).R``) a fit
    keeps so that they are of full rank, in ``R`` and in each factor of ``also`` (the same rows weighted,
    whose singular values differ) (module docstring): the zero columns left out, then among the others,
    as many columns as the null space has dimensions, each time the last in the names' order among those
    that carry at least half the largest share of what is left of the null space (a pivoted QR of the null
    space's basis: the columns kept are well conditioned), each expressed in the columns kept (``Merged``,
    from ``R``)."""
    names = tuple(names)
    R = np.asarray(R, dtype=float)
    norms = np.linalg.norm(R, axis=0)
    top = norms.max() if norms.size else 0.0
    live = [k for k in range(len(names)) if norms[k] > top * np.finfo(float).eps]
    zero = tuple(names[k] for k in range(len(names)) if k not in live)
    kept = list(live)
    for M in [R, *(np.asarray(a, dtype=float) for a in also)] * 2:  # twice: a drop for one may not suit the other
        if not kept:
            break
        rank, _ = rank_and_null_share(M[:, kept], rcond)
        if rank < len(kept):
            _, _, vt = np.linalg.svd(column_scaled(M[:, kept]))
            drop = {kept[i] for i in _pivots(vt[rank:].T)}
            kept = [k for k in kept if k not in drop]
    dropped = [k for k in live if k not in kept]
    merged = _merged(R, names, tuple(kept), dropped) if dropped else ()
    return ColumnReduction(names, tuple(kept), zero, merged)


def _pivots(null: np.ndarray) -> list[int]:
    """Rows of ``null`` (an orthonormal basis of the null space, one row per column) whose removal leaves
    columns of full rank: pivoted Gram-Schmidt on the rows, preferring the last of the rows within half
    the largest residual norm."""
    rest = null.copy()
    chosen: list[int] = []
    for _ in range(null.shape[1]):
        size = np.linalg.norm(rest, axis=1)
        candidates = np.flatnonzero(size >= 0.5 * size.max())
        k = int(candidates[-1])
        chosen.append(k)
        u = rest[k] / size[k]
        rest = rest - np.outer(rest @ u, u)
    return chosen


def _merged(R: np.ndarray, names: tuple[str, ...], kept: tuple[int, ...], dropped: list[int]) -> tuple[Merged, ...]:
    """Each dropped column in the kept ones (W_d = sum_i a_id W_i exactly): the kept column i holds its
    parameter plus sum_d a_id x parameter d."""
    A, *_ = np.linalg.lstsq(R[:, list(kept)], R[:, dropped], rcond=None)
    norms = np.linalg.norm(R, axis=0)
    out = []
    for i, k in enumerate(kept):
        terms = tuple((names[d], float(A[i, j])) for j, d in enumerate(dropped)
                      if abs(A[i, j]) * norms[k] > NEGLIGIBLE * norms[d])
        if terms:
            out.append(Merged(names[k], terms))
    return tuple(out)
