"""Processing chosen on the torques for logs of any length: the blocked cross-validation block by block.

:func:`choose_processing_streamed` makes the choice of
:func:`identify.observation.cross_validation.choose_processing` (same grid, same common scoring rate,
same 5 contiguous time blocks, same selection: :func:`~identify.observation.cross_validation.select_processing`)
without holding a log in memory:

1. one scan of every recording (:func:`identify.observation.stream.scan`) gives each segment's rate,
   its position-spectrum cut-off with the 2 Hz floor (the knee; the default candidate's cut-off is
   the same spectrum with the decimation's floor, :func:`~identify.observation.stream.scanned_cutoff`)
   and the times of its first and last seconds (where the filters' edges end: the time span of the
   decimated rows, hence the time blocks, exactly as in memory);
2. each candidate streams the recordings through the streamed fit's own row code
   (:func:`identify.observation.stream.piece`: segments, bridged rows, rest masks, parallel
   decimation to the common rate), assigns each decimated row to its time block and folds it into
   the per-(block, joint) triangular factor ``R_b`` of ``[W | Y]`` (incremental QR): memory
   blocks × joints × (c + 1)² doubles per candidate;
3. the fold fits are :func:`~identify.observation.cross_validation.fold_wls` on those factors; the
   held-back error of block b is ``‖R_b [β_-b; -1]‖²`` and its reference ``‖Y_b‖²`` the squared norm
   of ``R_b``'s last column: no second pass over the data.

Each candidate costs one pass over the recordings (reading, filtering, regressor, decimation), about
what the fit itself costs: the row cap (:data:`~identify.observation.cross_validation.DEFAULT_ROW_CAP`
observation rows, about 60 s of passes on the reference machine; a count, so the same log gets the
same choice on any machine) then leaves the cut-offs after the first unscored on a long log, listed
as such in the table. With a Dask client every block of a candidate is
a task (its factors are folded in block order on the client: the serial result).
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.estimation.incremental_qr import JointFactors, stacked_rows
from identify.io.blocks import BlockSource
from identify.observation.cross_validation import (DEFAULT_BLOCKS, DEFAULT_ROW_CAP, SCORED_REST, Budget, Candidate,
                                                   ProcessingChoice, block_scores, fold_wls, grid_around,
                                                   scoring_rate, select_processing, time_folds)
from identify.observation.matrix import DECIMATION_PASSBAND, DEFAULT_MIN_VELOCITY, presliding_base
from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.observation.processing import RestPolicy, drops_rest
from identify.observation.stream import (DEFAULT_BLOCK, Plan, Scan, StreamSettings, in_order, piece, plan_windows,
                                         scan, scanned_cutoff, windows_in_order)
from identify.signal.filtering import EDGE_PERIODS

__all__ = ["choose_processing_streamed", "grid_of_scans", "scans_for_choice", "time_span"]

#: Lowest cut-off of the grid [Hz] (candidate_grid's floor): the scan keeps each segment's first and
#: last 2 x EDGE_PERIODS / LOWEST_CUTOFF seconds of times, beyond the filters' longest edge.
LOWEST_CUTOFF = 2.0
KEEP_SECONDS = 2.0 * EDGE_PERIODS / LOWEST_CUTOFF


def grid_of_scans(scans: Sequence[Scan], default_decimate: float | None) -> tuple[float, list[Candidate]]:
    """(knee [Hz], candidates) of :func:`~identify.observation.cross_validation.candidate_grid` from scans
    made with the 2 Hz floor: the knee the largest segment cut-off over segments of 64 samples or more,
    the rate the lowest segment rate, the default cut-off the automatic one with ``default_decimate``."""
    segments = [g for s in scans for g in s.segments]
    knee = max(g.cutoff for g in segments if g.samples >= 64)
    rate = min(g.rate for g in segments)
    floor = max(LOWEST_CUTOFF, DECIMATION_PASSBAND * default_decimate) if default_decimate else LOWEST_CUTOFF
    return knee, grid_around(knee, rate, scanned_cutoff(scans, floor), default_decimate)


def choose_processing_streamed(robot: rx90sym.Robot, sources: Sequence[BlockSource], base: Any = None,
                               min_velocity: float | None = DEFAULT_MIN_VELOCITY, rest: RestPolicy | None = None,
                               spring: bool = True, blocks: int = DEFAULT_BLOCKS,
                               row_cap: int | None = DEFAULT_ROW_CAP, time_cap: float | None = None,
                               default_decimate: float | None = DEFAULT_DECIMATE_TO,
                               block: int = DEFAULT_BLOCK, client: Any = None,
                               policies: Sequence[str] = SCORED_REST,
                               scans: Sequence[Scan] | None = None) -> ProcessingChoice:
    """:func:`identify.observation.cross_validation.choose_processing` on recordings read block by block
    (module docstring). sources: the recordings (:func:`identify.io.blocks.block_source`); block: raw
    samples per block core; client: a ``dask.distributed.Client`` running the blocks (None: here);
    scans: the sources' :func:`scans_for_choice` when already made (the fit that follows reuses them).
    The other arguments are those of ``choose_processing``."""
    if blocks < 2:
        raise ValueError(f"cross-validation needs at least 2 blocks, got {blocks}")
    base = base if base is not None else rx90sym.base_parameters(robot)
    scans = scans if scans is not None else scans_for_choice(sources, block)
    knee, grid = grid_of_scans(scans, default_decimate)
    reference = scoring_rate(grid)
    context = (robot, sources, scans, base, reference, blocks, min_velocity, spring, block, client)
    budget = Budget(robot.n * sum(g.samples for s in scans for g in s.segments), row_cap, time_cap)
    return select_processing(lambda cand: _score(cand, *context), knee, grid, reference, blocks, min_velocity,
                             rest, budget, policies)


def scans_for_choice(sources: Sequence[BlockSource], block: int) -> list[Scan]:
    """The first pass the choice needs (:func:`identify.observation.stream.scan` with the 2 Hz floor and
    each segment's first and last :data:`KEEP_SECONDS` of times); a fit with a given cut-off reuses it."""
    return [scan(src, block, LOWEST_CUTOFF, KEEP_SECONDS) for src in sources]


def time_span(scans: Sequence[Scan], plans: Sequence[Sequence[Plan]]) -> tuple[float, float]:
    """(first, last) time [s] of the decimated rows of every segment planned: samples ``edge`` and
    ``edge + (samples - 1) factor`` of each (the rows :func:`filtered_motion` keeps)."""
    firsts, lasts = [], []
    for s, src_plans in zip(scans, plans):
        by_start = {g.start: g for g in s.segments}
        for p in src_plans:
            g = by_start[p.start]
            firsts.append(g.time_at(p.edge))
            lasts.append(g.time_at(p.edge + (p.samples - 1) * p.factor))
    return min(firsts), max(lasts)


def _fold_task(robot: rx90sym.Robot, rec: Any, window: Any, plan: Plan, settings: StreamSettings, columns: Any,
               span: tuple[float, float, int], drop: bool) -> list[tuple[int, int, np.ndarray, int, Any]]:
    """One block's rows (the streamed fit's :func:`piece`), per (time block, joint): the factor of the
    fitted rows, their number and, when rest rows are dropped, the factor and number of the scored
    (measured) rows (None otherwise: the same rows)."""
    m = piece(robot, rec, window, plan, settings.cutoff, settings, columns.regressor_batch, columns.names, 0).motion
    ids = time_folds(m.t, *span)
    fitted, measured = m.rows(drop), m.rows(False)
    out = []
    for b in np.unique(ids):
        here = ids == b
        for j in range(m.Phi.shape[1]):
            rows = stacked_rows(m.Phi, [m.Y], j, fitted[:, j] & here)
            held = None
            if drop:
                scored = stacked_rows(m.Phi, [m.Y], j, measured[:, j] & here)
                held = (JointFactors.block_factor(scored), scored.shape[0])
            out.append((int(b), j, JointFactors.block_factor(rows), rows.shape[0], held))
    return out


def _score(cand: Candidate, robot: rx90sym.Robot, sources: Sequence[BlockSource], scans: Sequence[Scan], base: Any,
           reference: float | None, blocks: int, min_velocity: float | None, spring: bool, block: int,
           client: Any) -> tuple[float, tuple[float, ...], tuple[tuple[float, ...], ...]]:
    """(score, per joint, per held-back block and joint) of one candidate, relative errors in %, its
    rows decimated to the common rate ``reference`` [Hz], from one pass over the recordings."""
    threshold = min_velocity if cand.rest is not None else None
    rest = cand.rest or "zero-coulomb"
    columns = presliding_base(robot, base, rest if threshold is not None else None)  # FPj with presliding
    settings = StreamSettings(cand.cutoff, reference, threshold, rest, 0.0, spring, block)
    plans = [plan_windows(s, cand.cutoff, settings)[0] for s in scans]
    first, last = time_span(scans, plans)
    span = (first, last - first + 1e-9, blocks)  # as choose_processing's blocks in time
    drop = threshold is not None and drops_rest(rest)
    n, c = robot.n, len(columns.names)
    fitted = [JointFactors(n, c) for _ in range(blocks)]
    held = [JointFactors(n, c) for _ in range(blocks)] if drop else fitted
    if client is not None:  # the robot and its compiled columns sent once to each worker
        robot, columns = client.scatter([robot, columns], broadcast=True, hash=False)
    tasks = ((robot, rec, window, plan, settings, columns, span, drop)
             for plan, window, rec, _ in windows_in_order(sources, plans))
    for parts in in_order(_fold_task, tasks, client, 4 if client is not None else 1):
        for b, j, factor, count, scored in parts:
            fitted[b].add_factor(j, factor, count)
            if scored is not None:
                held[b].add_factor(j, *scored)
    factors = {(b, j): (f.R[j], int(f.rows[j])) for b, f in enumerate(fitted) for j in range(n) if f.rows[j]}
    err2, ref2 = np.zeros((blocks, n)), np.zeros((blocks, n))
    for b in range(blocks):
        beta = fold_wls(factors, b, n)
        if beta is None:
            continue
        x = np.r_[beta, -1.0]
        for j in range(n):
            R = held[b].R[j]
            err2[b, j], ref2[b, j] = np.sum((R @ x) ** 2), np.sum(R[:, -1] ** 2)  # ||W b - Y||², ||Y||²
    if not np.any(ref2 > 0):
        raise ValueError("no fold could be fitted and scored (too few rows left after the filters' edges)")
    return block_scores(err2, ref2)
