"""Empty and loaded runs read, filtered and turned into decimated motions block by block: the pipeline of
the section-IV methods (payloads, drive gains) on logs of any length and any number of segments.

:func:`open_runs` makes the first pass over every run (:func:`identify.observation.scan.scan`: the
blocks checked, the rate, the segments, the spectrum of the automatic cut-off), pairs the segments of
paired runs (:func:`identify.signal.pairing.pair_runs`: segment k of an empty run with segment k of its
loaded run) and plans the windows of every segment (:func:`identify.observation.block_rows.plan_windows`);
:func:`run_blocks` then yields each window's motion through :func:`identify.observation.block_rows.piece`,
the rows :func:`identify.fit` makes of one processing (cut-off, decimation, rest policy, delay) — for a
pair, the loaded run on the empty run's time stamps beside the empty run, filtered alike — here or on
Dask (:func:`identify.observation.block_rows.in_order`), in order. Memory: one block of each run; a run held
in memory is one block when it fits in one.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Iterator, Sequence

import numpy as np

import rx90sym

from rx90sym.parameters import PAYLOAD_NAMES
from rx90sym.recording import Recording

from identify.io.blocks import DEFAULT_BLOCK, BlockSource, block_source, check_block
from identify.io.gains import DriveGains
from identify.observation.block_rows import Plan, in_order, piece, plan_windows
from identify.observation.matrix import DECIMATION_PASSBAND, FilteredMotion, column_regressor
from identify.observation.processing import Processing
from identify.observation.scan import Scan, SegmentScan, scan, scanned_cutoff
from identify.signal.pairing import PairedRuns, on_empty_grid, pair_runs

__all__ = ["RunBlock", "RunColumns", "Runs", "open_runs", "run_blocks", "run_sources"]

@dataclass(frozen=True, eq=False)
class RunBlock:
    """One window's decimated motion (its core): ``loaded`` whether of a loaded run (a pair: True),
    ``motion`` its :class:`~identify.observation.matrix.FilteredMotion`, ``empty`` the paired empty run's
    motion on the same samples (None: not paired), ``first`` the index of its first sample among the
    samples of every motion (the segment bootstrap's blocks)."""

    loaded: bool
    motion: FilteredMotion
    empty: FilteredMotion | None
    first: int


@dataclass(frozen=True, eq=False)
class _Group:
    """The windows of one run (``source``), or of one pair (the empty run's windows; ``partner`` the
    loaded run, ``pairs`` its pairs by the first raw sample of each common part)."""

    loaded: bool
    source: BlockSource
    plans: tuple[Plan, ...]
    partner: BlockSource | None = None
    pairs: dict | None = None


@dataclass(frozen=True, eq=False)
class Runs:
    """Runs opened for the block pipeline: ``scans`` (empty runs', then loaded runs'), the ``processing``
    (its one cut-off [Hz] chosen), raw samples per ``block``, ``pairs`` (one per segment of every pair; ()
    when not paired), ``rate`` [Hz] after decimation, ``samples`` the decimated samples of every motion,
    ``notes`` (decimation; segments too short to filter, left out)."""

    empty_scans: tuple[Scan, ...]
    loaded_scans: tuple[Scan, ...]
    processing: Processing
    block: int
    pairs: tuple[PairedRuns, ...]
    rate: float
    samples: int
    notes: tuple[str, ...]
    groups: tuple[_Group, ...]

    @property
    def cutoff(self) -> float:
        """The cut-off every run is filtered at [Hz]."""
        return float(self.processing.cutoff)

    @property
    def q_range(self) -> np.ndarray:
        """(2, n) smallest and largest position of each joint over the loaded runs [rad]."""
        ranges = [s.q_range for s in self.loaded_scans]
        return np.vstack([np.min([r[0] for r in ranges], axis=0), np.max([r[1] for r in ranges], axis=0)])


class RunColumns:
    """The columns of a run's motion: ``base``'s (None: none), the payload's ten (``payload``: XXc ... Mc,
    link n's columns of the standard regressor, eq. 21) and the spring torque as a last column
    (``spring`` True; False: a column of zeros; None: no such column), in that order; none at all
    (torques only) is a valid choice. Called as a regressor, (Q, QD, QDD) -> (S, n, c). A symbolic
    base is read off the standard regressor with the payload's columns (one evaluation); other
    columns (torque offsets, friction forms of a fit) are evaluated beside them. Picklable (a Dask
    task carries it): the compiled workspaces are made where it is called."""

    def __init__(self, robot: rx90sym.Robot, base: Any = None, payload: bool = True, spring: bool | None = None):
        self.robot, self.base, self.payload, self.spring = robot, base, payload, spring
        self.names = ((tuple(base.names) if base is not None else ()) + (PAYLOAD_NAMES if payload else ())
                      + (() if spring is None else ("spring",)))
        self._parts: list | None = None

    def __getstate__(self) -> dict:
        return {**self.__dict__, "_parts": None}

    def _make(self) -> list:
        robot, base = self.robot, self.base
        payload = [robot.parameter_names[i] for i in rx90sym.payload_regressor_columns(robot)] if self.payload else []
        if base is None or hasattr(base, "independent"):
            standard = [robot.parameter_names[i] for i in getattr(base, "independent", ())] + payload
            parts = [column_regressor(robot, columns=standard)[1]] if standard else []
        else:
            parts = [column_regressor(robot, base)[1]] + ([column_regressor(robot, columns=payload)[1]] if payload else [])
        if self.spring is not None:
            on = self.spring
            parts.append(lambda Q, QD, QDD: robot.spring_torque_batch(Q)[:, :, :1] if on
                         else np.zeros((len(Q), robot.n, 1)))
        return parts

    def __call__(self, Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray) -> np.ndarray:
        if self._parts is None:
            self._parts = self._make()
        if not self._parts:
            return np.zeros(np.shape(Q) + (0,))
        if len(self._parts) == 1:
            return self._parts[0](Q, QD, QDD)
        return np.concatenate([p(Q, QD, QDD) for p in self._parts], axis=2)


def run_sources(robot: rx90sym.Robot, runs: Sequence[Any], what: str, convention: str | None,
             gains: DriveGains | None) -> list[BlockSource]:
    """Block sources of ``runs`` (recordings, files or sources; ``what``: "empty" or "loaded", named by the
    refusal of a recording of another robot)."""
    out = []
    for run in runs:
        if isinstance(run, Recording):
            if run.q.shape[1] != robot.n:
                raise ValueError(f"{what} recording {run.source}: {run.q.shape[1]} joints, robot "
                                 f"{robot.name!r} has {robot.n}")
            if run.robot and run.robot != robot.name:
                raise ValueError(f"{what} recording {run.source} is of robot {run.robot!r}, not {robot.name!r}")
        out.append(block_source(run, robot, convention, gains))
    return out


def _common_parts(s: Scan, pairs: Sequence[PairedRuns]) -> Scan:
    """The scan of an empty run restricted to the common part of each of its segments with its pair."""
    segments = tuple(SegmentScan(p.span[0], p.samples, g.rate, None) for p, g in zip(pairs, s.segments))
    return Scan(s.source, s.samples, s.rate, segments, s.q_range, s.bridged, s.log)


def open_runs(robot: rx90sym.Robot, empty: Sequence[Any], loaded: Sequence[Any], processing: Processing,
              block: int = DEFAULT_BLOCK, *, paired: bool = False, position_tol: float = 0.02,
              instead: str = "--method 4", convention: str | None = None, gains: DriveGains | None = None) -> Runs:
    """The first pass over the runs (recordings, CSV files or block sources, read ``block`` raw samples at a
    time) and their windows.

    processing: the rows' (cut-off None: the automatic one, identify's rule on every run: the largest
    position-spectrum cut-off over the segments, at least 0.4 x ``decimate_to``; paired runs: on the
    loaded runs with the spectrum's own 2 Hz floor, both runs of a pair filtered alike); paired: run i of
    ``empty`` with run i of ``loaded``, segment by segment (:func:`identify.signal.pairing.pair_runs`,
    ``position_tol`` [rad], ``instead``: the method that needs no pairing); convention, gains: how files
    are read (gains: currents into torques).
    """
    block = check_block(block)
    src_e = run_sources(robot, empty, "empty", convention, gains)
    src_l = run_sources(robot, loaded, "loaded", convention, gains)
    if paired and len(src_e) != len(src_l):
        raise ValueError(f"paired runs: each loaded run is the same motion run empty: got {len(src_e)} empty and "
                         f"{len(src_l)} loaded recordings ({instead} takes any number of each)")
    need = processing.cutoff is None
    floor = (2.0 if paired else max(2.0, DECIMATION_PASSBAND * processing.decimate_to) if processing.decimate_to
             else 2.0) if need else None
    scans_e = [scan(s, block, None if paired else floor) for s in src_e]
    scans_l = [scan(s, block, floor) for s in src_l]
    if need:
        processing = processing.chosen(cutoff=scanned_cutoff(scans_l if paired else scans_e + scans_l, floor))
    groups, pairs, notes = [], [], []
    if paired:
        for se, sl, e, l in zip(scans_e, scans_l, src_e, src_l):
            found = pair_runs(e, l, position_tol, instead=instead, block=block,
                              segments=([(g.start, g.samples) for g in se.segments],
                                        [(g.start, g.samples) for g in sl.segments]))
            plans, skipped = plan_windows(_common_parts(se, found), processing, block)
            groups.append(_Group(True, e, tuple(plans), l, {p.span[0]: p for p in found}))
            pairs += found
            notes += skipped
    else:
        for loaded_run, srcs, scans in ((False, src_e, scans_e), (True, src_l, scans_l)):
            for src, s in zip(srcs, scans):
                plans, skipped = plan_windows(s, processing, block)
                groups.append(_Group(loaded_run, src, tuple(plans)))
                notes += skipped
    rates = [p.rate for g in groups for p in g.plans]
    if max(rates) > min(rates) * (1 + 1e-3):
        raise ValueError(f"recordings have different rates after decimation: {', '.join(f'{r:g}' for r in rates)} "
                         f"Hz; give decimate_to")
    notes = tuple(dict.fromkeys(p.note for g in groups for p in g.plans if p.note)) + tuple(notes)
    return Runs(tuple(scans_e), tuple(scans_l), processing, block, tuple(pairs), rates[0],
                sum(p.samples for g in groups for p in g.plans), notes, tuple(groups))


def _task(robot: rx90sym.Robot, loaded: bool, rec: Recording, partner: Recording | None, pair: PairedRuns | None,
          window: Any, plan: Plan, processing: Processing, columns: dict[str, RunColumns],
          first: int, reduce: Callable[[RunBlock], Any] | None) -> Any:
    """One window through :func:`identify.observation.block_rows.piece` (a pair: both runs on the empty run's
    samples), reduced by ``reduce`` where it runs (a Dask worker)."""
    def motion(r: Recording, role: str) -> FilteredMotion:
        return piece(robot, r, window, plan, processing, columns[role], columns[role].names, first).motion

    if pair is not None:
        block = RunBlock(True, motion(on_empty_grid(pair, rec, partner), "loaded"), motion(rec, "empty"),
                         first + window.core[0])
    else:
        block = RunBlock(loaded, motion(rec, "loaded" if loaded else "empty"), None, first + window.core[0])
    return block if reduce is None else reduce(block)


def _arguments(robot: rx90sym.Robot, runs: Runs, columns: dict[str, RunColumns],
               reduce: Callable[[RunBlock], Any] | None) -> Iterator[tuple]:
    first = 0
    for g in runs.groups:
        items = [(plan, window) for plan in g.plans for window in plan.windows]
        spans = [span for plan in g.plans for span in plan.spans]
        recs = g.source.windows(spans)
        if g.partner is not None:
            owner = [g.pairs[plan.start] for plan in g.plans for _ in plan.windows]
            partner = g.partner.windows([p.loaded_span(*s) for p, s in zip(owner, spans)])
        starts, at = {}, first
        for plan in g.plans:
            starts[id(plan)], at = at, at + plan.samples
        for k, ((plan, window), rec) in enumerate(zip(items, recs)):
            pair = owner[k] if g.partner is not None else None
            other = next(partner) if g.partner is not None else None
            yield (robot, g.loaded, rec, other, pair, window, plan, runs.processing, columns,
                   starts[id(plan)], reduce)
        first = at


def run_blocks(robot: rx90sym.Robot, runs: Runs, columns: dict[str, RunColumns],
               reduce: Callable[[RunBlock], Any] | None = None, client: Any = None) -> Iterator[Any]:
    """Every window of every run in order, as a :class:`RunBlock` (or ``reduce(block)``, computed where
    the block is: on a Dask worker with ``client``); ``columns``: the columns of the empty and of the
    loaded runs' motions (keys "empty", "loaded"; a pair's runs)."""
    return in_order(_task, _arguments(robot, runs, columns, reduce), client, 2 if client is not None else 1)
