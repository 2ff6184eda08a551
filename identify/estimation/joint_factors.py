"""One pass over the logs' rows folded into the per-joint triangular factors of the least squares.

Every block's decimated rows (:func:`identify.observation.block_rows.piece`, with the fit's one
:class:`~identify.observation.processing.Processing`) are reduced to the factor of ``[W_i | Y_i | Y'...]``
of each joint (the torques shifted by each lag of the delay search as extra right-hand sides) where the
block is made, then folded in block order (:class:`~identify.estimation.incremental_qr.JointFactors`):
the serial result, here or with every block a task on Dask. The same pass may feed the segment bootstrap
and keep the decimated rows when they are few.
"""
from __future__ import annotations

from typing import Any, Iterable, Sequence

import numpy as np

import rx90sym

from identify.estimation.bootstrap import SegmentBootstrap
from identify.estimation.incremental_qr import JointFactors, stacked_rows
from identify.io.blocks import BlockSource
from identify.observation.block_rows import Piece, Plan, in_order, piece, plan_windows, windows_in_order
from identify.observation.processing import Processing, drops_rest
from identify.observation.row_store import RowStore
from identify.observation.scan import Scan

__all__ = ["joint_factors", "plans_of"]


def plans_of(scans: Sequence[Scan], processing: Processing, block: int) -> tuple[list[list[Plan]], tuple[str, ...]]:
    """The windows of every segment of every recording (per recording), and the notes naming the segments
    left out; recordings of different rates after decimation are refused."""
    planned = [plan_windows(s, processing, block) for s in scans]
    rates = [p.rate for src_plans, _ in planned for p in src_plans]
    if max(rates) > min(rates) * (1 + 1e-3):
        raise ValueError(f"recordings have different rates after decimation: {', '.join(f'{r:g}' for r in rates)} Hz; "
                         f"give decimate_to")
    return [p for p, _ in planned], tuple(note for _, notes in planned for note in notes)


def _block_task(robot: rx90sym.Robot, rec: Any, window: Any, plan: Plan, processing: Processing, columns: Any,
                names: Sequence[str], first: int, lags: Sequence[float], left_out: Sequence[int]) -> tuple[Piece, list]:
    """One block: its decimated rows and, per joint, the triangular factor of ``[W_i | Y_i | Y_lags]``."""
    p = piece(robot, rec, window, plan, processing, columns.regressor_batch, names, first, lags, left_out)
    m = p.motion
    keep = m.rows(processing.min_velocity is not None and drops_rest(processing.rest))
    factors = []
    for j in range(m.Phi.shape[1]):
        rows = stacked_rows(m.Phi, [m.Y, *p.extra_Y], j, keep[:, j])
        factors.append((JointFactors.block_factor(rows), rows.shape[0]))
    return p, factors


def _workers(client: Any) -> int:
    try:
        return max(1, len(client.scheduler_info().get("workers", {})))
    except Exception:  # a client that cannot say: two blocks in flight per assumed worker
        return 1


def joint_factors(robot: rx90sym.Robot, sources: Sequence[BlockSource], plans: Sequence[Sequence[Plan]],
                  processing: Processing, columns: Any, lags: Sequence[float] = (), left_out: Sequence[int] = (),
                  client: Any = None, boot: SegmentBootstrap | None = None,
                  store: RowStore | None = None) -> tuple[JointFactors, np.ndarray, int]:
    """(per-joint factors of ``columns``' rows with the torques and the torques shifted by each of ``lags``
    [s], moving-sample counts per joint, the number of blocks) of one pass with ``processing`` (its cut-off
    and delay chosen) over the windows ``plans`` of ``sources``; ``left_out``: the joints whose torque is
    left out; ``boot``: a segment bootstrap fed on the way; ``store``: the decimated rows kept too."""
    names = tuple(columns.names)
    factors = JointFactors(robot.n, len(names), 1 + len(lags))
    moving = np.zeros(robot.n)
    drop = processing.min_velocity is not None and drops_rest(processing.rest)
    count = 0
    # On Dask the robot and its compiled regressor are sent once to each worker, not with every block.
    shared = client.scatter([robot, columns], broadcast=True, hash=False) if client is not None else (robot, columns)
    tasks: Iterable[tuple] = ((shared[0], rec, window, plan, processing, shared[1], names, first, tuple(lags),
                               tuple(left_out)) for plan, window, rec, first in windows_in_order(sources, plans))
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
