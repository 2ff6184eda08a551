"""The prior's weight λ chosen by blocked cross-validation against the raw measured torques.

For each held-back time block b (the processing choice's blocks: :mod:`identify.selection.raw_torque_scores`),
the prior-weighted model (:mod:`identify.estimation.consistency.weighted_fit`) is fitted on the
other blocks' rows — each joint weighted by 1/σ_j of its own least-squares residual there, as eq. 11
— at every weight λ of the grid, and predicts the held-back block's raw torques (the same quadratic
form in β as the processing choice's scores). The grid holds both ends: λ = 0 is the data alone
(physically consistent), λ = ∞ the description's rigid bodies with the drives and offsets fitted.

The choice: the largest λ whose held-back error the best weight does not clearly beat, so that the
description is kept unless the data clearly improve on it (what the data determine is theirs at any λ:
:mod:`identify.estimation.consistency.weighted_fit`). Clearly: beyond one standard error of the paired
difference over the blocks (:func:`~identify.selection.cross_validation.clearly_better`), on all blocks
but one at most, and by :data:`WEIGHT_MARGIN` of the larger λ's error. Nor is a λ chosen whose model moves
a base parameter the data determine further than they allow (``keeps``: the physical constraints can,
where the description's bodies are held in the directions the data do not see). Why so strict: the blocks of a
short log share its few motions, and the bodies a small λ fits to them can absorb what the drives' model
misses there, which does not carry to other motions (measured: docs/identified-model.md).
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from identify.estimation.consistency.errors import ConsistencyError
from identify.estimation.results import json_number
from identify.estimation.consistency.weighted_fit import PriorProblem
from identify.selection.raw_torque_scores import offset_columns_of
from identify.selection.candidates import Candidate
from identify.selection.cross_validation import clearly_better
from identify.selection.folds import block_scores

__all__ = ["WEIGHT_GRID", "WEIGHT_MARGIN", "FoldSystem", "ObservationFolds", "WeightChoice", "choose_prior_weight", "fold_system",
           "held_back_scores", "observation_folds"]

#: λ of the grid: the data alone (0), decades, the description's bodies (inf).
WEIGHT_GRID = (0.0, 1e-1, 1.0, 1e1, 1e2, 1e3, 1e4, 1e5, math.inf)
#: How much lower a smaller λ's held-back error must be to be chosen over a larger one [fraction].
WEIGHT_MARGIN = 0.2


def weight_label(value: float) -> str:
    return "inf" if math.isinf(value) else f"{value:g}"


@dataclass(frozen=True)
class WeightChoice:
    """The prior weights scored: λ, their scores (mean over joints of the held-back relative error
    [%]), per joint and per block, the chosen λ and why."""

    weights: tuple[float, ...]
    scores: tuple[Candidate, ...]
    chosen: float
    reason: str
    blocks: int
    unconstrained: Candidate | None = None

    def table(self) -> str:
        n = max((len(c.per_joint) for c in self.scores), default=0)
        lines = [f"prior weight λ chosen by {self.blocks}-block cross-validation against the raw measured torques",
                 f"  {'λ':>8}  held-back error [%]" + "".join(f"{'j' + str(j + 1):>7}" for j in range(n))]
        for w, c in zip(self.weights, self.scores):
            score = "-" if math.isnan(c.score) else f"{c.score:.3f}"
            joints = "".join(_cell(v) for v in c.per_joint)
            mark = " <- chosen" if w == self.chosen else ""
            lines.append(f"  {weight_label(w):>8}  {score:>19}{joints}{mark}")
        c = self.unconstrained
        if c is not None and not math.isnan(c.score):
            lines.append(f"  {'(LS)':>8}  {_cell(c.score, 19, 3)}" + "".join(_cell(v) for v in c.per_joint)
                         + "  least squares, no physical constraint (for reference)")
        return "\n".join(lines + ["  " + self.reason])

    def to_dict(self) -> dict[str, Any]:
        return {"method": "blocked cross-validation", "blocks": self.blocks,
                "chosen": None if math.isinf(self.chosen) else self.chosen, "chosen_label": weight_label(self.chosen),
                "reason": self.reason,
                "weights": [weight_label(w) for w in self.weights],
                "scores_pct": [None if math.isnan(c.score) else c.score for c in self.scores],
                "per_joint_pct": [[json_number(v) for v in c.per_joint] for c in self.scores], "table": self.table()}


def _cell(v: float, width: int = 7, digits: int = 2) -> str:
    """A table cell of ``width`` with a space before it however large the number (3 significant digits
    from 1e4 on: a least squares without constraints can predict a held-back block at 10⁵ %)."""
    text = f"{v:.{digits}f}" if abs(v) < 1e4 else f"{v:.3g}"
    return " " + text.rjust(width - 1)


@dataclass(frozen=True, eq=False)
class FoldSystem:
    """The weighted least-squares system of some blocks: R (k, c'), z (k,) with ‖R β − z‖² the weighted
    residual (up to a constant), ``scale`` the weighted residual of its least squares, ``weights`` (n,)
    1/σ_j (0 for a joint without rows), and per joint the unweighted factor of [W_j | Y_j] and its rows."""

    R: np.ndarray
    z: np.ndarray
    scale: float
    weights: np.ndarray
    joints: tuple
    rows: tuple


def fold_system(fitted: Sequence[Any], held: int | None, n: int, c: int,
                offsets: Sequence[int] = ()) -> FoldSystem | None:
    """The :class:`FoldSystem` of every block but ``held`` (None: all) from the per-block factors
    ``fitted`` (:class:`~identify.estimation.incremental_qr.JointFactors` of rows ``[W | 1 | Y]``),
    with a torque offset column for each joint of ``offsets`` (the column of ones, after W's ``c``
    columns; left out on the other joints): each joint weighted by 1/σ_j of its own least-squares
    residual (eq. 11); None when a joint with rows has too few of them."""
    parts, weights, joints, counts = [], np.zeros(n), [], []
    for j in range(n):
        blocks = [f.R[j] for b, f in enumerate(fitted) if b != held and f.rows[j]]
        rows = sum(int(f.rows[j]) for b, f in enumerate(fitted) if b != held)
        if not blocks:
            joints.append(None)
            counts.append(0)
            continue  # a joint without rows (its torque left out)
        stacked = offset_columns_of(np.vstack(blocks), c, j, offsets)
        width = stacked.shape[1] - 1
        live = np.flatnonzero(np.any(stacked[:, :width] != 0.0, axis=0))
        x, *_ = np.linalg.lstsq(stacked[:, live], stacked[:, width], rcond=None)
        resid = float(np.linalg.norm(stacked[:, live] @ x - stacked[:, width]))
        if rows <= live.size or resid == 0.0:
            return None
        weights[j] = math.sqrt(rows - live.size) / resid
        parts.append(stacked * weights[j])
        joints.append(np.linalg.qr(stacked, mode="r"))
        counts.append(rows)
    if not parts:
        return None
    R = np.linalg.qr(np.vstack(parts), mode="r")
    width = R.shape[1] - 1
    beta, *_ = np.linalg.lstsq(R[:width, :width], R[:width, width], rcond=None)
    scale = float(np.sum((R[:, :width] @ beta - R[:, width]) ** 2))
    return FoldSystem(R[:width, :width], R[:width, width], max(scale, 1e-12 * float(np.sum(R[:, width] ** 2)), 1e-300),
                      weights, tuple(joints), tuple(counts))


def held_back_scores(factors: Any, problems: dict, weights: Sequence[float], offsets: Sequence[int]) -> list[Candidate]:
    """Per weight the held-back errors of every block, a Candidate each (``factors``: a RawFactors of the
    fit's columns, with an offset on the joints ``offsets``; ``problems``: the compiled problems for
    finite λ (key False) and λ = ∞ (True); the weight -1 stands for the unconstrained least squares)."""
    blocks, n, c = factors.span.blocks, factors.n, factors.c
    offsets = tuple(offsets)
    err2 = np.full((len(weights), blocks, n), np.nan)
    ref2 = np.zeros((blocks, n))
    for b in range(blocks):
        system = fold_system(factors.fitted, b, n, c, offsets)
        for j in range(n):
            ref2[b, j] = float(np.sum(factors.scored[b].R[j][:, -1] ** 2))
        if system is None:
            continue
        for k, w in enumerate(weights):
            problem = problems[math.isinf(w)]
            try:
                beta = (np.linalg.lstsq(system.R, system.z, rcond=None)[0] if w == -1.0 else
                        problem.cmap.beta(problem.solve(system.R, system.z, w, system.scale)))
            except ConsistencyError:
                continue  # this weight unscored on this block
            for j in range(n):
                v = np.r_[beta[:c], beta[c + offsets.index(j)] if j in offsets else 0.0, -1.0, 0.0]
                err2[k, b, j] = float(np.sum((factors.scored[b].R[j] @ v) ** 2))
    out = []
    for k, w in enumerate(weights):
        scored = np.isfinite(err2[k]).all(axis=1) & (ref2.sum(axis=1) > 0)
        if not scored.any():
            out.append(Candidate(math.nan, None, label=f"λ {weight_label(w)} not scored"))
            continue
        e, r = np.where(scored[:, None], err2[k], 0.0), np.where(scored[:, None], ref2, 0.0)
        score, per_joint, per_block = block_scores(e, r)
        per_block = tuple(row if ok else tuple(math.nan for _ in row) for row, ok in zip(per_block, scored))
        out.append(Candidate(math.nan, None, score=score, per_joint=per_joint, per_block=per_block,
                             label=f"λ {weight_label(w)}"))
    return out


def choose_prior_weight(factors: Any, free: PriorProblem, fixed: PriorProblem, offsets: Sequence[int] = (),
                        weights: Sequence[float] = WEIGHT_GRID,
                        keeps: Callable[[float], str | None] | None = None) -> WeightChoice:
    """The λ of the module docstring: ``factors`` the fit's columns' per-(block, joint) factors of
    fitted rows and raw samples scored (:class:`~identify.selection.raw_torque_scores.RawFactors`), with a
    torque offset on the joints ``offsets``; ``free``/``fixed`` the compiled problems for finite λ and
    for λ = ∞; ``keeps(λ)``: why the model at λ overrides what the data determine (None: it does not),
    such a λ never chosen."""
    scored = held_back_scores(factors, {False: free, True: fixed}, (-1.0,) + tuple(weights), offsets)
    unconstrained, scored = scored[0], scored[1:]
    valid = [(w, s) for w, s in zip(weights, scored) if not math.isnan(s.score)]
    if not valid:
        raise ValueError("no fold could be fitted and scored for the prior weight")
    best_w, best = min(valid, key=lambda ws: ws[1].score)
    chosen_w, chosen, refused = best_w, best, []
    for w, s in sorted(valid, key=lambda ws: -ws[0]):  # from the description's bodies down
        if s is not best and _clearly_lower(best, s):
            continue
        why = keeps(w) if keeps is not None else None
        if why:
            refused.append((w, why))
            continue
        chosen_w, chosen = w, s
        break
    why = (f"λ {weight_label(chosen_w)}: the lowest held-back error ({chosen.score:.3f} %)" if chosen is best else
           f"λ {weight_label(chosen_w)}: the largest weight whose held-back error ({chosen.score:.3f} %) the best "
           f"(λ {weight_label(best_w)}, {best.score:.3f} %) does not beat clearly (beyond the blocks' spread, on "
           f"all blocks but one, by {100 * WEIGHT_MARGIN:g} %)")
    if refused:
        why += ("; larger weights not taken, the prior would override what the data determine: "
                + "; ".join(f"λ {weight_label(w)} {reason}" for w, reason in refused))
    return WeightChoice(tuple(weights), tuple(scored), chosen_w, why, factors.span.blocks, unconstrained)


def _clearly_lower(best: Candidate, other: Candidate) -> bool:
    """Whether ``best``'s held-back error is below ``other``'s beyond the blocks' spread, on all blocks but one
    at most, and by WEIGHT_MARGIN of ``other``'s (module docstring)."""
    if not (clearly_better(best, other) and best.score < (1.0 - WEIGHT_MARGIN) * other.score):
        return False
    a, b = np.asarray(best.per_block, dtype=float), np.asarray(other.per_block, dtype=float)
    if a.shape != b.shape or a.ndim != 2:
        return True
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a block not scored: NaN, left out
        d = np.nanmean(a - b, axis=1)
    d = d[np.isfinite(d)]
    return bool(np.sum(d >= 0.0) <= 1)


@dataclass(frozen=True, eq=False)
class _Span:
    blocks: int


@dataclass(frozen=True, eq=False)
class ObservationFolds:
    """The folds of an observation matrix held in memory, in the layout of
    :class:`~identify.selection.raw_torque_scores.RawFactors` (fitted rows ``[W | 1 | Y]``; scored
    ``[W | 1 | Y | Y]``: the held-back error against the observation's own filtered torques)."""

    fitted: tuple
    scored: tuple
    span: _Span
    n: int
    c: int


def observation_folds(obs: Any, blocks: int = 5) -> ObservationFolds:
    """:class:`ObservationFolds` of ``obs`` (an :class:`identify.Observation` with its sample times):
    its rows cut into ``blocks`` contiguous blocks of equal duration."""
    from identify.estimation.incremental_qr import JointFactors
    from identify.selection.folds import time_blocks

    if obs.t is None:
        raise ValueError("the observation has no sample times: the prior weight cannot be cross-validated")
    n, c = int(obs.joint.max()) + 1, obs.W.shape[1]
    ids = time_blocks([np.asarray(obs.t)[obs.samples]], blocks)[0]
    fitted = tuple(JointFactors(n, c + 1) for _ in range(blocks))
    scored = tuple(JointFactors(n, c + 1, 2) for _ in range(blocks))
    ones = np.ones(obs.W.shape[0])
    for b in range(blocks):
        for j in range(n):
            rows = (ids == b) & (obs.joint == j)
            if rows.any():
                fitted[b].add(j, np.column_stack([obs.W[rows], ones[rows], obs.Y[rows]]))
                scored[b].add(j, np.column_stack([obs.W[rows], ones[rows], obs.Y[rows], obs.Y[rows]]))
    return ObservationFolds(fitted, scored, _Span(blocks), n, c)
