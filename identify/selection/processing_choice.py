"""The processing chosen on the torques for logs of any length: the blocked cross-validation block by block.

:func:`choose_processing` is the cross-validated choice of the cut-off, the decimation, the rest policy
per joint and the torque offsets (the grid, the folds and the selection of
:mod:`identify.selection.cross_validation`: :func:`~identify.selection.cross_validation.select_processing`),
without holding a log in memory (a recording in memory is read as one block when it fits in one):

1. one scan of every recording (:func:`identify.observation.scan.scan`) gives each segment's rate,
   its position-spectrum cut-off with the 2 Hz floor (the knee; the default candidate's cut-off is
   the same spectrum with the decimation's floor, :func:`~identify.observation.scan.scanned_cutoff`)
   and the times of its first and last seconds (where the raw samples scored start and end, hence the
   time blocks: :func:`identify.selection.raw_torque_scores.raw_span`);
2. each candidate reads the recordings through the fit's own row code
   (:func:`identify.observation.block_rows.piece`: segments, bridged rows, rest masks, parallel
   decimation to the candidate's own rate) and folds its fitted rows and the raw samples it scores into
   per-(time block, joint) triangular factors (:mod:`identify.selection.raw_torque_scores`): memory
   blocks x joints x (c + 3)^2 doubles per candidate;
3. the fold fits are the fit's own weighted least squares on those factors
   (:func:`identify.selection.folds.fold_system`), each candidate scored against the raw measured
   torques, its held-back prediction interpolated onto the recordings' own time stamps: no second pass
   over the data, and none for the torque offsets (a column of ones is in every factor).

Each candidate costs one pass over the recordings (reading, filtering, regressor, decimation), about
what the fit itself costs: the row cap (:data:`~identify.selection.cross_validation.DEFAULT_ROW_CAP`
observation rows, about 60 s of passes on the reference machine; a count, so the same log gets the
same choice on any machine) then leaves the cut-offs after the first unscored on a long log, listed
as such in the table. With a Dask client every block of a candidate is
a task (its factors are folded in block order on the client: the serial result).
"""
from __future__ import annotations

import time
from dataclasses import replace
from types import SimpleNamespace
from typing import Any, Sequence

import rx90sym

from identify.io.blocks import DEFAULT_BLOCK, BlockSource, block_source
from identify.observation.block_rows import Plan, in_order, plan_windows, windows_in_order
from identify.observation.matrix import DECIMATION_PASSBAND
from identify.observation.processing import Processing, drops_rest
from identify.observation.rest import presliding_base
from identify.observation.scan import Scan, scan, scanned_cutoff, torque_left_out
from identify.selection.candidates import Candidate, ProcessingChoice
from identify.selection.cross_validation import (DEFAULT_BLOCKS, DEFAULT_ROW_CAP, RAW, SCORED_REST, Budget,
                                                 clearly_better, grid_around, score_candidates, select_processing)
from identify.selection.raw_torque_scores import RawFactors, RawSpan, raw_span, window_factors
from identify.signal.filtering import EDGE_PERIODS

__all__ = ["KEEP_SECONDS", "LOWEST_CUTOFF", "choose_processing", "column_factors", "grid_of_scans", "scans_for_choice",
           "time_span"]

#: Lowest cut-off of the grid [Hz] (the knee's floor): the scan keeps each segment's first and
#: last 2 x EDGE_PERIODS / LOWEST_CUTOFF seconds of times, beyond the filters' longest edge.
LOWEST_CUTOFF = 2.0
KEEP_SECONDS = 2.0 * EDGE_PERIODS / LOWEST_CUTOFF


def grid_of_scans(scans: Sequence[Scan], default_decimate: float | None) -> tuple[float, list[Candidate]]:
    """(knee [Hz], candidates of :func:`~identify.selection.cross_validation.grid_around`) from scans
    made with the 2 Hz floor: the knee the largest segment cut-off over segments of 64 samples or more,
    the rate the lowest segment rate, the default cut-off the automatic one with ``default_decimate``."""
    segments = [g for s in scans for g in s.segments]
    knee = max(g.cutoff for g in segments if g.samples >= 64)
    rate = min(g.rate for g in segments)
    floor = max(LOWEST_CUTOFF, DECIMATION_PASSBAND * default_decimate) if default_decimate else LOWEST_CUTOFF
    return knee, grid_around(knee, rate, scanned_cutoff(scans, floor), default_decimate)


def choose_processing(robot: rx90sym.Robot, recordings: Sequence[Any], processing: Processing | None = None,
                      base: Any = None, *, blocks: int = DEFAULT_BLOCKS, row_cap: int | None = DEFAULT_ROW_CAP,
                      time_cap: float | None = None, block: int = DEFAULT_BLOCK, client: Any = None,
                      policies: Sequence[str] = SCORED_REST, scans: Sequence[Scan] | None = None,
                      candidates: Sequence[Candidate] | None = None, offsets: Sequence[int] = ()) -> ProcessingChoice:
    """Score the candidate processings of ``recordings`` (recordings, files or block sources) and choose
    the lowest held-back error (module docstring; :mod:`identify.selection.cross_validation`).

    processing: what the choice leaves as the fit has it (None: the defaults,
    :class:`~identify.observation.processing.Processing`): its rest threshold and spring (the rows of W),
    its rest policy (one or one per joint, or None: open, chosen per joint among ``policies``, default
    :data:`~identify.selection.cross_validation.SCORED_REST`), its decimation (the default candidate's),
    its torque delay [s] (every candidate is scored with it, as the fit will use it; "auto" is refused:
    estimate it first, :func:`identify.estimate_delay`); its cut-off must be open (None). base: the
    columns (default: the symbolic base parameters). blocks: contiguous blocks (>= 2); row_cap: no cut-off
    is started once the candidates scored have processed that many observation rows (None: no cap; the
    first is always scored); time_cap [s]: the same on the wall clock, on request (None: off, the default:
    the choice then never depends on the machine's speed); block: raw samples per block core; client: a
    ``dask.distributed.Client`` running the blocks (None: here); scans: the recordings'
    :func:`scans_for_choice` when already made (the fit that follows reuses them); candidates: another
    grid (default: the knee's, :func:`grid_of_scans`); offsets: the joints (0-based) that may get a torque
    offset (:func:`identify.observation.offsets.offset_joints`): the chosen processing is scored again with
    an offset on each of them, and a joint keeps its offset where it clearly lowers that joint's held-back
    error (``ProcessingChoice.offsets``).
    """
    processing = processing if processing is not None else Processing()
    if processing.cutoff is not None:
        raise ValueError(f"choose_processing: the cut-off is given ({processing.cutoff:g} Hz): nothing to choose")
    if processing.delay == "auto":
        raise ValueError("choose_processing: the candidates are scored at the fit's torque delay: give it in seconds "
                         "(estimate it first: identify.estimate_delay)")
    if blocks < 2:
        raise ValueError(f"cross-validation needs at least 2 blocks, got {blocks}")
    sources = [block_source(r, robot) for r in recordings]
    base = base if base is not None else rx90sym.base_parameters(robot)
    scans = scans if scans is not None else scans_for_choice(sources, block)
    knee, grid = grid_of_scans(scans, processing.decimate_to)
    grid = list(candidates) if candidates is not None else grid
    span = raw_span(scans, grid, blocks, float(processing.delay))
    kept: dict = {}  # (cut-off, decimation, rest) -> RawFactors: the offsets are scored on the chosen one's
    context = _Context(robot, sources, scans, base, span, processing, block, client, kept)
    budget = Budget(robot.n * sum(g.samples for s in scans for g in s.segments), row_cap, time_cap)
    choice = select_processing(lambda cand: _score(cand, context), knee, grid, RAW, blocks, processing.min_velocity,
                               processing.rest, budget, policies)
    chosen = kept.get(_key(choice.chosen))
    offsets = tuple(j for j in offsets if j not in context.left_out)
    if not offsets or chosen is None:
        return choice
    return _with_offsets(choice, chosen, offsets, budget)


def _with_offsets(choice: ProcessingChoice, factors: RawFactors, offsets: tuple[int, ...],
                  budget: Budget) -> ProcessingChoice:
    """The choice with the torque offsets that clearly lower their joint's held-back error (the chosen
    processing scored with an offset on each joint allowed one, from its factors: no pass)."""
    free = Budget(budget.rows, None)
    inseparable = factors.inseparable_offsets(offsets)  # a model the fitted rows cannot solve is never chosen
    offsets = tuple(j for j in offsets if j not in inseparable)
    choice = replace(choice, inseparable_offsets=inseparable)
    if not offsets:
        return choice
    with_offsets = score_candidates(lambda c: factors.scores(offsets), [replace(choice.chosen, label="offsets")],
                                    time.perf_counter(), free)[0]
    if not with_offsets.per_block:
        return replace(choice, offset_candidate=with_offsets)
    kept = tuple(j for j in offsets if clearly_better(with_offsets, choice.chosen, j))
    if kept and kept != offsets:
        # The joints share the other parameters: the offsets kept are scored together, and dropped unless
        # that lowers the mean held-back error and stays clearly better on each of them.
        alone = score_candidates(lambda c: factors.scores(kept), [replace(choice.chosen, label="offsets kept")],
                                 time.perf_counter(), free)[0]
        if not (alone.per_block and alone.score < choice.chosen.score
                and all(clearly_better(alone, choice.chosen, j) for j in kept)):
            kept = ()
        with_offsets = alone
    elif kept and with_offsets.score >= choice.chosen.score:
        kept = ()
    return replace(choice, offsets=kept, offset_candidate=with_offsets)


def scans_for_choice(sources: Sequence[BlockSource], block: int) -> list[Scan]:
    """The first pass the choice needs (:func:`identify.observation.scan.scan` with the 2 Hz floor and
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


class _Context:
    """What every candidate's pass reads: the recordings, their scans, the columns, the raw samples
    scored, the fit's processing, and the factors kept per candidate."""

    def __init__(self, robot: rx90sym.Robot, sources: Sequence[BlockSource], scans: Sequence[Scan], base: Any,
                 span: RawSpan, processing: Processing, block: int, client: Any, kept: dict) -> None:
        self.robot, self.sources, self.scans, self.base, self.span = robot, sources, scans, base, span
        self.processing, self.block, self.client = processing, block, client
        self.kept = kept
        self.left_out = torque_left_out(scans)  # joints whose torque is constant: not fitted, not scored


def _key(cand: Candidate) -> tuple:
    return cand.cutoff, cand.decimate_to, cand.rest


def _score(cand: Candidate, ctx: _Context) -> tuple[float, tuple[float, ...], tuple[tuple[float, ...], ...]]:
    """(score, per joint, per held-back block and joint) of one candidate, relative errors in % against
    the raw measured torques, from one pass over the recordings; its factors kept in ``ctx.kept``."""
    threshold = ctx.processing.min_velocity if cand.rest is not None else None
    rest = cand.rest or "zero-coulomb"
    columns = presliding_base(ctx.robot, ctx.base, rest if threshold is not None else None)  # FPj with presliding
    processing = ctx.processing.chosen(cutoff=cand.cutoff, decimate_to=cand.decimate_to, min_velocity=threshold,
                                       rest=rest, delay=float(ctx.processing.delay))
    factors = column_factors(ctx.robot, ctx.sources, ctx.scans, columns, processing, ctx.span, ctx.block,
                             ctx.left_out, ctx.client)
    ctx.kept[_key(cand)] = factors
    return factors.scores()


def column_factors(robot: rx90sym.Robot, sources: Sequence[BlockSource], scans: Sequence[Scan], columns: Any,
                   processing: Processing, span: RawSpan, block: int, left_out: Sequence[int] = (),
                   client: Any = None) -> RawFactors:
    """The per-(time block, joint) factors of the fitted rows of ``columns`` made with ``processing`` (its
    cut-off chosen; ``left_out``: the joints whose torque is left out) and of the raw samples of ``span``
    they predict, from one pass over the recordings in blocks of ``block`` samples (a recording too short
    for the cut-off's edges left out)."""
    plans, notes = [], []
    for s in scans:  # a recording too short for this cut-off's edges is left out, as on whole recordings
        try:
            plans.append(plan_windows(s, processing, block)[0])
        except ValueError as exc:
            plans.append([])
            notes.append(str(exc))
    if not any(plans):
        raise ValueError(notes[0])
    drop = processing.min_velocity is not None and drops_rest(processing.rest)
    names = tuple(columns.names)
    factors = RawFactors(robot.n, len(names), span)
    if client is not None:  # the robot and its compiled columns sent once to each worker
        robot, columns = client.scatter([robot, columns], broadcast=True, hash=False)
    elif hasattr(columns, "regressor_workspace"):  # one reused buffer for the full-rate regressor, as in memory
        columns = SimpleNamespace(regressor_batch=columns.regressor_workspace().evaluate)
    index = {id(src): k for k, src in enumerate(sources)}
    tasks = ((robot, rec, window, plan, processing, columns, names, span,
              span.bounds.get((index[id(src)], plan.start)), drop, tuple(left_out))
             for src, (plan, window, rec, _) in _with_source(sources, plans))
    for parts in in_order(window_factors, tasks, client, 4 if client is not None else 1):
        factors.add(*parts)
    return factors


def _with_source(sources: Sequence[BlockSource], plans: Sequence[Sequence[Any]]) -> Any:
    """(source, (plan, window, raw samples, first)) of :func:`windows_in_order`, per source in order."""
    for src, src_plans in zip(sources, plans):
        for item in windows_in_order([src], [src_plans]):
            yield src, item
