"""The presliding travel per joint from per-joint triangular factors: the same choice in memory and block by block.

The presliding magnitude FPj is linear, its travel δ_j one of the candidates: one pass of rows whose
columns hold FPj_k for every candidate k (:class:`~identify.observation.friction_model.FrictionBase`
with ``candidates``) gives per joint the factor R_j of ``[W_j | Y_j]``; a choice of one candidate per
joint is then a selection of columns, its weighted projected cost ½‖D(Y − W β̂)‖² read from the
factors' Gram matrices (eq. 11's weights D of the fit at the middle candidate). Coordinate descent,
two sweeps (z is piecewise linear in 1/δ: a grid, not a gradient). The factors are equal to rounding
whatever the blocks, and the choice is discrete: the same travels.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from identify.estimation.compression import _from_augmented_rows

__all__ = ["travels_from_factors"]


def _cost(G: np.ndarray, keep: Sequence[int]) -> float:
    """½ weighted residual of the least squares on columns ``keep`` of the summed Gram ``G`` (last: Y)."""
    idx = np.asarray(keep)
    A, g = G[np.ix_(idx, idx)], G[idx, -1]
    x = np.linalg.lstsq(A, g, rcond=None)[0]
    return 0.5 * float(G[-1, -1] - g @ x)


def travels_from_factors(R: Sequence[np.ndarray], rows: Sequence[int], names: Sequence[str],
                         columns: dict[int, list[int]], n_candidates: int) -> tuple[dict[int, int], dict[int, list[float]]]:
    """(joint -> index of the candidate chosen, joint -> cost per candidate at the others' choice) from the
    per-joint factors ``R`` (each (c + 1, c + 1) of ``[W_j | Y_j]``, ``rows`` their row counts) of the
    columns ``names``; ``columns``: joint -> its candidate columns (one per candidate). Columns that are 0
    on every row (no rest after a motion) are left out, as :func:`identify.observation.matrix.observation_matrix` does."""
    from identify.estimation.least_squares import joint_weights

    c = len(names)
    grams = [Rj.T @ Rj for Rj in R]
    live = np.flatnonzero(np.diag(sum(grams))[:c] > 0)
    columns = {j: cols for j, cols in columns.items() if all(k in live for k in cols)}
    chosen = sorted(k for cols in columns.values() for k in cols)
    fixed = [k for k in live if k not in chosen]
    choice = {j: n_candidates // 2 for j in columns}
    first = fixed + [columns[j][choice[j]] for j in columns]
    systems = [_from_augmented_rows(Rj[:, first + [c]], rows[j]) for j, Rj in enumerate(R)]
    weights = joint_weights(systems)
    G = sum((w ** 2) * g for w, g in zip(weights, grams))

    def cost(pick: dict[int, int]) -> float:
        return _cost(G, fixed + [columns[j][pick[j]] for j in columns])

    table: dict[int, list[float]] = {}
    for _ in range(2):
        for j in columns:
            table[j] = [cost({**choice, j: k}) for k in range(n_candidates)]
            choice[j] = int(np.argmin(table[j]))
    return choice, table
