"""Identification and prediction on logs of any length: the real-data fit streamed block by block.

:func:`fit_streamed` does what :func:`identify.fit` does (rest policy, torque-delay
estimate, one filtering, (weighted) least squares, optionally the consistent fit) plus the segment
bootstrap, without ever holding a full-rate array of a whole log: recordings are read in blocks
(:mod:`identify.io.blocks`), filtered in overlapping blocks (:mod:`identify.signal.blocks`), turned
into decimated rows block by block (:mod:`identify.observation.stream`) and folded into the
per-joint triangular factors (:mod:`identify.estimation.incremental_qr`) from which eqs. 9-15 follow.
Without a cut-off the processing is first chosen by blocked cross-validation, block by block too
(:mod:`identify.selection.processing_choice`).

With a Dask ``client`` every block is a task (filtering, regressor, parallel decimation and the
block's QR run on the workers); the client folds the factors in block order, so the result is the
serial one (the same operations in the same order).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Iterable, Sequence

import numpy as np

import rx90sym
from rx90sym.threads import one_blas_thread

from identify.estimation.bootstrap import BLOCK_S, DRAWS, SegmentBootstrap
from identify.estimation.incremental_qr import JointFactors, stacked_rows
from identify.estimation.compression import stack_systems
from identify.estimation.dependent_columns import ColumnReduction, reduce_columns
from identify.estimation.least_squares import joint_weights, solve_joint_systems
from identify.estimation.results import METHODS, IdentificationResult
from identify.io.blocks import BlockSource, block_source, check_block
from identify.selection.candidates import Candidate, DEFAULT_LABEL
from identify.selection.cross_validation import DEFAULT_BLOCKS, NoCandidateScored, ProcessingChoice, RAW
from identify.observation.matrix import DECIMATION_PASSBAND, DEFAULT_MIN_VELOCITY, DEFAULT_REST, Observation
from identify.observation.rest import presliding_base
from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.observation.offsets import offset_base
from identify.observation.processing import RestPolicy, drops_rest
from identify.observation.row_store import RowStore, keeps_rows
from identify.observation.stream import (DEFAULT_BLOCK, Piece, Plan, Scan, StreamSettings, in_order, piece,
                                         plan_windows, scan_all, scanned_cutoff, torque_left_out,
                                         windows_in_order)
from identify.selection.required_length import too_short
from identify.selection.processing_choice import KEEP_SECONDS, choose_processing_streamed, scans_for_choice
from identify.estimation.delay import DelayEstimate, delay_grid, joint_log_rms, refined_delay

__all__ = ["BootstrapSpec", "StreamedFit", "carry_choice", "estimate_delay", "fit_streamed"]


@dataclass(frozen=True)
class BootstrapSpec:
    """Segment bootstrap of the streamed fit: block length [s], draws, seed."""

    block_s: float = 0.5
    draws: int = 200
    seed: int = 0


@dataclass(frozen=True, eq=False)
class StreamedFit:
    """A fit on recordings read block by block.

    result: the identification; cutoff [Hz]; rate [Hz] after decimation; notes: decimation notes;
    sources: file names; samples: decimated samples used; moving_fraction: (n,) share of moving
    samples per joint (None without a rest threshold); delay_estimate (None when not estimated);
    delay [s] compensated; bootstrap_std: (c,) (None when not asked); bootstrap_block: samples per
    bootstrap block; settings: the processing; blocks: number of blocks processed; q_range: (2, n)
    smallest and largest position of each joint over the recordings [rad]; recordings: per recording
    its samples, segments, bridged samples and stale rows (:meth:`identify.observation.stream.Scan.layout`);
    choice: the cross-validated processing (a :class:`~identify.selection.cross_validation.ProcessingChoice`;
    None when the processing was given); columns: the base fitted; friction: the fit file's
    ``model.friction`` of the friction columns searched (None: none); reduction: the columns the fitted
    rows cannot separate, left out or merged (:func:`identify.estimation.dependent_columns.reduce_columns`;
    None: every column fitted).
    """

    result: IdentificationResult
    cutoff: float
    rate: float
    notes: tuple[str, ...]
    sources: tuple[str, ...]
    samples: int
    moving_fraction: np.ndarray | None
    delay_estimate: DelayEstimate | None
    delay: float
    bootstrap_std: np.ndarray | None
    bootstrap_block: int
    settings: StreamSettings
    blocks: int
    q_range: np.ndarray | None = None
    recordings: tuple[dict, ...] = ()
    choice: ProcessingChoice | None = None
    observation: Observation | None = None  # the decimated rows, when kept (identify.observation.row_store)
    scans: tuple[Scan, ...] = ()  # the first pass over each recording (the baseline's and checks' passes reuse it)
    columns: Any = None
    friction: dict | None = None
    bootstrap_draws: np.ndarray | None = None  # (draws, c) the bootstrap's refits (payload method 2 differences them)
    reduction: ColumnReduction | None = None  # the columns left out or merged (None: every column fitted)

    def summary(self) -> str:
        """What was fitted, in the manner of :meth:`identify.Observation.summary`."""
        lines = [f"{self.result.rows} equations, {len(self.result.names)} parameters, {self.samples} samples after "
                 f"decimation to {self.rate:g} Hz, {self.blocks} blocks of at most {self.settings.block} samples"]
        lines += [f"  {src}: cut-off {self.cutoff:.3g} Hz" for src in self.sources]
        if self.moving_fraction is not None:
            frac = " ".join(f"{100 * f:.0f}%" for f in self.moving_fraction)
            lines.append(f"  rest below {self.settings.min_velocity:g} rad/s ({self.settings.rest}); moving per joint: {frac}")
        return "\n".join(lines + [f"  note: {n}" for n in self.notes if n])

    def filtering(self, spring: bool = True) -> dict[str, Any]:
        """Keyword arguments of :func:`identify.predict` that reuse this processing."""
        s = self.settings
        return {"cutoff": self.cutoff, "decimate_to": s.decimate_to, "min_velocity": s.min_velocity,
                "delay": self.delay, "spring": spring}


def _block_task(robot: rx90sym.Robot, rec: Any, window: Any, plan: Any, cutoff: float, settings: StreamSettings,
                base: Any, names: Sequence[str], first: int, lags: Sequence[float]) -> tuple[Piece, list]:
    """One block: its decimated rows and, per joint, the triangular factor of ``[W_i | Y_i | Y_lags]``."""
    p = piece(robot, rec, window, plan, cutoff, settings, base.regressor_batch, names, first, lags)
    m = p.motion
    keep = m.rows(settings.min_velocity is not None and drops_rest(settings.rest))
    factors = []
    for j in range(m.Phi.shape[1]):
        rows = stacked_rows(m.Phi, [m.Y, *p.extra_Y], j, keep[:, j])
        factors.append((JointFactors.block_factor(rows), rows.shape[0]))
    return p, factors


def _tasks(robot: rx90sym.Robot, sources: Sequence[BlockSource], plans: Sequence[Sequence[Plan]], cutoff: float,
           settings: StreamSettings, base: Any, names: Sequence[str], lags: Sequence[float]) -> Iterable[tuple]:
    for plan, window, rec, first in windows_in_order(sources, plans):
        yield (robot, rec, window, plan, cutoff, settings, base, names, first, tuple(lags))


def _workers(client: Any) -> int:
    try:
        return max(1, len(client.scheduler_info().get("workers", {})))
    except Exception:  # a client that cannot say: two blocks in flight per assumed worker
        return 1


def _accumulate(robot: rx90sym.Robot, sources: Sequence[BlockSource], plans: Sequence[Any], cutoff: float,
                settings: StreamSettings, base: Any, lags: Sequence[float], client: Any,
                boot: SegmentBootstrap | None, store: RowStore | None = None) -> tuple[JointFactors, np.ndarray, int]:
    """The second pass: per-joint factors, moving-sample counts and the number of blocks (``store``: the
    decimated rows kept too)."""
    names = tuple(base.names)
    factors = JointFactors(robot.n, len(names), 1 + len(lags))
    moving = np.zeros(robot.n)
    drop = settings.min_velocity is not None and drops_rest(settings.rest)
    count = 0
    # On Dask the robot and its compiled regressor are sent once to each worker, not with every block.
    shared = client.scatter([robot, base], broadcast=True, hash=False) if client is not None else (robot, base)
    tasks = _tasks(shared[0], sources, plans, cutoff, settings, shared[1], names, lags)
    for p, block_factors in in_order(_block_task, tasks, client, 2 * _workers(client) if client is not None else 1):
        count += 1
        m = p.motion
        moving += m.moving.sum(axis=0)
        if store is not None:
            store.add(p)
        for j, (factor, rows) in enumerate(block_factors):
            factors.add_factor(j, factor, rows)
            if boot is not None:
                keep = m.rows(drop)[:, j]
                boot.add(j, p.first + np.flatnonzero(keep), m.Phi[keep, j, :], m.Y[keep, j])
    return factors, moving, count


def _plans(scans: Sequence[Any], cutoff: float, settings: StreamSettings) -> tuple[list[list[Plan]], tuple[str, ...]]:
    """The windows of every segment of every recording (per recording), and the notes naming the segments
    left out; recordings of different rates after decimation are refused."""
    planned = [plan_windows(s, cutoff, settings) for s in scans]
    rates = [p.rate for src_plans, _ in planned for p in src_plans]
    if max(rates) > min(rates) * (1 + 1e-3):
        raise ValueError(f"recordings have different rates after decimation: {', '.join(f'{r:g}' for r in rates)} Hz; "
                         f"give decimate_to")
    return [p for p, _ in planned], tuple(note for _, notes in planned for note in notes)


def _choose(robot: rx90sym.Robot, sources: Sequence[BlockSource], base: Any, cutoff: float | None,
            decimate_to: float | None, min_velocity: float | None, rest: RestPolicy | None, spring: bool, block: int,
            client: Any, delay: float, offsets: Sequence[int]) -> tuple[ProcessingChoice, list[Scan]]:
    """(the processing chosen by blocked cross-validation block by block, the scans it made: the fit
    that follows reuses that pass). Recordings too short for the blocks (:mod:`identify.selection.required_length`),
    or on which no candidate could be scored, get the fixed defaults, said in the choice's record."""
    if cutoff is not None:
        raise ValueError("a cut-off is given and cross_validate asks to choose one: give one of them")
    scans = scans_for_choice(sources, block)
    _left_out(robot, scans)
    columns = len(base.names) if base is not None else len(rx90sym.base_parameters(robot).names)
    why = too_short(scans, columns, decimate_to or None, DEFAULT_BLOCKS, delay)
    if why is None:
        try:
            return choose_processing_streamed(robot, sources, base, min_velocity or None, rest, spring,
                                              default_decimate=decimate_to or None, block=block, client=client,
                                              scans=scans, delay=delay, offsets=offsets), scans
        except NoCandidateScored as exc:
            why = f"no candidate processing could be scored ({exc})"
    floor = max(2.0, DECIMATION_PASSBAND * decimate_to) if decimate_to else 2.0
    fixed = Candidate(scanned_cutoff(scans, floor), decimate_to or None, DEFAULT_REST if rest is None else rest,
                      label=DEFAULT_LABEL)
    return ProcessingChoice((), fixed, fixed.cutoff, RAW, DEFAULT_BLOCKS, 0.0, skipped=why), scans


def _left_out(robot: rx90sym.Robot, scans: Sequence[Scan]) -> tuple[int, ...]:
    """The joints whose torque is left out (constant over a recording: not logged); an error when all are."""
    left = torque_left_out(scans)
    if len(left) == robot.n:
        raise ValueError(f"{', '.join(s.source for s in scans)}: every joint's torque holds one value on every sample "
                         f"(channels not logged): nothing to fit; log the joint torques, or the currents with gains")
    return left


@one_blas_thread()
def estimate_delay(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any = None, cutoff: float | None = None,
                   decimate_to: float | None = DEFAULT_DECIMATE_TO, spring: bool = True,
                   min_velocity: float | None = None, rest: RestPolicy = "drop", max_delay: float = 0.02,
                   steps: int = 41, block: int = DEFAULT_BLOCK, client: Any = None, convention: str | None = None,
                   gains: Any = None) -> DelayEstimate:
    """Torque-to-position lag [s] of ``recordings`` (recordings, files or block sources; one lag for all),
    within ±``max_delay`` s, read block by block: the torques shifted by each lag of a grid of ``steps``
    points (at least one sampling period apart) are extra right-hand sides of the per-joint factors, the
    best refined by a parabola (:mod:`identify.estimation.delay`). The filtering options are those of
    :func:`identify.observation_matrix` (cutoff None: the automatic cut-off).
    BLAS on one thread inside the call, the caller's count back after it (rx90sym.threads)."""
    if not (max_delay > 0 and np.isfinite(max_delay)):
        raise ValueError(f"max_delay must be a positive duration in s, got {max_delay!r}")
    sources = [block_source(r, robot, convention, gains) for r in recordings]
    columns = presliding_base(robot, base if base is not None else rx90sym.base_parameters(robot),
                              rest if min_velocity is not None else None)
    settings = StreamSettings(cutoff, decimate_to or None, min_velocity, rest, 0.0, spring, check_block(block))
    scans, fc = scan_all(sources, settings)
    settings = replace(settings, left_out=_left_out(robot, scans))  # a torque not logged: its rows out
    plans, _ = _plans(scans, fc, replace(settings, delay=max_delay))
    grid, step = delay_grid(max(1.0 / s.rate for s in scans), max_delay, steps)
    factors = _accumulate(robot, sources, plans, fc, settings, columns, grid, client, None)[0]
    return _lag_estimate(factors, grid, step)


def _lag_estimate(factors: JointFactors, grid: np.ndarray, step: float) -> DelayEstimate:
    """The lag of least cost on ``grid`` [s] (the torques shifted by each: right-hand sides 1.. of the
    factors), refined by a parabola."""
    return refined_delay(grid, np.array([joint_log_rms(factors.systems(k + 1)) for k in range(len(grid))]), step)


def fit_streamed(robot: rx90sym.Robot, recordings: Sequence[Any], method: str = "wls", base: Any = None,
                 cutoff: float | None = None, decimate_to: float | None = DEFAULT_DECIMATE_TO,
                 min_velocity: float | None = DEFAULT_MIN_VELOCITY, rest: RestPolicy | None = None,
                 delay: float | str = 0.0, spring: bool = True, estimate: bool = False,
                 block: int = DEFAULT_BLOCK, client: Any = None, bootstrap: BootstrapSpec | None = None,
                 convention: str | None = None, gains: Any = None, cross_validate: bool | None = None,
                 offsets: Sequence[int] = (), friction: Any = None) -> StreamedFit:
    """:func:`identify.fit` on recordings of any length, block by block.

    recordings: CSV paths (streamed), :class:`~identify.Recording` objects or
    :class:`~identify.io.blocks.BlockSource`; block: raw samples per block core (peak memory grows
    with it, not with the logs: docs/long-logs.md); client: a ``dask.distributed.Client`` to run the
    blocks on (None: here); bootstrap: also the segment-bootstrap σ; convention, gains: how CSV files
    are read; cross_validate: choose the cut-off, decimation and (``rest`` None) the rest policy per
    joint by blocked cross-validation, block by block
    (:func:`identify.selection.processing_choice.choose_processing_streamed`); None: whenever ``cutoff`` is
    None, as :class:`identify.Processing`; ``decimate_to`` is then the default candidate's. rest: None
    is open (chosen by the cross-validation, else zero-coulomb); offsets: the joints (0-based) the
    cross-validation may give a torque offset (the columns OFFj of those it keeps are fitted:
    :class:`identify.observation.offsets.OffsetBase`); the candidates are scored at ``delay`` (0 when
    "auto": the lag is searched after the choice); friction: ``friction(robot, sources, scans, cutoff,
    settings, base, client, choose=...)`` -> (columns, record) called once the torques are in step (the delay
    known; ``choose`` False where the processing's choice fell back on the fixed defaults: no friction
    choice either): the friction columns searched block by block (:mod:`identify.friction.fitted_columns`),
    then fitted. The other arguments are those of :func:`identify.fit`. An error raised once the processing
    is chosen carries the choice (:func:`carry_choice`: its ``processing_choice``, the table).
    """
    made: list[ProcessingChoice] = []
    try:
        return _fit_streamed(made, robot, recordings, method, base, cutoff, decimate_to, min_velocity, rest, delay,
                             spring, estimate, block, client, bootstrap, convention, gains, cross_validate, offsets,
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


def _fit_streamed(made: list, robot: rx90sym.Robot, recordings: Sequence[Any], method: str, base: Any,
                  cutoff: float | None, decimate_to: float | None, min_velocity: float | None, rest: RestPolicy | None,
                  delay: float | str, spring: bool, estimate: bool, block: int, client: Any,
                  bootstrap: BootstrapSpec | None, convention: str | None, gains: Any, cross_validate: bool | None,
                  offsets: Sequence[int], friction: Any) -> StreamedFit:
    """:func:`fit_streamed`, the processing choice appended to ``made`` once made."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if not (delay == "auto" or isinstance(delay, (int, float))):
        raise ValueError(f"delay must be 'auto' or a number of seconds, got {delay!r}")
    block = check_block(block)
    sources = [block_source(r, robot, convention, gains) for r in recordings]
    if gains is not None and sources and not any(s.holds_current for s in sources):
        raise ValueError(f"drive gains given, but no recording holds motor currents "
                         f"({', '.join(s.source for s in sources)}: joint torques): the gains would not be used")
    choice = scans = None
    if (cutoff is None) if cross_validate is None else cross_validate:
        # Scored at the lag the fit compensates; "auto": the lag estimated on the default processing first (W
        # and Y filtered alike, it hardly depends on the cut-off; one delay search, one pass).
        scored = (estimate_delay(robot, sources, base, None, decimate_to, spring, min_velocity or None,
                                 DEFAULT_REST if rest is None else rest, block=block, client=client).delay
                  if delay == "auto" else float(delay))
        choice, scans = _choose(robot, sources, base, cutoff, decimate_to, min_velocity, rest, spring, block,
                                client, scored, offsets)
        made.append(choice)
        cutoff, decimate_to, rest = choice.chosen.cutoff, choice.chosen.decimate_to, choice.chosen.rest or rest
        if choice.offsets:  # the torque offsets kept, as the whole-signal fit's columns
            base = offset_base(base if base is not None else rx90sym.base_parameters(robot), choice.offsets)
    rest = DEFAULT_REST if rest is None else rest
    base = presliding_base(robot, base, rest if min_velocity else None)  # FPj columns with "presliding"
    settings = StreamSettings(cutoff, decimate_to or None, min_velocity or None, rest,
                              0.0 if delay == "auto" else float(delay), spring, block)
    # Each segment's first and last seconds of times kept: the identified model's folds are cut on them.
    scans, fc = (scans, float(cutoff)) if scans is not None else scan_all(sources, settings, KEEP_SECONDS)
    settings = replace(settings, left_out=_left_out(robot, scans))  # a torque not logged: its rows out of W
    search = estimate or delay == "auto"
    plans, skipped = _plans(scans, fc, replace(settings, delay=0.02 if search else settings.delay))
    flat = [p for src_plans in plans for p in src_plans]
    grid, step = delay_grid(max(1.0 / s.rate for s in scans))
    lags = tuple(grid) if search else ()
    total = sum(p.samples for p in flat)
    bblock = max(1, int(round(bootstrap.block_s * flat[0].rate))) if bootstrap else 0

    def make_boot(spec: BootstrapSpec | None) -> SegmentBootstrap | None:
        return (SegmentBootstrap(total, max(1, int(round(spec.block_s * flat[0].rate))), robot.n, len(base.names),
                                 spec.draws, spec.seed) if spec else None)

    def make_store() -> RowStore | None:  # the decimated rows kept when few (of the columns fitted)
        return RowStore(base.names, drop) if keeps_rows(total, robot.n, len(base.names)) else None
    drop = settings.min_velocity is not None and drops_rest(settings.rest)
    found = record = None
    if lags or friction is None:
        boot, store = make_boot(bootstrap), make_store()
        factors, moving, count = _accumulate(robot, sources, plans, fc, settings, base, lags, client, boot, store)
    if lags:
        found = _lag_estimate(factors, grid, step)
    if delay == "auto":  # the torques put back in step
        settings = replace(settings, delay=found.delay)
    searched = base
    if friction is not None:
        # No friction choice where the processing's could not be made (the same blocks): the fixed form.
        base, record = friction(robot, sources, scans, fc, settings, base, client,
                                choose=choice is None or not choice.skipped)
    # A second pass with the torques in step, the friction columns (none when the first pass fitted these columns
    # at this delay: coulomb chosen, no presliding).
    if delay == "auto" or base is not searched or not (lags or friction is None):
        boot, store = make_boot(bootstrap), make_store()
        factors, moving, count = _accumulate(robot, sources, plans, fc, settings, base, (), client, boot, store)
    # Columns the fitted rows cannot separate (a joint that never moves, one that moves one way only, columns only a
    # left-out joint's rows see): left out or merged, never refused (identify.estimation.dependent_columns).
    # The weights of eq. 11 from every column (each joint's own fit: the same without the columns left out).
    systems = factors.systems(0)
    weights = joint_weights(systems) if method != "ols" else None
    reduction = reduce_columns(stack_systems(systems).R, base.names,
                               also=() if weights is None else (stack_systems(systems, weights).R,))
    kept = None if reduction.full else list(reduction.kept)
    fitted = factors if kept is None else factors.subset(kept)
    # The (weighted) least squares of eqs. 9-15; the identified model is made from them by the fit (identify.fit).
    result = solve_joint_systems(fitted.systems(0), reduction.kept_names, weighted=method != "ols", weights=weights)
    if reduction.merged:
        result = replace(result, holds=tuple(reduction.holds().items()))
    notes = tuple(p.note for p in flat) + skipped
    observation = None if store is None else store.observation(
        [fc] * len(flat), [p.rate for p in flat], [p.source for p in flat], notes, settings.min_velocity, settings.rest,
        kept)
    draws = boot.estimates(result.weights, kept) if boot is not None else None
    return StreamedFit(result, fc, flat[0].rate, notes, tuple(s.source for s in scans), total,
                       moving / total if settings.min_velocity is not None else None, found, settings.delay,
                       None if draws is None else np.nanstd(draws, axis=0, ddof=1), bblock, settings, count,
                       np.vstack([np.min([s.q_range[0] for s in scans], axis=0),
                                  np.max([s.q_range[1] for s in scans], axis=0)]),
                       tuple(s.layout() for s in scans), choice, observation, tuple(scans), base, record, draws,
                       None if reduction.full else reduction)
