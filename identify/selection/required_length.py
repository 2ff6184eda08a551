"""How long the recordings must be for the cross-validated processing choice, and why a shorter one is not.

The choice (:mod:`identify.selection.processing_choice`) fits every candidate processing on all time blocks but
one and scores it on the one held back. Each fold's fit weights a joint by the residual of its own fit
(eq. 11), which needs more rows per joint than the model has columns. A recording is long enough when
every fold of the default candidate (the one kept unless clearly beaten) has that many: its rows are
those beyond the filter's edges at its cut-off, at its decimated rate, and the time blocks cut the span
of the raw samples scored (beyond the edges of the grid's lowest cut-off), so the outer blocks hold
the rows near the ends too. A shorter recording is fitted with the fixed defaults (the position
spectrum's cut-off, the default decimation and rest policy, no torque offsets), said in the fit's
processing choice record: a choice from folds that cannot be fitted would be chance.

For one recording of duration T [s], rate r [Hz] of the default candidate's rows, c columns, B blocks,
its filter edge e and the scored span's margin m [s] at each end, the worst fold (an outer block held
back) keeps T r - 2 e r - ((T - 2 m) / B + m - e) r rows, more than c when
T > ((c + 1) / r + e + m (1 - 2 / B)) / (1 - 1 / B).
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from identify.selection.raw_torque_scores import raw_span
from identify.selection.processing_choice import grid_of_scans
from identify.selection.candidates import Candidate, DEFAULT_LABEL
from identify.selection.cross_validation import MIN_GRID_CUTOFF
from identify.selection.folds import time_folds
from identify.observation.scan import Scan
from identify.io.blocks import DEFAULT_BLOCK
from identify.observation.processing import Processing
from identify.observation.block_rows import plan_windows
from identify.signal.filtering import EDGE_PERIODS, decimation_plan

__all__ = ["fold_rows", "required_seconds", "too_short"]


def fold_rows(scans: Sequence[Scan], default: Candidate, grid: Sequence[Candidate], blocks: int,
              delay: float = 0.0) -> int:
    """The fewest rows per joint a fold's fit of the ``default`` candidate keeps (every fitted row but those
    of the block held back; the rows at the default's decimated rate beyond its filter's edges, in the time
    blocks of ``grid``'s scored span): ValueError when the recordings are too short for the span or the
    filter."""
    span = raw_span(scans, grid, blocks, delay)
    processing = Processing(cutoff=default.cutoff, decimate_to=default.decimate_to, min_velocity=None,
                            rest="zero-coulomb", delay=delay)
    counts = np.zeros(blocks, dtype=int)
    for s in scans:
        by_start = {g.start: g for g in s.segments}
        for p in plan_windows(s, processing, DEFAULT_BLOCK)[0]:
            g = by_start[p.start]
            t = np.linspace(g.time_at(p.edge), g.time_at(p.edge + (p.samples - 1) * p.factor), p.samples)
            ids = np.clip(time_folds(t + delay, span.start, span.span, blocks), 0, blocks - 1)
            counts += np.bincount(ids, minlength=blocks)
    return int(counts.sum() - counts.max())


def required_seconds(columns: int, rate: float, cutoff: float, margin: float, blocks: int) -> float:
    """The shortest recording [s] whose every fold keeps more rows than ``columns`` (module docstring):
    rows at ``rate`` [Hz] beyond the edges of a filter at ``cutoff`` [Hz], blocks cutting the span scored
    ``margin`` [s] from each end."""
    edge = EDGE_PERIODS / cutoff
    return ((columns + 1) / rate + edge + margin * (1 - 2 / blocks)) / (1 - 1 / blocks)


def too_short(scans: Sequence[Scan], columns: int, default_decimate: float | None, blocks: int,
              delay: float = 0.0) -> str | None:
    """Why the recordings ``scans`` are too short for the cross-validation's ``blocks`` with a model of
    ``columns`` columns (how long they are, how long one must be), or None when every fold of the default
    candidate can be fitted."""
    rate = min(g.rate for s in scans for g in s.segments)
    default = Candidate(MIN_GRID_CUTOFF, default_decimate, label=DEFAULT_LABEL)
    grid: Sequence[Candidate] = [default]
    try:
        grid = grid_of_scans(scans, default_decimate)[1]
        default = next((c for c in grid if c.label == DEFAULT_LABEL), grid[0])  # a grid given without it: its first
        fewest = fold_rows(scans, default, grid, blocks, delay)
    except ValueError:  # shorter than the filters' edges, or than a spectrum's 64 samples
        fewest = 0
    if fewest > columns:
        return None
    rows_rate = decimation_plan(rate, default.decimate_to).rate if default.decimate_to else rate
    lowest = min(c.cutoff for c in grid)
    coarsest = min((c.decimate_to for c in grid if c.decimate_to), default=None)
    margin = EDGE_PERIODS / lowest + (2.0 / coarsest if coarsest else 0.0) + abs(delay)
    longest = max(g.samples / g.rate for s in scans for g in s.segments)  # samples x period
    need = max(required_seconds(columns, rows_rate, default.cutoff, margin, blocks), longest + 1.0 / rows_rate)
    what = "the recording is" if len(scans) == 1 else "the longest recording is"
    return (f"{what} {longest:.3g} s long, too short for the cross-validation's {blocks} blocks: each fold's fit "
            f"needs more rows per joint than the model's {columns} columns ({fewest} in the worst fold, at "
            f"{rows_rate:.4g} Hz beyond the filters' edges), about {math.ceil(100 * need) / 100:.3g} s of recording")
