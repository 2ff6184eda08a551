"""The scale tables of smooth friction: per (fold, joint) the triangular factor of the probe rows with
the form's columns at a list of scales, and the histogram of the joint's speeds.

A smooth form's column of joint j (tanh(v/s), or Stribeck's pair) is evaluated on the filtered,
decimated driver speed v of every row (the probe observation's own Coulomb column) at each scale s_k
listed for the joint, beside W_j (own Coulomb column sign(v)) and Y_j, and the rows are folded into
``R_j = qr([W_j | F_j(s_1) … F_j(s_K) | Y_j])`` block after block (incremental QR, per
cross-validation time block when asked): what :mod:`identify.friction.scale_search` searches the
scales from, whatever the blocks. The histogram of |v| on fixed bins gives each joint's lower bound
(:func:`lower_bounds`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from identify.estimation.compression import _qr_r
from identify.friction.forms import friction_columns

__all__ = ["LOW_SPEED_SHARE", "SCALE_BOUNDS", "SPEED_EDGES", "ScaleTable", "lower_bounds"]

#: Velocity scales searched [rad/s]: below 1e-4 the form is sign(q̇) on any logged speed; above
#: 2 rad/s it is a second viscous term on the speeds of an arm.
SCALE_BOUNDS = (1e-4, 2.0)
#: Share of a joint's moving rows that must lie below its velocity scale (see :func:`lower_bounds`).
LOW_SPEED_SHARE = 0.02
#: Histogram of |v| per joint: bin edges [rad/s], 1/1000 decade apart.
SPEED_EDGES = 10.0 ** (-8 + np.arange(11001) / 1000)


def _columns_per_scale(forms: dict[int, str]) -> int:
    return 2 if "stribeck" in forms.values() else 1


@dataclass(eq=False)
class ScaleTable:
    """Per (fold, joint) the triangular factor of ``[W_j (own Coulomb column = sign v) | F_j(scales_j) | Y_j]``
    and the histogram of the joint's |v|, filled row block after row block.

    c: probe columns; own: joint (0-based) -> column of its own Coulomb term (holding v in the probe);
    forms: joint -> "tanh" | "stribeck" for the joints whose scale is searched; scales: joint -> the
    scales [rad/s] tabulated (the same count for every joint); folds: time blocks (1: no folds);
    derivatives: also each column's derivative in ln s (after the columns: the σ of the scales)."""

    n: int
    c: int
    own: dict[int, int]
    forms: dict[int, str]
    scales: dict[int, np.ndarray]
    folds: int = 1
    derivatives: bool = False
    R: dict[tuple[int, int], np.ndarray] = field(default_factory=dict)
    rows: dict[tuple[int, int], int] = field(default_factory=dict)
    counts: np.ndarray | None = None

    def __post_init__(self) -> None:
        sizes = {len(s) for s in self.scales.values()}
        if len(sizes) > 1:
            raise ValueError(f"scale table: every joint needs as many scales, got {sorted(sizes)}")
        self.K = sizes.pop() if sizes else 0
        self.m = _columns_per_scale(self.forms)
        self.width = self.c + (2 if self.derivatives else 1) * self.K * self.m + 1
        if self.counts is None:
            self.counts = np.zeros((self.folds, self.n, SPEED_EDGES.size + 1), dtype=np.int64)

    def empty(self) -> "ScaleTable":
        """A table of the same columns without rows (what a block's task fills)."""
        return ScaleTable(self.n, self.c, self.own, self.forms, self.scales, self.folds, self.derivatives)

    def rows_of(self, joint: int, W: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """The table's rows (m, width) of joint ``joint`` from probe rows W (m, c) and torques Y (m,)."""
        out = np.zeros((W.shape[0], self.width))
        out[:, :self.c] = W
        out[:, -1] = Y
        col = self.own.get(joint)
        if col is None:
            return out
        v = W[:, col]
        out[:, col] = np.sign(v)
        form = self.forms.get(joint)
        if form is not None:
            d0 = self.c + self.K * self.m   # the derivatives' columns, after the columns
            for k, s in enumerate(self.scales[joint]):
                cols, dcols = friction_columns(form, v, float(s))
                out[:, self.c + k * self.m:self.c + k * self.m + cols.shape[1]] = cols
                if self.derivatives:   # ∂/∂ln s = s ∂/∂s (Gauss-Newton's Jacobian in log s)
                    out[:, d0 + k * self.m:d0 + k * self.m + cols.shape[1]] = float(s) * dcols
        return out

    def add(self, joint: int, W: np.ndarray, Y: np.ndarray, fold: np.ndarray | int = 0) -> None:
        """Fold in probe rows W (m, c), Y (m,) of joint ``joint`` falling in time block(s) ``fold``."""
        rows = self.rows_of(joint, np.asarray(W, dtype=float), np.asarray(Y, dtype=float))
        ids = np.broadcast_to(np.asarray(fold), (rows.shape[0],))
        for b in np.unique(ids):
            self.add_factor(int(b), joint, *self.block_part(joint, rows[ids == b], W[ids == b]))

    def block_part(self, joint: int, rows: np.ndarray, W: np.ndarray) -> tuple[np.ndarray, int, np.ndarray]:
        """(factor, row count, |v| histogram) of one block's rows of ``joint`` (a Dask task's result)."""
        col = self.own.get(joint)
        hist = np.zeros(SPEED_EDGES.size + 1, dtype=np.int64)
        if col is not None:
            v = np.abs(W[:, col])
            hist += np.bincount(np.searchsorted(SPEED_EDGES, v[v > 0], side="right"), minlength=hist.size)
        return _qr_r(np.array(rows, order="F")), rows.shape[0], hist

    def add_factor(self, fold: int, joint: int, factor: np.ndarray, count: int, hist: np.ndarray) -> None:
        """Fold in a block's factor of ``count`` rows and its histogram (TSQR: R ← qr([R; R_block]))."""
        self.counts[fold, joint] += hist
        if count == 0:
            return
        key = (fold, joint)
        self.R[key] = factor if key not in self.R else _qr_r(np.vstack([self.R[key], factor]))
        self.rows[key] = self.rows.get(key, 0) + int(count)

    def merged(self, folds: Sequence[int]) -> tuple[dict[int, np.ndarray], dict[int, int], np.ndarray]:
        """(per joint the factor over ``folds``, its rows, the joints' histograms (n, bins))."""
        R, rows = {}, {}
        for j in range(self.n):
            parts = [self.R[(b, j)] for b in folds if (b, j) in self.R]
            if parts:
                R[j] = parts[0] if len(parts) == 1 else _qr_r(np.vstack(parts))
                rows[j] = sum(self.rows[(b, j)] for b in folds if (b, j) in self.R)
        return R, rows, self.counts[list(folds)].sum(axis=0)


def _order_statistic(cum: np.ndarray, i: int) -> float:
    """The i-th smallest value (1-based) of a histogram on :data:`SPEED_EDGES` (``cum`` its cumulative
    counts): the (geometric) centre of its bin."""
    k = int(np.searchsorted(cum, i))          # its bin: [EDGES[k-1], EDGES[k])
    if k == 0 or k >= SPEED_EDGES.size:
        return float(SPEED_EDGES[min(k, SPEED_EDGES.size - 1)])
    return float(np.sqrt(SPEED_EDGES[k - 1] * SPEED_EDGES[k]))


def lower_bounds(counts: np.ndarray, joints: Sequence[int]) -> np.ndarray:
    """ln of each joint's lowest scale: :data:`SCALE_BOUNDS`, raised to half the :data:`LOW_SPEED_SHARE`
    quantile of its moving speeds (``np.quantile``'s linear rule on the order statistics read from the
    histogram, each to within its bin), at most a tenth of the upper bound."""
    lo = []
    for j in joints:
        cum = np.cumsum(counts[j])
        total = int(cum[-1])
        if total == 0:
            lo.append(SCALE_BOUNDS[0])
            continue
        r = LOW_SPEED_SHARE * (total - 1)             # 0-based position, as np.quantile
        i = int(np.floor(r))
        a = _order_statistic(cum, i + 1)
        b = _order_statistic(cum, min(i + 2, total))
        lo.append(max(SCALE_BOUNDS[0], (a + (r - i) * (b - a)) / 2))
    return np.log(np.minimum(np.array(lo), SCALE_BOUNDS[1] / 10))
