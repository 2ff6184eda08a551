"""The second pass over a log read block by block: each block's decimated rows (eqs. 6-8 and 20 without the
whole log in memory).

After the first pass (:mod:`identify.observation.scan`), :func:`plan_windows` cuts every segment into the
blocks of :func:`identify.signal.blocks.motion_windows` (core plus margins from the filters' impulse
responses), and :func:`piece` takes each through :func:`identify.observation.matrix.filtered_motion`
with the fit's one :class:`~identify.observation.processing.Processing`, exactly as a whole recording,
cut back to its core: a :class:`Piece` of decimated rows. The filters restart at each segment and no
window spans two; a sample bridged over lost packets (``measured`` 0) runs through the filters but its
row is left out (:meth:`identify.observation.matrix.FilteredMotion.rows`).

Peak memory is that of one block: the full-rate regressor of a block with its margins,
(block + 2·margin) × n × c doubles, and its parallel-filtered copies (about three such arrays).
Every quantity downstream (incremental QR, bootstrap, validation) consumes pieces.
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace
from typing import Any, Callable, Iterable, Iterator, Sequence

import numpy as np

import rx90sym

from identify.io.blocks import BlockSource
from identify.observation.matrix import filtered_motion, shifted_torques
from identify.observation.processing import CROSSING_SECONDS, Processing, has_policy
from identify.observation.scan import Scan
from identify.signal.blocks import decimation_margin, lowpass_margin, motion_windows
from identify.signal.filtering import EDGE_PERIODS, decimate, decimation_plan

__all__ = ["DELAY_MARGIN", "Piece", "Plan", "in_order", "piece", "plan_windows", "windows_in_order"]


@dataclass(frozen=True)
class Plan:
    """How one segment of a recording is cut: its first raw sample ``start`` in the recording, the
    filter's edge and the decimation, the windows (in the segment's samples)."""

    source: str
    start: int
    edge: int
    factor: int
    rate: float
    note: str
    windows: tuple
    samples: int  # decimated samples of the segment's motion
    length: int = 0  # raw samples of the segment

    @property
    def spans(self) -> list[tuple[int, int]]:
        """The raw samples of each window, counted in the recording."""
        return [(self.start + w.raw[0], self.start + w.raw[1]) for w in self.windows]


#: Extra raw samples of margin for the torque shifts of the delay search (±20 ms at up to 2.5 kHz).
DELAY_MARGIN = 50


def plan_windows(s: Scan, processing: Processing, block: int) -> tuple[list[Plan], list[str]]:
    """The windows of every segment of one recording, of at most ``block`` samples each, for :func:`piece`
    with ``processing`` (its cut-off chosen; margins from the filters' impulse responses), and notes naming
    the segments too short for the filters' edges (left out, as
    :func:`identify.observation.matrix.filtered_motions` does)."""
    cutoff = processing.cutoff
    plans, notes = [], []
    for k, g in enumerate(s.segments):
        edge = max(2, math.ceil(EDGE_PERIODS * g.rate / cutoff)) if g.samples > 1 else 2
        name = f"{s.source}#{k + 1}" if len(s.segments) > 1 else s.source
        if len(s.segments) > 1 and g.samples < 2 * edge + 5:
            notes.append(f"{name}: segment of {g.samples} samples left out (shorter than the {2 * edge + 5} the "
                         f"filter's edges need at {cutoff:.3g} Hz)")
            continue
        dplan = decimation_plan(g.rate, processing.decimate_to)
        factor = dplan.factor
        delay = processing.delay
        delay_samples = int(math.ceil(abs(delay) * g.rate)) + 1 if delay else 0
        lp = lowpass_margin(g.rate, cutoff) + delay_samples + DELAY_MARGIN
        if processing.min_velocity is not None and has_policy(processing.rest, "crossing"):
            # A rest run is a crossing when shorter than CROSSING_SECONDS: a run cut by a window's edge is then at
            # least that long inside it, and judged as the whole run is.
            lp += int(math.ceil(CROSSING_SECONDS * g.rate)) + 1
        windows = motion_windows(g.samples, edge, factor, block, lp, decimation_margin(factor))
        plans.append(Plan(name, g.start, edge, factor, dplan.rate, dplan.note, tuple(windows), windows[-1].core[1],
                          g.samples))
    if not plans:
        raise ValueError("no segment is long enough to filter: " + "; ".join(notes))
    return plans, notes


@dataclass(frozen=True, eq=False)
class Piece:
    """The decimated rows of one block's core: ``motion`` (a FilteredMotion cut to the core),
    ``first`` the index of its first sample in the motion of all recordings, ``extra_Y`` the torques
    shifted by each lag asked (delay search), each (S, n)."""

    motion: Any
    first: int
    extra_Y: tuple[np.ndarray, ...] = ()


def piece(robot: rx90sym.Robot, rec: Any, window: Any, plan: Plan, processing: Processing,
          regressor: Callable[..., np.ndarray], names: Sequence[str], first: int = 0,
          lags: Sequence[float] = (), left_out: Sequence[int] = ()) -> Piece:
    """One window through :func:`filtered_motion` with ``processing`` (its cut-off chosen), cut back to its
    core (a Dask task when distributed); ``lags`` [s]: the torques shifted by each too (the delay search);
    ``left_out``: the joints (0-based) whose torque is left out (none of their rows enters W)."""
    r0 = window.raw[0]
    d0, d1 = window.span
    rest_span = None
    if processing.min_velocity is not None and has_policy(processing.rest, "crossing"):
        # The rest runs of "crossing" measured beyond the window's core, up to the segment's own filter edges,
        # as in one window (plan_windows gave the margin room for them).
        context = int(math.ceil(CROSSING_SECONDS * rec.rate)) + 1 if rec.n_samples > 1 else 0
        rest_span = slice(max(plan.edge, d0 - context) - r0, min(plan.length - plan.edge, d1 + context) - r0)
    # The plan's factor for every window of a segment (its achieved rate: a window's own median step could round a
    # ratio of 12.5 the other way, and its rows would then not tile the segment's).
    at_plan = replace(processing, decimate_to=plan.rate if plan.factor > 1 else None)
    m = filtered_motion(robot, rec, at_plan, regressor, names, kept=slice(d0 - r0, d1 - r0), rest_span=rest_span)
    j0 = (d0 - plan.edge) // plan.factor
    core = slice(window.core[0] - j0, window.core[1] - j0)
    extra = []
    for lag in lags:  # the delay search: only Y moves (identify.estimation.delay)
        Y = shifted_torques(rec, lag)[m.kept] + m.extra
        extra.append((decimate(Y, m.factor) if m.factor > 1 else Y)[core])
    kept = None
    if left_out:  # joints whose torque is left out: none of their rows enters W
        kept = np.ones(m.Phi.shape[1], dtype=bool)
        kept[list(left_out)] = False
    cut = type(m)(m.t[core], m.q[core], m.dq[core], m.ddq[core], m.Y[core], m.Phi[core], m.cutoff, m.rate,
                  m.source, m.moving[core], m.usable[core], m.factor, m.kept, 0.0, m.note,
                  None if m.measured is None else m.measured[core], kept)
    return Piece(cut, first + window.core[0], tuple(extra))


def windows_in_order(sources: Sequence[BlockSource], plans: Sequence[Sequence[Plan]]) -> Iterator[tuple]:
    """(plan, window, raw samples, first) for every window of every segment of every recording, in
    order; ``first``: the index of the segment's first decimated sample among all segments."""
    offset = 0
    for src, src_plans in zip(sources, plans):
        pairs = [(plan, window) for plan in src_plans for window in plan.windows]
        spans = [span for plan in src_plans for span in plan.spans]
        starts = {}
        for plan in src_plans:
            starts[id(plan)] = offset
            offset += plan.samples
        for (plan, window), rec in zip(pairs, src.windows(spans)):
            yield plan, window, rec, starts[id(plan)]


def in_order(task: Callable[..., Any], arguments: Iterable[tuple], client: Any = None,
             in_flight: int = 2) -> Iterator[Any]:
    """``task(*args)`` for every tuple of ``arguments``, here, or on a ``dask.distributed.Client`` with at
    most ``in_flight`` tasks submitted; the results in order (the fold that follows is the serial one)."""
    if client is None:
        for args in arguments:
            yield task(*args)
        return
    queue: deque = deque()
    for args in arguments:
        queue.append(client.submit(task, *args, pure=False))
        if len(queue) >= in_flight:
            yield queue.popleft().result()
    while queue:
        yield queue.popleft().result()
