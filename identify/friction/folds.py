"""The friction choice's passes over a fit's rows, block by block, and what it computes of them.

The friction choice (:mod:`identify.friction.choice`) reads the fit's rows in passes (:class:`FoldRows`:
one filtered motion per block, :func:`identify.observation.block_rows.piece`, with the time block of each
row). Everything else is computed from per-(time block, joint) triangular factors, so it is the same
whatever the blocks:

- :func:`fold_scales_of`: per held-back block the velocity scales searched on the other blocks
  (:mod:`identify.friction.scale_search`, two passes of the probe columns);
- :func:`held_back_errors`: the form's exact (parallel-filtered) columns at each fold's scales, all folds
  in one pass (:class:`FoldColumns`: a column FSj_f per fold f, resting like FSj), the fold fits (the
  fit's own weighted least squares, :func:`identify.estimation.least_squares.weighted_system`) and the
  held-back errors from the factors.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, Iterator, Sequence

import numpy as np

import rx90sym

from identify.estimation.compression import _qr_r
from identify.friction.forms import friction_columns
from identify.friction.scale_search import find_scales
from identify.friction.scales import VelocityScales, as_velocity_scales, smooth_joints
from identify.observation.block_rows import in_order, piece, plan_windows, windows_in_order
from identify.observation.processing import FrictionForm, Processing, drops_rest
from identify.observation.rest import STRIBECK_PREFIX
from identify.selection.cross_validation import DEFAULT_BLOCKS
from identify.estimation.least_squares import fold_wls
from identify.selection.folds import time_folds
from identify.selection.processing_choice import time_span

__all__ = ["FoldColumns", "FoldRows", "fold_scales_of", "held_back_errors"]


@dataclass(frozen=True, eq=False)
class FoldRows:
    """The rows of a fit read block by block (:mod:`identify.observation.block_rows`): sources, plans (per
    recording), the fit's processing (its cut-off and delay chosen), the time span (start, length [s],
    blocks) of the time blocks, the joints whose torque is left out, a Dask client (None: here)."""

    robot: rx90sym.Robot
    sources: Sequence[Any]
    plans: Sequence[Any]
    processing: Processing
    span: tuple[float, float, int]
    left_out: tuple[int, ...] = ()
    client: Any = None

    @classmethod
    def of(cls, robot: rx90sym.Robot, sources: Sequence[Any], scans: Sequence[Any], processing: Processing, block: int,
           left_out: Sequence[int] = (), client: Any = None, blocks: int = DEFAULT_BLOCKS) -> "FoldRows":
        """The rows of ``sources`` (``scans``: their first pass, each segment's first and last times kept) made
        with ``processing`` in blocks of ``block`` samples, cut into ``blocks`` time blocks over the rows' span
        (the processing choice's blocks)."""
        plans = [plan_windows(s, processing, block)[0] for s in scans]
        first, last = time_span(scans, plans)
        return cls(robot, tuple(sources), plans, processing, (first, last - first + 1e-9, blocks), tuple(left_out),
                   client)

    @property
    def blocks(self) -> int:
        return self.span[2]

    @property
    def presliding_rest(self) -> Any:
        return self.processing.rest if self.processing.min_velocity is not None else None

    @property
    def drop(self) -> bool:
        return self.processing.min_velocity is not None and drops_rest(self.processing.rest)

    def motions(self, columns: Any) -> Iterator[tuple[Any, np.ndarray]]:
        tasks = ((self.robot, rec, window, plan, self.processing, columns.regressor_batch, columns.names, 0, (),
                  tuple(self.left_out)) for plan, window, rec, _ in windows_in_order(self.sources, self.plans))
        for p in in_order(piece, tasks, self.client, 4 if self.client is not None else 1):
            yield p.motion, time_folds(p.motion.t, *self.span)


def fold_scales_of(rows: Any, probe: Any, terms: Sequence[Any], form: FrictionForm,
                   n: int) -> list[VelocityScales]:
    """Per held-back time block the scales of ``form`` searched on the other blocks only (probe columns
    ``probe``: own Coulomb columns holding the driver speed; ``terms`` its own Coulomb terms)."""
    from identify.observation.rest import presliding_base

    own, forms = smooth_joints(terms, form)
    blocks = rows.blocks
    probe = presliding_base(rows.robot, probe, rows.presliding_rest)   # FPj columns with "presliding", as in the fit

    def feed(table: Any) -> None:
        for m, ids in rows.motions(probe):
            keep = m.rows(rows.drop)
            for j in range(n):
                k = keep[:, j]
                table.add(j, m.Phi[k, j, :], m.Y[k, j], ids[k])

    sets = [[x for x in range(blocks) if x != b] for b in range(blocks)]
    return [as_velocity_scales(x, form, n) for x in find_scales(feed, n, len(probe.names), own, forms, sets, blocks,
                                                                   std=False)]


@dataclass(frozen=True, eq=False)
class FoldColumns:
    """``inner``'s columns and, per fold f and joint j of a smooth form, FSj_f (and FSTj_f for
    Stribeck): the form's columns at fold f's scale ``scales[f][j]`` [rad/s] (a column per fold, all
    filtered in one pass; the rest policy zeroes them like FSj)."""

    inner: Any
    terms: tuple[Any, ...]
    form: FrictionForm
    scales: tuple[tuple[float, ...], ...]

    def form_of(self, j: int) -> str:
        return self.form if isinstance(self.form, str) else self.form[j]

    @cached_property
    def smooth(self) -> tuple[Any, ...]:
        return tuple(t for t in self.terms if self.form_of(t.row) in ("tanh", "stribeck"))

    @cached_property
    def names(self) -> tuple[str, ...]:
        extra = [f"FS{t.row + 1}_{f}" for f in range(len(self.scales)) for t in self.smooth]
        extra += [f"{STRIBECK_PREFIX}{t.row + 1}_{f}" for f in range(len(self.scales)) for t in self.smooth
                  if self.form_of(t.row) == "stribeck"]
        return tuple(self.inner.names) + tuple(extra)

    def regressor_batch(self, Q: Any, QD: Any, QDD: Any) -> np.ndarray:
        Phi = self.inner.regressor_batch(Q, QD, QDD)
        out = np.zeros(Phi.shape[:2] + (len(self.names),))
        out[:, :, :Phi.shape[2]] = Phi
        QD = np.asarray(QD, dtype=float)
        where = {name: k for k, name in enumerate(self.names)}
        for f, scales in enumerate(self.scales):
            for t in self.smooth:
                if not np.isfinite(scales[t.row]):  # no rows to search it on (a torque left out): nothing to fit
                    continue
                cols, _ = friction_columns(self.form_of(t.row), QD @ np.asarray(t.driver), scales[t.row])
                out[:, t.row, where[f"FS{t.row + 1}_{f}"]] = cols[:, 0]
                if cols.shape[1] > 1:
                    out[:, t.row, where[f"{STRIBECK_PREFIX}{t.row + 1}_{f}"]] = cols[:, 1]
        return out


def held_back_errors(rows: Any, inner: Any, terms: Sequence[Any], form: FrictionForm,
                     scales: Sequence[Sequence[float]] | None, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(squared held-back errors, squared held-back torques) (blocks, n) of ``form`` with its exact
    columns at each fold's ``scales`` (None: the Coulomb form, ``inner``'s own columns): per fold the
    WLS on the other blocks (eq. 11's weights), the held-back block predicted; one pass."""
    from identify.observation.rest import presliding_base

    blocks = rows.blocks
    inner = presliding_base(rows.robot, inner, rows.presliding_rest)   # FPj columns with "presliding", as in the fit
    columns = inner if scales is None else FoldColumns(inner, tuple(terms), form, tuple(tuple(s) for s in scales))
    R: dict[tuple[int, int], np.ndarray] = {}
    count: dict[tuple[int, int], int] = {}
    for m, ids in rows.motions(columns):
        keep = m.rows(rows.drop)
        for b in np.unique(ids):
            for j in range(n):
                k = keep[:, j] & (ids == b)
                if not k.any():
                    continue
                part = _qr_r(np.column_stack([m.Phi[k, j, :], m.Y[k, j]]))
                R[(b, j)] = part if (b, j) not in R else _qr_r(np.vstack([R[(b, j)], part]))
                count[(b, j)] = count.get((b, j), 0) + int(k.sum())
    c = len(inner.names)
    stribeck = [t.row for t in (columns.smooth if scales is not None else ()) if columns.form_of(t.row) == "stribeck"]
    C = c + len(stribeck)
    names = list(columns.names)

    def placed(Rbj: np.ndarray, j: int, fold: int) -> np.ndarray:
        """A factor's columns for fold ``fold``'s fit: FSj ← FSj_fold, FSTj_fold appended (C + 1 columns)."""
        out = np.zeros((Rbj.shape[0], C + 1))
        out[:, :c] = Rbj[:, :c]
        out[:, C] = Rbj[:, -1]
        if scales is not None:
            for t in columns.smooth:
                if t.row == j:
                    out[:, t.column] = Rbj[:, names.index(f"FS{j + 1}_{fold}")]
                    if j in stribeck:
                        out[:, c + stribeck.index(j)] = Rbj[:, names.index(f"{STRIBECK_PREFIX}{j + 1}_{fold}")]
        return out

    err2, ref2 = np.zeros((blocks, n)), np.zeros((blocks, n))
    for b in range(blocks):
        factors = {key: (placed(Rk, key[1], b), count[key]) for key, Rk in R.items()}
        beta = fold_wls(factors, b, n)  # eq. 11's per-joint weights, as the processing's folds
        if beta is None:
            raise ValueError(f"friction choice: too few rows to fit without block {b + 1}")
        x = np.r_[beta, -1.0]
        for j in range(n):
            if (b, j) in factors:
                M = factors[(b, j)][0]
                err2[b, j], ref2[b, j] = float(np.sum((M @ x) ** 2)), float(np.sum(M[:, -1] ** 2))
    return err2, ref2
