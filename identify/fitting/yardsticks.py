"""Both yardsticks of every validation from one pass over the fitted data, and their held-out errors.

:func:`log_yardsticks` reads the logs once, window by window (:mod:`identify.fitting.baseline_blocks`),
and folds the baseline's rows into per-(time block, joint) factors
(:mod:`identify.fitting.baseline_factors`); from them come the plain OLS baseline
(:mod:`identify.fitting.baseline`), the model the user had (:mod:`identify.fitting.user_model`) and, given
the time blocks of the blocked cross-validation (:class:`identify.selection.raw_torque_scores.RawSpan`: the
processing choice's), both yardsticks' held-out errors per (block, joint) (:class:`YardstickFolds`): each
fitted on the other blocks' samples, scored on the block's raw measured torques, against the same
reference as the fit's own held-back errors (:meth:`identify.selection.raw_torque_scores.RawFactors.scores`).

The yardsticks score their own samples (0.5 s from each segment's ends, measured) within the
cross-validation's bounds (``RawSpan.bounds``: the filters' edges of its lowest cut-off from each end);
a fitted sample at time t falls in the block of t (the fit's rows: t + delay). Memory: blocks x joints x
(13 n + 2)² doubles, twice.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.selection.raw_torque_scores import RawSpan
from identify.fitting.baseline import PlainBaseline, baseline_names, memory_windows
from identify.fitting.baseline_blocks import source_windows
from identify.fitting.baseline_factors import BaselineFactors, baseline_factors, plain_solution
from identify.fitting.user_model import UserModel, described_bodies, user_model, user_values
from identify.selection.folds import block_scores

__all__ = ["KINDS", "Yardsticks", "YardstickFolds", "fit_yardsticks", "held_out", "log_yardsticks",
           "yardstick_folds"]

#: The yardsticks by name: the plain OLS baseline, the model the user had.
KINDS = ("plain", "user")


@dataclass(frozen=True, eq=False)
class YardstickFolds:
    """Held-out errors of the yardsticks per time block of a blocked cross-validation: ``err2[kind]``
    (blocks, n) the squared error [N² m²] on block b's samples scored of the yardstick ``kind`` ("plain",
    "user": :data:`KINDS`) fitted on the other blocks; ``ref2`` (blocks, n) the squared measured torque
    there; ``samples`` (blocks,) the samples scored; ``user_note``: why there is no "user" (else "").
    A block whose other blocks hold no fitted sample, or without a sample scored, has 0 in both."""

    err2: dict[str, np.ndarray]
    ref2: np.ndarray
    samples: np.ndarray
    user_note: str = ""

    def scores(self, kind: str = "plain") -> tuple[float, tuple[float, ...], tuple[tuple[float, ...], ...]]:
        """(score, per joint, per held-back block and joint) of yardstick ``kind``: relative errors
        100 sqrt(err2 / ref2) in %, exactly as :meth:`identify.selection.raw_torque_scores.RawFactors.scores`."""
        if kind not in KINDS:
            raise ValueError(f"yardstick must be one of {KINDS}, got {kind!r}")
        if kind not in self.err2:
            raise ValueError(f"no held-out errors of the model the user had: {self.user_note}")
        return block_scores(self.err2[kind], self.ref2)


@dataclass(frozen=True, eq=False)
class Yardsticks:
    """The two yardsticks fitted on the same samples: ``plain`` (None: it cannot be fitted: a rate of
    20 Hz or less, every segment shorter than 1 s), ``user`` (None: not computed, ``user_note`` says why),
    ``folds`` their held-out errors per time block (None: no time blocks given)."""

    plain: PlainBaseline | None
    user: UserModel | None
    user_note: str = ""
    folds: YardstickFolds | None = None


def held_out(factors: BaselineFactors, theta: np.ndarray | None, note: str = "") -> YardstickFolds:
    """:class:`YardstickFolds` from per-(time block, joint) factors with the samples scored
    (:func:`identify.fitting.baseline_factors.baseline_factors` given the time blocks); θ₀ the description's
    bodies (None: no "user" errors, ``note`` says why)."""
    if factors.scored is None:
        raise ValueError("the held-out yardsticks need the factors of the samples scored (give the time blocks)")
    B, n, c = factors.blocks, factors.n, factors.c
    kinds = KINDS if theta is not None else KINDS[:1]
    err2, ref2 = {k: np.zeros((B, n)) for k in kinds}, np.zeros((B, n))
    for b in range(B):
        if not sum(int(f.rows[0]) for k, f in enumerate(factors.fitted) if k != b):
            continue  # nothing to fit the other blocks on
        values = {"plain": plain_solution(factors.stacked(without=b), c)[0]}
        if theta is not None:
            values["user"] = user_values(factors, theta, without=b)[0]
        held = factors.scored[b]
        for j in range(n):
            S = held.R[j]
            ref2[b, j] = np.sum(S[:, c + 1] ** 2)
            for k in kinds:
                err2[k][b, j] = np.sum((S[:, :c + 1] @ np.r_[values[k], -1.0]) ** 2)
    return YardstickFolds(err2, ref2, np.array([int(f.rows[0]) for f in factors.scored]), note)


def _yardsticks(robot: rx90sym.Robot, factors: BaselineFactors, spring: bool) -> Yardsticks:
    names = baseline_names(robot)
    plain = factors.plain(names, spring)
    theta, where = described_bodies(robot)
    user = user_model(factors, theta, names, spring, where) if theta is not None else None
    folds = held_out(factors, theta, "" if user is not None else where) if factors.scored is not None else None
    return Yardsticks(plain, user, "" if user is not None else where, folds)


def fit_yardsticks(robot: rx90sym.Robot, recordings: Sequence[Any], spring: bool = True,
                   block: int | None = None) -> Yardsticks:
    """Both yardsticks on every segment of ``recordings`` (held in memory), each filtered in blocks of at
    most ``block`` samples (None: whole). ValueError where the baseline cannot be fitted."""
    return _yardsticks(robot, baseline_factors(robot, memory_windows(recordings, block), spring), spring)


def log_yardsticks(robot: rx90sym.Robot, sources: Sequence[Any], scans: Sequence[Any], spring: bool,
                        block: int, client: Any = None, span: RawSpan | None = None) -> Yardsticks:
    """Both yardsticks of logs read block by block (``scans``: their first pass,
    :func:`identify.observation.scan.scan`), in one pass; with ``span`` (the cross-validation's time
    blocks) their held-out errors per block too. Where the baseline cannot be fitted (a rate of 20 Hz or
    less, every segment shorter than 1 s) neither is, said in ``user_note``. client: a
    ``dask.distributed.Client`` running the windows (read here, filtered and compressed on the workers,
    folded here in order)."""
    runner = None
    if client is not None:
        from identify.observation.block_rows import in_order

        shared = client.scatter(robot, broadcast=True, hash=False)  # sent once to each worker

        def on_dask(task: Any, arguments: Any) -> Any:
            return in_order(task, ((shared, *a[1:]) for a in arguments), client, 4)
        runner = on_dask
    try:
        factors = baseline_factors(robot, source_windows(sources, scans, block), spring, runner, span)
        return _yardsticks(robot, factors, spring)
    except ValueError as exc:
        return Yardsticks(None, None, f"no yardstick could be fitted ({exc})")


def yardstick_folds(robot: rx90sym.Robot, sources: Sequence[Any], scans: Sequence[Any], span: RawSpan,
                    spring: bool, block: int, client: Any = None) -> YardstickFolds:
    """Both yardsticks' held-out errors per (time block, joint) of the blocked cross-validation whose time
    blocks are ``span`` (:func:`identify.selection.raw_torque_scores.raw_span`), from logs read block by block
    (:func:`log_yardsticks`). ValueError where the baseline cannot be fitted."""
    done = log_yardsticks(robot, sources, scans, spring, block, client, span)
    if done.folds is None:
        raise ValueError(done.user_note)
    return done.folds
