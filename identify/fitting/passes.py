"""The fit's passes over the logs, block by block, for every log length.

:func:`run_passes` does what :func:`identify.fit` needs of the recordings (the processing chosen where it
is open, the torque-delay estimate, one filtering, (weighted) least squares) plus the segment bootstrap,
without ever holding a full-rate array of a whole log: recordings are read in blocks
(:mod:`identify.io.blocks`), scanned (:mod:`identify.observation.scan`), turned into decimated rows block
by block with the fit's one :class:`~identify.observation.processing.Processing`
(:mod:`identify.observation.block_rows`) and folded into the per-joint triangular factors
(:mod:`identify.estimation.joint_factors`) from which eqs. 9-15 follow. Where the processing is open
(no cut-off) it is first chosen by blocked cross-validation, block by block too
(:mod:`identify.selection.processing_choice`).

With a Dask ``client`` every block is a task (filtering, regressor, parallel decimation and the
block's QR run on the workers); the client folds the factors in block order, so the result is the
serial one (the same operations in the same order).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.estimation.bootstrap import SegmentBootstrap
from identify.estimation.compression import stack_systems
from identify.estimation.delay import DelayEstimate, delay_grid, estimate_delay, lag_estimate
from identify.estimation.dependent_columns import ColumnReduction, reduce_columns
from identify.estimation.joint_factors import joint_factors, plans_of
from identify.estimation.least_squares import joint_weights, solve_joint_systems
from identify.estimation.results import METHODS, IdentificationResult
from identify.io.blocks import DEFAULT_BLOCK, BlockSource, block_source, check_block
from identify.observation.matrix import DECIMATION_PASSBAND, Observation
from identify.observation.offsets import offset_base
from identify.observation.processing import DEFAULT_REST, Processing, drops_rest
from identify.observation.rest import presliding_base
from identify.observation.row_store import RowStore, keeps_rows
from identify.observation.scan import Scan, scan_all, scanned_cutoff, torque_left_out
from identify.selection.candidates import DEFAULT_LABEL, Candidate
from identify.selection.candidates import ProcessingChoice
from identify.selection.cross_validation import DEFAULT_BLOCKS, RAW, NoCandidateScored
from identify.selection.processing_choice import KEEP_SECONDS, choose_processing, scans_for_choice
from identify.selection.required_length import too_short

__all__ = ["BootstrapSpec", "Passes", "carry_choice", "run_passes"]


@dataclass(frozen=True)
class BootstrapSpec:
    """Segment bootstrap of the fit's passes: block length [s], draws, seed."""

    block_s: float = 0.5
    draws: int = 200
    seed: int = 0


@dataclass(frozen=True, eq=False)
class Passes:
    """What the fit's passes over the recordings read, chose and fitted.

    result: the identification; processing: the one the rows were made with (its cut-off [Hz],
    decimation, rest policy and torque delay [s] chosen); rate [Hz] after decimation; notes: decimation
    notes; sources: file names; samples: decimated samples used; moving_fraction: (n,) share of moving
    samples per joint (None without a rest threshold); delay_estimate (None when not estimated);
    bootstrap_std: (c,) (None when not asked); bootstrap_block: samples per bootstrap block; block: raw
    samples per block; blocks: number of blocks processed; left_out: the joints (0-based) whose torque
    was left out (constant: not logged); q_range: (2, n) smallest and largest position of each joint over
    the recordings [rad]; recordings: per recording its samples, segments, bridged samples and stale rows
    (:meth:`identify.observation.scan.Scan.layout`); choice: the cross-validated processing (a
    :class:`~identify.selection.candidates.ProcessingChoice`; None when the processing was given); columns:
    the base fitted; friction: the fit file's ``model.friction`` of the friction columns searched (None:
    none); reduction: the columns the fitted rows cannot separate, left out or merged
    (:func:`identify.estimation.dependent_columns.reduce_columns`; None: every column fitted).
    """

    result: IdentificationResult
    processing: Processing
    rate: float
    notes: tuple[str, ...]
    sources: tuple[str, ...]
    samples: int
    moving_fraction: np.ndarray | None
    delay_estimate: DelayEstimate | None
    bootstrap_std: np.ndarray | None
    bootstrap_block: int
    block: int
    blocks: int
    left_out: tuple[int, ...] = ()
    q_range: np.ndarray | None = None
    recordings: tuple[dict, ...] = ()
    choice: ProcessingChoice | None = None
    observation: Observation | None = None  # the decimated rows, when kept (identify.observation.row_store)
    scans: tuple[Scan, ...] = ()  # the first pass over each recording (the baseline's and checks' passes reuse it)
    columns: Any = None
    friction: dict | None = None
    bootstrap_draws: np.ndarray | None = None  # (draws, c) the bootstrap's refits (payload method 2 differences them)
    reduction: ColumnReduction | None = None  # the columns left out or merged (None: every column fitted)

    @property
    def cutoff(self) -> float:
        """The cut-off the rows were filtered at [Hz]."""
        return float(self.processing.cutoff)

    @property
    def delay(self) -> float:
        """The torque delay compensated [s]."""
        return float(self.processing.delay)

    def summary(self) -> str:
        """What was fitted, in the manner of :meth:`identify.Observation.summary`."""
        p = self.processing
        lines = [f"{self.result.rows} equations, {len(self.result.names)} parameters, {self.samples} samples after "
                 f"decimation to {self.rate:g} Hz, {self.blocks} blocks of at most {self.block} samples"]
        lines += [f"  {src}: cut-off {self.cutoff:.3g} Hz" for src in self.sources]
        if self.moving_fraction is not None:
            frac = " ".join(f"{100 * f:.0f}%" for f in self.moving_fraction)
            lines.append(f"  rest below {p.min_velocity:g} rad/s ({p.rest}); moving per joint: {frac}")
        return "\n".join(lines + [f"  note: {n}" for n in self.notes if n])

    def filtering(self, spring: bool = True) -> dict[str, Any]:
        """Keyword arguments of :func:`identify.predict` that reuse this processing."""
        p = self.processing
        return {"cutoff": self.cutoff, "decimate_to": p.decimate_to, "min_velocity": p.min_velocity,
                "delay": self.delay, "spring": spring}


def _choose(robot: rx90sym.Robot, sources: Sequence[BlockSource], columns: Any, processing: Processing, block: int,
            client: Any, delay: float, offsets: Sequence[int]) -> tuple[ProcessingChoice, list[Scan]]:
    """(the processing chosen by blocked cross-validation block by block, the scans it made: the fit
    that follows reuses that pass). Recordings too short for the blocks (:mod:`identify.selection.required_length`),
    or on which no candidate could be scored, get the fixed defaults, said in the choice's record."""
    scans = scans_for_choice(sources, block)
    torque_left_out(scans, robot.n)
    width = len(columns.names) if columns is not None else len(rx90sym.base_parameters(robot).names)
    decimate_to = processing.decimate_to
    why = too_short(scans, width, decimate_to, DEFAULT_BLOCKS, delay)
    if why is None:
        try:
            return choose_processing(robot, sources, processing.chosen(delay=delay), columns, block=block,
                                     client=client, scans=scans, offsets=offsets), scans
        except NoCandidateScored as exc:
            why = f"no candidate processing could be scored ({exc})"
    floor = max(2.0, DECIMATION_PASSBAND * decimate_to) if decimate_to else 2.0
    rest = DEFAULT_REST if processing.rest is None else processing.rest
    fixed = Candidate(scanned_cutoff(scans, floor), decimate_to, rest, label=DEFAULT_LABEL)
    return ProcessingChoice((), fixed, fixed.cutoff, RAW, DEFAULT_BLOCKS, 0.0, skipped=why), scans


def run_passes(robot: rx90sym.Robot, sources: Sequence[BlockSource], processing: Processing, method: str = "wls",
               columns: Any = None, *, block: int = DEFAULT_BLOCK, client: Any = None,
               bootstrap: BootstrapSpec | None = None, offsets: Sequence[int] = (), friction: Any = None) -> Passes:
    """The passes of :func:`identify.fit` over ``sources`` (:func:`identify.io.blocks.block_source` of the
    recordings, or recordings in memory) with ``processing``: open (no cut-off, or ``cross_validate``), the cut-off, the decimation and
    (``rest`` None) the rest policy per joint are chosen first by blocked cross-validation, block by block
    (:func:`identify.selection.processing_choice.choose_processing`), the candidates scored at the
    processing's delay (0 when "auto": the lag is searched after the choice); rest None is open (chosen by
    the cross-validation, else zero-coulomb). columns: the base fitted (None: the symbolic base
    parameters); block: raw samples per block core (peak memory grows with it, not with the logs:
    docs/long-logs.md); client: a ``dask.distributed.Client`` running the blocks (None: here); bootstrap:
    also the segment-bootstrap σ; offsets: the joints (0-based) the cross-validation may give a torque
    offset (the columns OFFj of those it keeps are fitted: :class:`identify.observation.offsets.OffsetBase`);
    friction: ``friction(robot, sources, scans, processing, block, left_out, columns, client, choose=...)`` ->
    (columns, record), called once the torques are in step (the delay known; ``choose`` False where the
    processing's choice fell back on the fixed defaults: no friction choice either): the friction columns
    searched block by block (:class:`identify.friction.fitted_columns.FrictionHook`), then fitted. An error
    raised once the processing is chosen carries the choice (:func:`carry_choice`: its
    ``processing_choice``, the table).
    """
    made: list[ProcessingChoice] = []
    sources = [block_source(r, robot) for r in sources]  # the sources given, or recordings in memory
    try:
        return _run(made, robot, sources, processing, method, columns, check_block(block), client, bootstrap, offsets,
                    friction)
    except Exception as exc:
        carry_choice(exc, made[0] if made else None)
        raise


def carry_choice(exc: BaseException, choice: ProcessingChoice | None) -> BaseException:
    """``exc`` with the processing ``choice`` made before it as its attribute ``processing_choice`` (when
    it has none: the first choice made), for a caller to show the candidate table of a fit that then
    stopped (``rx90 identify`` prints it before the error)."""
    if choice is not None and getattr(exc, "processing_choice", None) is None:
        exc.processing_choice = choice  # type: ignore[attr-defined]
    return exc


def _run(made: list, robot: rx90sym.Robot, sources: Sequence[BlockSource], processing: Processing, method: str,
         columns: Any, block: int, client: Any, bootstrap: BootstrapSpec | None, offsets: Sequence[int],
         friction: Any) -> Passes:
    """:func:`run_passes`, the processing choice appended to ``made`` once made."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    auto = processing.delay == "auto"
    choice = scans = None
    if processing.cross_validates:
        # Scored at the lag the fit compensates; "auto": the lag estimated on the default processing first (W
        # and Y filtered alike, it hardly depends on the cut-off; one delay search, one pass).
        scored = (estimate_delay(robot, sources, processing, columns, block=block, client=client).delay if auto
                  else float(processing.delay))
        choice, scans = _choose(robot, sources, columns, processing, block, client, scored, offsets)
        made.append(choice)
        c = choice.chosen
        processing = processing.chosen(cutoff=c.cutoff, decimate_to=c.decimate_to, rest=c.rest or processing.rest)
        if choice.offsets:  # the torque offsets kept, as the whole-signal fit's columns
            columns = offset_base(columns if columns is not None else rx90sym.base_parameters(robot), choice.offsets)
    processing = processing.chosen(rest=DEFAULT_REST if processing.rest is None else processing.rest,
                                   delay=0.0 if auto else float(processing.delay))
    columns = presliding_base(robot, columns, processing.rest if processing.min_velocity else None)
    # Each segment's first and last seconds of times kept: the identified model's folds are cut on them.
    if scans is None:
        scans, processing = scan_all(sources, processing, block, KEEP_SECONDS)
    left_out = torque_left_out(scans, robot.n)  # a torque not logged: its rows out of W
    search = processing.estimate_delay or auto
    plans, skipped = plans_of(scans, processing.chosen(delay=0.02) if search else processing, block)
    flat = [p for src_plans in plans for p in src_plans]
    grid, step = delay_grid(max(1.0 / s.rate for s in scans))
    lags = tuple(grid) if search else ()
    total = sum(p.samples for p in flat)
    bblock = max(1, int(round(bootstrap.block_s * flat[0].rate))) if bootstrap else 0
    drop = processing.min_velocity is not None and drops_rest(processing.rest)

    def make_boot(spec: BootstrapSpec | None) -> SegmentBootstrap | None:
        return (SegmentBootstrap(total, max(1, int(round(spec.block_s * flat[0].rate))), robot.n, len(columns.names),
                                 spec.draws, spec.seed) if spec else None)

    def make_store() -> RowStore | None:  # the decimated rows kept when few (of the columns fitted)
        return RowStore(columns.names, drop) if keeps_rows(total, robot.n, len(columns.names)) else None

    found = record = None
    if lags or friction is None:
        boot, store = make_boot(bootstrap), make_store()
        factors, moving, count = joint_factors(robot, sources, plans, processing, columns, lags, left_out, client,
                                               boot, store)
    if lags:
        found = lag_estimate(factors, grid, step)
    if auto:  # the torques put back in step
        processing = processing.chosen(delay=found.delay)
    searched = columns
    if friction is not None:
        # No friction choice where the processing's could not be made (the same blocks): the fixed form.
        columns, record = friction(robot, sources, scans, processing, block, left_out, columns, client,
                                   choose=choice is None or not choice.skipped)
    # A second pass with the torques in step, the friction columns (none when the first pass fitted these columns
    # at this delay: coulomb chosen, no presliding).
    if auto or columns is not searched or not (lags or friction is None):
        boot, store = make_boot(bootstrap), make_store()
        factors, moving, count = joint_factors(robot, sources, plans, processing, columns, (), left_out, client,
                                               boot, store)
    # Columns the fitted rows cannot separate (a joint that never moves, one that moves one way only, columns only a
    # left-out joint's rows see): left out or merged, never refused (identify.estimation.dependent_columns).
    # The weights of eq. 11 from every column (each joint's own fit: the same without the columns left out).
    systems = factors.systems(0)
    weights = joint_weights(systems) if method != "ols" else None
    reduction = reduce_columns(stack_systems(systems).R, columns.names,
                               also=() if weights is None else (stack_systems(systems, weights).R,))
    kept = None if reduction.full else list(reduction.kept)
    fitted = factors if kept is None else factors.subset(kept)
    # The (weighted) least squares of eqs. 9-15; the identified model is made from them by the fit (identify.fit).
    result = solve_joint_systems(fitted.systems(0), reduction.kept_names, weighted=method != "ols", weights=weights)
    if reduction.merged:
        result = replace(result, holds=tuple(reduction.holds().items()))
    notes = tuple(p.note for p in flat) + skipped
    observation = None if store is None else store.observation(
        [processing.cutoff] * len(flat), [p.rate for p in flat], [p.source for p in flat], notes,
        processing.min_velocity, processing.rest, kept)
    draws = boot.estimates(result.weights, kept) if boot is not None else None
    return Passes(result, processing, flat[0].rate, notes, tuple(s.source for s in scans), total,
                  moving / total if processing.min_velocity is not None else None, found,
                  None if draws is None else np.nanstd(draws, axis=0, ddof=1), bblock, block, count, left_out,
                  np.vstack([np.min([s.q_range[0] for s in scans], axis=0),
                             np.max([s.q_range[1] for s in scans], axis=0)]),
                  tuple(s.layout() for s in scans), choice, observation, tuple(scans), columns, record, draws,
                  None if reduction.full else reduction)
