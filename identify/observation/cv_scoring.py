"""The scores of the blocked cross-validation (:mod:`identify.observation.cross_validation`): the folds by
time, the per-(block, joint) compressed rows, the fold fits (WLS, eq. 11's weights), and a candidate's
held-back error, against the raw measured torques (:func:`score_raw`, the default: each candidate at its
own cut-off and decimation, its held-back prediction interpolated onto the recordings' own time stamps,
the same raw samples for every candidate) or, as before, against the torques filtered like its rows at
one common rate (:func:`score_common_rate`, what the block-by-block choice still does)."""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.observation.candidates import Candidate
from identify.observation.matrix import column_regressor, filtered_motions, stack_rows
from identify.observation.processing import drops_rest
from identify.signal.filtering import EDGE_PERIODS
from identify.signal.interpolate import onto

__all__ = ["RawTargets", "raw_targets", "score_raw", "with_offsets", "CACHE_BYTES", "score_common_rate", "time_folds", "time_blocks",
           "block_factors", "block_scores", "fold_wls"]


def time_folds(t: np.ndarray, start: float, span: float, blocks: int) -> np.ndarray:
    """The contiguous block (0 .. blocks-1) of each time ``t`` [s] in ``[start, start + span)``."""
    return np.minimum((blocks * (t - start) / span).astype(int), blocks - 1)


def time_blocks(times: Sequence[np.ndarray], blocks: int) -> list[np.ndarray]:
    """The fold of every sample: per array of sample times [s] (one per motion or segment), the
    block 0..blocks-1 it falls in when the common span (earliest to latest time of all) is cut into
    ``blocks`` contiguous blocks of equal duration (:func:`time_folds`). The one fold assignment of the
    processing and the friction choices (by time, not by sample index: recordings and segments of other
    lengths or rates fall in the same blocks for both)."""
    start = min(float(np.min(t)) for t in times)
    span = max(float(np.max(t)) for t in times) - start + 1e-9
    return [time_folds(np.asarray(t), start, span, blocks) for t in times]


def _compressed_blocks(motions: Sequence[Any], ids: Sequence[np.ndarray], blocks: int, drop: bool,
                       n: int) -> dict[tuple[int, int], tuple[np.ndarray, int]]:
    """(block, joint) -> (the triangular factor of [W | Y] over the block's rows of that joint, their number)."""
    # The rows stacked once (a block's rows of a joint keep their order): one copy of W, not one per block.
    W, Y, joint, samples = stack_rows([m.Phi for m in motions], [m.Y for m in motions],
                                      masks=[m.rows(drop) for m in motions])
    return block_factors(W, Y, joint, np.concatenate(ids)[samples], range(blocks), n)


def block_factors(W: np.ndarray, Y: np.ndarray, joint: np.ndarray, ids: np.ndarray, blocks: Sequence[int],
                  n: int) -> dict[tuple[int, int], tuple[np.ndarray, int]]:
    """(block, joint) -> (the triangular factor of [W | Y] over the rows of that block (``ids``) and
    joint, their number), for the ``blocks`` listed: what :func:`fold_wls` solves from."""
    # The rows grouped by (block, joint) with one stable sort (each group keeps its order), not a mask per group.
    key = np.asarray(ids) * n + joint
    order = np.argsort(key, kind="stable")
    edges = np.searchsorted(key[order], [[b * n + j, b * n + j + 1] for b in blocks for j in range(n)])
    out = {}
    for bj, (lo, hi) in zip([(b, j) for b in blocks for j in range(n)], edges):
        if hi > lo:
            rows = order[lo:hi]
            out[bj] = (np.linalg.qr(np.column_stack([W[rows], Y[rows]]), mode="r"), int(hi - lo))
    return out


def block_scores(err2: np.ndarray, ref2: np.ndarray) -> tuple[float, tuple[float, ...], tuple[tuple[float, ...], ...]]:
    """(score, per joint, per held-back block and joint), relative errors 100 sqrt(err2 / ref2) in %,
    from the squared errors and references (blocks, n) of the held-back blocks."""
    total = ref2.sum(axis=0)
    per_joint = 100.0 * np.sqrt(err2.sum(axis=0) / np.where(total > 0, total, np.nan))
    per_block = 100.0 * np.sqrt(err2 / np.where(ref2 > 0, ref2, np.nan))
    return (float(np.nanmean(per_joint)), tuple(float(v) for v in per_joint),
            tuple(tuple(float(v) for v in row) for row in per_block))


def fold_wls(factors: dict[tuple[int, int], tuple[np.ndarray, int]], held: int, n: int) -> np.ndarray | None:
    """WLS (each joint weighted by 1 / its residual standard deviation, as the fit does) on every
    block but ``held``, from the compressed blocks; None when a joint has too few rows."""
    systems = []
    for j in range(n):
        parts = [f for (b, jj), f in factors.items() if jj == j and b != held]
        if not parts:
            return None
        stacked = np.vstack([R for R, _ in parts])  # the same norms as the rows it compresses
        rows = sum(count for _, count in parts)
        c = stacked.shape[1] - 1
        # The joint's own columns only (its rows hold no parameter of the links before it): the same
        # residual, and rank threshold (rows > columns), from a smaller SVD.
        live = np.flatnonzero(np.any(stacked[:, :c] != 0.0, axis=0))
        x, *_ = np.linalg.lstsq(stacked[:, live], stacked[:, c], rcond=None)
        resid = np.linalg.norm(stacked[:, live] @ x - stacked[:, c])
        if rows <= c or resid == 0:
            return None
        systems.append(stacked / (resid / np.sqrt(rows - c)))  # sigma_j as in eq. 12, per joint
    R = np.vstack(systems)
    c = R.shape[1] - 1
    beta, *_ = np.linalg.lstsq(R[:, :c], R[:, c], rcond=None)
    return beta


def score_raw(robot: rx90sym.Robot, recordings: Sequence[Any], cand: Candidate, base: Any, targets: "RawTargets",
           blocks: int, options: dict) -> tuple[float, tuple[float, ...], tuple[tuple[float, ...], ...]]:
    """(score, per joint, per held-back block and joint), relative errors in % against the raw
    measured torques of ``targets`` (the same samples for every candidate): each candidate at its own
    cut-off and decimation, its held-back prediction interpolated onto the recordings' time stamps."""
    min_velocity = options["min_velocity"] if cand.rest is not None else None
    rest = cand.rest or "zero-coulomb"
    # A presliding joint gets its magnitude FPj (travel PRESLIDING_TRAVEL), as in the fit.
    names, regressor = column_regressor(robot, base, rest=rest if min_velocity is not None else None)
    delay = options.get("delay", 0.0)
    cache = options.get("cache")  # (cut-off, decimation, rest) -> (motions, segments): choose_processing's
    key = (cand.cutoff, cand.decimate_to, cand.rest)
    if cache is not None and key in cache:
        motions, used = cache[key]
    else:
        motions, _, used = filtered_motions(robot, recordings, cand.cutoff, cand.decimate_to, options["spring"],
                                            regressor, names, min_velocity, rest, delay)
        if cache is not None and sum(m.Phi.nbytes for m in motions) <= CACHE_BYTES:
            cache[key] = (motions, used)
    if options.get("offsets"):  # an offset OFFj on these joints: a column of ones in joint j's rows
        motions = [with_offsets(m, options["offsets"]) for m in motions]
    ids = [np.clip(time_folds(m.t + delay, targets.start, targets.span, blocks), 0, blocks - 1) for m in motions]
    drop = min_velocity is not None and drops_rest(rest)
    n = robot.n
    # One compression per (block, joint): [R | z] of the QR of [W | Y] (eq. 10 on few rows).
    blocks_R = _compressed_blocks(motions, ids, blocks, drop, n)
    betas = [fold_wls(blocks_R, b, n) for b in range(blocks)]
    err2, ref2 = np.zeros((blocks, n)), np.zeros((blocks, n))
    for m, piece in zip(motions, used):
        target = targets.pieces.get(piece.source)
        if target is None:
            continue
        t, tau, fold = target
        spring = robot.spring_torque_batch(m.q)[:, :, 0] if options["spring"] and robot.spring is not None else 0.0
        for b, beta in enumerate(betas):
            here = fold == b
            if beta is None or not here.any():
                continue
            pred = onto(t[here], m.t + delay, m.Phi @ beta - spring)
            err2[b] += np.sum((tau[here] - pred) ** 2, axis=0)
            ref2[b] += np.sum(tau[here] ** 2, axis=0)
    if not np.any(ref2 > 0):
        raise ValueError("no fold could be fitted and scored (too few rows left after the filters' edges)")
    return block_scores(err2, ref2)


#: Bytes of filtered rows (Phi) a choice keeps for reuse (the candidate with offsets reuses the chosen one's).
CACHE_BYTES = 200_000_000


def with_offsets(m: Any, joints: Sequence[int]) -> Any:
    """A FilteredMotion with a column of ones per joint of ``joints`` (0-based) in that joint's rows:
    the offset columns (identify.observation.offsets.OffsetBase), constant through any filter."""
    from identify.observation.offsets import offset_columns

    S, n, _ = m.Phi.shape
    return replace(m, Phi=np.concatenate([m.Phi, offset_columns(S, n, joints)], axis=2))


def score_common_rate(robot: rx90sym.Robot, recordings: Sequence[Any], cand: Candidate, base: Any, reference: float | None,
           blocks: int, options: dict) -> tuple[float, tuple[float, ...], tuple[tuple[float, ...], ...]]:
    """(score, per joint, per held-back block and joint), relative errors in %; the rows decimated
    to the common scoring rate ``reference`` [Hz] (None: not decimated), whatever the candidate's."""
    min_velocity = options["min_velocity"] if cand.rest is not None else None
    rest = cand.rest or "zero-coulomb"
    # A presliding joint gets its magnitude FPj (travel PRESLIDING_TRAVEL), as in the fit.
    names, regressor = column_regressor(robot, base, rest=rest if min_velocity is not None else None)
    motions, _, _ = filtered_motions(robot, recordings, cand.cutoff, reference, options["spring"],
                                     regressor, names, min_velocity, rest, options.get("delay", 0.0))
    ids = time_blocks([m.t for m in motions], blocks)
    drop = min_velocity is not None and drops_rest(rest)
    n = robot.n
    # One compression per (block, joint): [R | z] of the QR of [W | Y] (eq. 10 on few rows).
    blocks_R = _compressed_blocks(motions, ids, blocks, drop, n)
    err2, ref2 = np.zeros((blocks, n)), np.zeros((blocks, n))
    for b in range(blocks):
        beta = fold_wls(blocks_R, b, n)
        if beta is None:
            continue
        for m, i in zip(motions, ids):
            held = np.flatnonzero(i == b)
            pred = m.Phi[held] @ beta
            meas = m.Y[held]
            ok = m.measured[held] if m.measured is not None else np.ones(held.size, dtype=bool)
            err2[b] += np.sum((pred - meas)[ok] ** 2, axis=0)
            ref2[b] += np.sum(meas[ok] ** 2, axis=0)
    if not np.any(ref2 > 0):
        raise ValueError("no fold could be fitted and scored (too few rows left after the filters' edges)")
    return block_scores(err2, ref2)


@dataclass(frozen=True, eq=False)
class RawTargets:
    """The raw samples every candidate is scored on: per segment (by its source name) the times
    (S,) [s], the measured torques (S, n) [N m] and the held-back block of each; the blocks' start
    and span [s]. The samples: measured, ``margin`` seconds from each segment's ends (beyond the
    edges of every candidate's filters), so that every candidate predicts all of them."""

    pieces: dict
    start: float
    span: float


def raw_targets(recordings: Sequence[Any], grid: Sequence[Candidate], blocks: int, delay: float = 0.0) -> RawTargets:
    """:class:`RawTargets` of ``recordings`` for the candidates of ``grid`` (its lowest cut-off and
    coarsest decimation set the margin)."""
    lowest = min(c.cutoff for c in grid)
    coarsest = min((c.decimate_to for c in grid if c.decimate_to), default=None)
    margin = EDGE_PERIODS / lowest + (2.0 / coarsest if coarsest else 0.0) + abs(delay)
    pieces = {}
    for rec in recordings:
        for piece in rec.pieces():
            t = np.asarray(piece.t, dtype=float)
            keep = (t >= t[0] + margin) & (t <= t[-1] - margin) & piece.measured_mask
            if keep.sum() >= 2:
                pieces[piece.source] = (t[keep], np.asarray(piece.torques, dtype=float)[keep])
    if not pieces:
        raise ValueError(f"no segment is longer than the {2 * margin:.3g} s the cross-validation's filters' edges need")
    start = min(float(t[0]) for t, _ in pieces.values())
    span = max(float(t[-1]) for t, _ in pieces.values()) - start + 1e-9
    return RawTargets({k: (t, tau, time_folds(t, start, span, blocks)) for k, (t, tau) in pieces.items()}, start, span)
