"""The decimated rows of a fit made block by block, kept as an :class:`Observation` when they are few.

A fit reads, filters and decimates the recordings block by block (:mod:`identify.observation.block_rows`)
and folds each block's rows into triangular factors: its memory is the block's. The decimated rows
themselves (eqs. 6-8) are what the report's residual plots, the essential parameters and a later
bootstrap read; they are kept, in the order :func:`identify.observation.matrix.observation_matrix`
stacks them, whenever they hold at most :data:`KEPT_ROWS_BYTES` (a count of the log's decimated
rows, never of the block size: the same log keeps them or not whatever its blocks).
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from identify.observation.matrix import Observation, stack_rows
from identify.observation.processing import RestPolicy

__all__ = ["KEPT_ROWS_BYTES", "RowStore", "keeps_rows"]

#: Largest W kept beside the factors [bytes]: 256 MiB, e.g. 1.5 h of a 7-joint log decimated to
#: 50 Hz with 69 columns would take 1.4 GB and is not kept (its fit and prediction need none).
KEPT_ROWS_BYTES = 2 ** 28


def keeps_rows(samples: int, joints: int, columns: int) -> bool:
    """Whether ``samples`` decimated samples of ``joints`` rows and ``columns`` columns are kept."""
    return samples * joints * columns * 8 <= KEPT_ROWS_BYTES


class RowStore:
    """The pieces' rows in order (a workspace filled while the blocks stream by).

    add(): one piece (:class:`identify.observation.block_rows.Piece`), its rows kept as the fit keeps
    them (``drop``: rest rows dropped); observation(): the :class:`Observation` of them all."""

    def __init__(self, names: Sequence[str], drop: bool) -> None:
        self.names, self.drop = tuple(names), drop
        self.Phi: list[np.ndarray] = []
        self.Y: list[np.ndarray] = []
        self.keep: list[np.ndarray] = []
        self.t: list[np.ndarray] = []
        self.moving: list[np.ndarray] = []

    def add(self, piece: Any) -> None:
        m = piece.motion
        self.Phi.append(m.Phi)
        self.Y.append(m.Y)
        self.keep.append(m.rows(self.drop))
        self.t.append(m.t)
        self.moving.append(m.moving)

    def observation(self, cutoffs: Sequence[float], rates: Sequence[float], sources: Sequence[str],
                    notes: Sequence[str], min_velocity: float | None, rest: RestPolicy,
                    columns: Sequence[int] | None = None) -> Observation:
        """The rows kept as :func:`observation_matrix` stacks them (per joint, eqs. 7-8); ``cutoffs``,
        ``rates``, ``sources``: per segment filtered [Hz, Hz, name]; ``notes``: the processing's notes;
        ``columns``: those of the parameters fitted (None: all)."""
        W, Y, joint, samples = stack_rows(self.Phi, self.Y, masks=self.keep)
        names = self.names
        if columns is not None:
            W, names = W[:, list(columns)], tuple(self.names[c] for c in columns)
        moving = np.concatenate(self.moving)
        return Observation(W, Y, joint, names, samples, tuple(cutoffs), tuple(rates), rates[0], tuple(sources),
                           int(moving.shape[0]), tuple(notes), min_velocity, rest,
                           moving.mean(axis=0) if min_velocity is not None else None, np.concatenate(self.t))
