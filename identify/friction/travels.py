"""The presliding travel per joint, chosen from per-joint triangular factors whatever read the rows.

The presliding magnitude FPj (:class:`identify.observation.rest.PreslidingBase`) is linear, its travel
δ_j one of :data:`TRAVEL_CANDIDATES`: one pass of rows whose columns hold FPj_k for every candidate k
(:func:`travel_columns`) gives per joint the factor R_j of ``[W_j | Y_j]``; a choice of one candidate per
joint is then a selection of columns, its weighted projected cost ½‖D(Y − W β̂)‖² read from the
factors' Gram matrices (eq. 11's weights D of the fit at the middle candidate). Coordinate descent,
two sweeps (z is piecewise linear in 1/δ: a grid, not a gradient). The factors are equal to rounding
whatever the blocks, and the choice is discrete: the same travels.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.estimation.compression import _from_augmented_rows
from identify.friction.columns import form_columns, friction_base, friction_probe
from identify.observation.matrix import observation_matrix
from identify.observation.rest import PRESLIDING_PREFIX, PreslidingBase

__all__ = ["TRAVEL_CANDIDATES", "PreslidingTravels", "presliding_travels", "travel_columns", "travels_from_factors",
           "travels_of"]

#: Presliding travels δ tried for every joint [rad] (docs/real-logs.md: the UR10e prefers the short
#: ones, the twin's Dahl state has 5 mrad).
TRAVEL_CANDIDATES = (0.25e-3, 0.5e-3, 1e-3, 2e-3, 5e-3, 10e-3)


@dataclass(frozen=True)
class PreslidingTravels:
    """The presliding travel δ [rad] per joint (nan: no presliding column, e.g. never at rest),
    chosen among ``candidates`` [rad] by the fit's weighted cost (``cost``: per joint, per
    candidate, the others at their choice)."""

    travels: tuple[float, ...]
    candidates: tuple[float, ...]
    cost: tuple[tuple[float, ...], ...]

    def to_json(self) -> dict[str, Any]:
        return {"presliding_travel": [float(v) if np.isfinite(v) else None for v in self.travels],
                "presliding_candidates": list(self.candidates),
                "presliding_cost": [[float(c) if np.isfinite(c) else None for c in row] for row in self.cost]}


def travel_columns(robot: rx90sym.Robot, base: Any, candidates: Sequence[float] = TRAVEL_CANDIDATES) -> PreslidingBase:
    """The columns of the travel search: ``base``'s (its friction form and scales kept) with one column FPj_k
    per joint with a Coulomb term and per candidate travel k [rad]."""
    inner, _, terms, _ = friction_probe(robot, base)
    forms = form_columns(base)
    columns = friction_base(inner, terms, forms.form, forms.scales) if forms is not None else inner
    return PreslidingBase(columns, tuple((t.row, t.column, t.driver) for t in terms), None,
                          tuple(float(d) for d in candidates))


def travels_of(robot: rx90sym.Robot, R: Sequence[np.ndarray], rows: Sequence[int], names: Sequence[str],
               candidates: Sequence[float] = TRAVEL_CANDIDATES) -> PreslidingTravels:
    """The travels chosen from the per-joint factors of the :func:`travel_columns` rows (whatever read them)."""
    names = list(names)
    columns = {j: [names.index(f"{PRESLIDING_PREFIX}{j + 1}_{k}") for k in range(len(candidates))]
               for j in range(robot.n)
               if all(f"{PRESLIDING_PREFIX}{j + 1}_{k}" in names for k in range(len(candidates)))}
    choice, table = travels_from_factors(R, rows, names, columns, len(candidates))
    travels = tuple(float(candidates[choice[j]]) if j in choice else np.nan for j in range(robot.n))
    return PreslidingTravels(travels, tuple(float(c) for c in candidates),
                             tuple(tuple(table.get(j, [np.nan] * len(candidates))) for j in range(robot.n)))



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


def presliding_travels(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any,
                       candidates: Sequence[float] = TRAVEL_CANDIDATES, **options: Any) -> PreslidingTravels:
    """The presliding travel per joint, separable like the velocity scales: FPj is linear, δ_j
    one of ``candidates`` [rad]. One observation matrix holds a column FPj_k per candidate (rest
    policy "presliding" in ``options``, the fit's other observation options); each joint's δ chosen by
    coordinate descent on the weighted cost from its per-joint factors
    (:func:`travels_from_factors`, as block by block)."""
    from identify.estimation.incremental_qr import JointFactors

    obs = observation_matrix(robot, recordings, base=travel_columns(robot, base, candidates), **options)
    factors = JointFactors(robot.n, len(obs.names))
    for j in range(robot.n):
        rows = obs.joint == j
        factors.add(j, np.column_stack([obs.W[rows], obs.Y[rows]]))
    return travels_of(robot, factors.R, factors.rows, obs.names, candidates)
