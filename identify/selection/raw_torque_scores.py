"""One candidate processing of the cross-validated choice, scored against the raw measured torques block by block.

For each held-back time block b the fit of the other blocks (:func:`~identify.estimation.least_squares.fold_wls`,
eq. 11's weights) predicts the torques at the candidate's own cut-off and decimation; that prediction,
``Phi(t_k) beta - spring(t_k)`` at the decimated rows t_k (shifted by the fit's torque delay), is
interpolated linearly onto the recording's own time stamps and compared with the unfiltered torques
there (:func:`identify.signal.interpolate.onto`'s rule: between two rows the straight line, before the
first and after the last row of a segment the end value). The interpolated regressor is
``W_interp(t) = (1 - w) Phi_k + w Phi_k+1``, so the squared error of block b is a quadratic form in
``beta``: the rows ``[W_interp | 1 | tau + spring_interp | tau]`` of every raw sample scored are folded
into a per-(time block, joint) triangular factor ``S_b`` (incremental QR), and the error of block b is
``||S_b [beta_-b; offset; -1; 0]||^2``, its reference ``||tau||^2`` the squared norm of ``S_b``'s last
column. The fitted rows ``[W | 1 | Y]`` go into a factor per (block, joint) the same way. The column
of ones is joint j's torque offset (``identify.observation.offsets``): the factors kept, the chosen
processing is scored with offsets without another pass over the recordings.

The raw samples scored (:class:`RawSpan`) are the same for every candidate: measured (not bridged), at
least the filters' edges of the grid's lowest cut-off (plus two periods of its coarsest decimation and
the delay) from each segment's ends; the time blocks cut their span, and a fitted row at time t falls
in the block of t + delay. A window of the block-wise pipeline (:mod:`identify.observation.block_rows`)
scores the raw samples between its own first and last rows; those between the last row of one window
and the first of the next are scored when both rows are known (:class:`RawFactors` joins them), so
that every raw sample sees the same two rows as on the whole recording.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.estimation.dependent_columns import reduce_columns
from identify.estimation.incremental_qr import JointFactors
from identify.selection.candidates import Candidate
from identify.estimation.least_squares import fold_wls
from identify.selection.folds import block_scores, time_folds
from identify.observation.block_rows import Plan, piece
from identify.observation.scan import Scan
from identify.observation.processing import Processing
from identify.signal.filtering import EDGE_PERIODS
from identify.signal.interpolate import onto, onto_weights

__all__ = ["RawSpan", "RawFactors", "offset_columns_of", "raw_span", "window_factors"]


@dataclass(frozen=True)
class RawSpan:
    """The raw samples every candidate is scored on: per segment (recording index, first sample) the
    times [s] ``(lo, hi)`` between which its measured samples are scored (segments absent: none), and
    the time blocks' ``start`` and ``span`` [s] (from the first to the last sample scored)."""

    bounds: dict
    start: float
    span: float
    blocks: int


def raw_span(scans: Sequence[Scan], grid: Sequence[Candidate], blocks: int, delay: float = 0.0) -> RawSpan:
    """:class:`RawSpan` of the recordings scanned (their segments' first and last times, kept by the
    scan) for the candidates of ``grid``: the margin from each segment's ends is the filters' edges at
    its lowest cut-off, two periods of its coarsest decimation and the ``delay`` [s]; a segment with
    fewer than two samples scored is left out."""
    lowest = min(c.cutoff for c in grid)
    coarsest = min((c.decimate_to for c in grid if c.decimate_to), default=None)
    margin = EDGE_PERIODS / lowest + (2.0 / coarsest if coarsest else 0.0) + abs(delay)
    bounds, firsts, lasts = {}, [], []
    for k, s in enumerate(scans):
        for g in s.segments:
            lo, hi = float(g.head[0]) + margin, float(g.tail[-1]) - margin
            first, last, count = _scored_ends(g, lo, hi, s.source)
            if count >= 2:
                bounds[(k, g.start)] = (lo, hi)
                firsts.append(first)
                lasts.append(last)
    if not bounds:
        raise ValueError(f"no segment is longer than the {2 * margin:.3g} s the cross-validation's filters' edges need")
    start = min(firsts)
    return RawSpan(bounds, start, max(lasts) - start + 1e-9, blocks)


def _scored_ends(g: Any, lo: float, hi: float, source: str) -> tuple[float, float, int]:
    """(first, last time [s], number) of the measured samples of segment ``g`` within [lo, hi], from the
    times its scan kept (the number is at least 2 when unseen samples lie between its head and tail)."""
    overlap = g.head.size + g.tail.size - g.samples
    if overlap >= 0:  # every sample's time seen
        t = np.concatenate([g.head, g.tail[overlap:]])
        ok = np.concatenate([g.head_measured, g.tail_measured[overlap:]])
        kept = t[ok & (t >= lo) & (t <= hi)]
        return (float(kept[0]), float(kept[-1]), kept.size) if kept.size else (math.nan, math.nan, 0)
    head = g.head[g.head_measured & (g.head >= lo) & (g.head <= hi)]
    tail = g.tail[g.tail_measured & (g.tail >= lo) & (g.tail <= hi)]
    if not (head.size and tail.size):
        raise ValueError(f"{source}: no measured sample found within the first and last "
                         f"{g.head[-1] - g.head[0]:.3g} s of a segment beyond the filters' edges "
                         f"({lo - g.head[0]:.3g} s): the cross-validation cannot place its time blocks")
    return float(head[0]), float(tail[-1]), 2


@dataclass(frozen=True, eq=False)
class _Edge:
    """A window's end row for the raw samples between two windows: its prediction time [s] (row time +
    delay), regressor row (n, c) and spring torque (n,), and the raw samples beyond it on that side
    (index in the recording, time [s], torques (m, n)), measured and within the segment's bounds."""

    time: float
    Phi: np.ndarray
    spring: np.ndarray
    index: np.ndarray
    t: np.ndarray
    tau: np.ndarray


def _scored_rows(blocks: int, span: RawSpan, t: np.ndarray, tau: np.ndarray, x: np.ndarray, xp: np.ndarray,
                 Phi: np.ndarray, spring: np.ndarray) -> list[tuple[int, int, np.ndarray, int]]:
    """Per (time block, joint): the factor of ``[W_interp | 1 | tau + spring_interp | tau]`` of the raw
    samples at times ``t`` (torques ``tau`` (m, n)), the rows ``Phi`` (S, n, c) and ``spring`` (S, n)
    at the prediction times ``xp`` interpolated at ``x`` (= t)."""
    if t.size == 0:
        return []
    weights = onto_weights(x, xp) if xp.size > 1 else None
    s = onto(x, xp, spring, weights)
    ids = time_folds(t, span.start, span.span, blocks)
    out = []
    for j in range(Phi.shape[1]):  # one joint's interpolated rows at a time: (m, c), not (m, n, c)
        W = onto(x, xp, Phi[:, j, :], weights)
        for b in np.unique(ids):
            here = ids == b
            rows = np.column_stack([W[here], np.ones(int(here.sum())), tau[here, j] + s[here, j], tau[here, j]])
            out.append((int(b), j, JointFactors.block_factor(rows), rows.shape[0]))
    return out


def window_factors(robot: rx90sym.Robot, rec: Any, window: Any, plan: Plan, processing: Processing, columns: Any,
                   names: Sequence[str], span: RawSpan, bounds: tuple[float, float] | None, drop: bool,
                   left_out: Sequence[int] = ()) -> tuple[list, list, _Edge | None, _Edge | None]:
    """One window of a candidate (the streamed fit's :func:`~identify.observation.block_rows.piece`, a Dask
    task when distributed; ``columns``: what gives the regressor, ``regressor_batch``, of the columns
    ``names``): per (time block, joint) the factors of its fitted rows ``[W | 1 | Y]`` and of
    the raw samples it scores (:func:`_scored_rows`), and its first and last rows with the raw samples
    beyond them (None at a segment's end: there the end row is held, scored here)."""
    m = piece(robot, rec, window, plan, processing, columns.regressor_batch, names, 0, (), left_out).motion
    delay, blocks = processing.delay, span.blocks
    ids = np.clip(time_folds(m.t + delay, span.start, span.span, blocks), 0, blocks - 1)
    keep = m.rows(drop)
    fitted = []
    for b in np.unique(ids):
        here = ids == b
        for j in range(m.Phi.shape[1]):
            sel = keep[:, j] & here
            rows = np.column_stack([m.Phi[sel, j, :], np.ones(int(sel.sum())), m.Y[sel, j]])
            fitted.append((int(b), j, JointFactors.block_factor(rows), rows.shape[0]))
    n = m.Phi.shape[1]
    spring = robot.spring_torque_batch(m.q)[:, :, 0] if processing.spring and robot.spring is not None \
        else np.zeros((m.t.size, n))
    xp = m.t + delay
    first, last = window.core[0] == 0, window.core[1] == plan.samples
    t = np.asarray(rec.t, dtype=float)
    tau = np.asarray(rec.torques, dtype=float)
    scored = np.zeros(t.size, dtype=bool) if bounds is None else \
        np.asarray(rec.measured_mask, dtype=bool) & (t >= bounds[0]) & (t <= bounds[1])
    before = scored & (t < xp[0]) & (not first)
    after = scored & (t >= xp[-1]) & (not last)
    own = scored & ~before & ~after
    raw = _scored_rows(blocks, span, t[own], tau[own], t[own], xp, m.Phi, spring)
    index = plan.start + window.raw[0] + np.arange(t.size)

    def edge(row: int, beyond: np.ndarray) -> _Edge:
        return _Edge(float(xp[row]), m.Phi[row], spring[row], index[beyond], t[beyond], tau[beyond])

    return fitted, raw, None if first else edge(0, before), None if last else edge(-1, after)


class RawFactors:
    """The factors of one candidate over every window (folded in window order): fitted rows and raw
    samples scored per (time block, joint); :meth:`scores` with or without torque offsets."""

    def __init__(self, n: int, c: int, span: RawSpan) -> None:
        self.n, self.c, self.span = n, c, span
        self.fitted = [JointFactors(n, c + 1) for _ in range(span.blocks)]  # [W | 1 | Y]
        self.scored = [JointFactors(n, c + 1, 2) for _ in range(span.blocks)]  # [W | 1 | tau + spring | tau]
        self._after: _Edge | None = None

    def add(self, fitted: list, raw: list, before: _Edge | None, after: _Edge | None) -> None:
        """Fold in one window's :func:`window_factors` (windows in order)."""
        for b, j, factor, count in fitted:
            self.fitted[b].add_factor(j, factor, count)
        self._add_scored(raw)
        if before is not None and self._after is not None:  # the raw samples between the two windows' rows
            a = self._after
            index, at = np.unique(np.r_[a.index, before.index], return_index=True)
            t, tau = np.r_[a.t, before.t][at], np.concatenate([a.tau, before.tau])[at]
            between = (t >= a.time) & (t < before.time)
            xp = np.array([a.time, before.time])
            self._add_scored(_scored_rows(self.span.blocks, self.span, t[between], tau[between], t[between], xp,
                                          np.stack([a.Phi, before.Phi]), np.stack([a.spring, before.spring])))
        self._after = after

    def _add_scored(self, parts: list) -> None:
        for b, j, factor, count in parts:
            self.scored[b].add_factor(j, factor, count)

    def scores(self, offsets: Sequence[int] = ()) -> tuple[float, tuple[float, ...], tuple[tuple[float, ...], ...]]:
        """(score, per joint, per held-back block and joint), relative errors in %, with a torque offset
        on the joints ``offsets`` (0-based; a column OFFj in joint j's rows, as
        :class:`identify.observation.offsets.OffsetBase`)."""
        offsets = tuple(offsets)
        blocks, n, c = self.span.blocks, self.n, self.c
        factors = {(b, j): (self._columns(self.fitted[b].R[j], j, offsets), int(self.fitted[b].rows[j]))
                   for b in range(blocks) for j in range(n) if self.fitted[b].rows[j]}
        err2, ref2 = np.zeros((blocks, n)), np.zeros((blocks, n))
        fitted = {j for (_, j) in factors}  # a joint without fitted rows (its torque left out) is not scored
        for b in range(blocks):
            beta = fold_wls(factors, b, n)
            if beta is None:
                continue
            for j in sorted(fitted):
                S = self.scored[b].R[j]
                x = np.r_[beta[:c], beta[c + offsets.index(j)] if j in offsets else 0.0, -1.0, 0.0]
                err2[b, j], ref2[b, j] = np.sum((S @ x) ** 2), np.sum(S[:, -1] ** 2)  # ||W b - Y||², ||tau||²
        if not np.any(ref2 > 0):
            raise ValueError("no fold could be fitted and scored (too few rows left after the filters' edges)")
        return block_scores(err2, ref2)

    def inseparable_offsets(self, offsets: Sequence[int]) -> tuple[int, ...]:
        """The joints of ``offsets`` (0-based) whose torque offset the fitted rows cannot tell from the other
        columns (a joint that moves one way only: its Coulomb column is +1 or -1 on every row, its offset's
        1): the model with those offsets would be rank deficient (:func:`reduce_columns` of every fitted row
        with an offset column per joint; an offset column it leaves out or merges into another)."""
        offsets = tuple(offsets)
        if not offsets:
            return ()
        c = self.c
        parts = [self._columns(f.R[j], j, offsets)[:, :-1] for f in self.fitted for j in range(self.n) if f.rows[j]]
        R = JointFactors.block_factor(np.vstack(parts))
        names = [f"c{k}" for k in range(c)] + [f"OFF{j + 1}" for j in offsets]
        reduction = reduce_columns(R, names)
        out = set(reduction.zero) | set(reduction.absorbed)
        return tuple(j for j in offsets if f"OFF{j + 1}" in out)

    def _columns(self, R: np.ndarray, joint: int, offsets: tuple[int, ...]) -> np.ndarray:
        return offset_columns_of(R, self.c, joint, offsets)


def offset_columns_of(R: np.ndarray, c: int, joint: int, offsets: Sequence[int]) -> np.ndarray:
    """A fitted factor's columns ``[W | 1 | Y | …]`` (``c`` columns of W) as ``[W | one offset column per
    joint of offsets | Y]``: the ones in joint ``joint``'s own offset column, zeros in the others (the
    rows of the joints stacked share the columns; the right-hand sides after Y are dropped)."""
    cols = [R[:, :c]] + [R[:, c:c + 1] if k == joint else np.zeros((R.shape[0], 1)) for k in offsets]
    return np.hstack(cols + [R[:, c + 1:c + 2]])
