"""Processing chosen on the torques: the cut-off and decimation by blocked cross-validation.

The position-spectrum knee (:func:`identify.signal.filtering.choose_cutoff`) looks at the positions
only; nothing checks it against the torques. Here every candidate processing (a cut-off ``fc`` of
the position filter, with the decimation to about 2.5 fc so that the parallel filter's pass band,
0.4 x the decimated rate, is the cut-off) is scored *inside the fitted data*:

1. the recordings' time span is cut into ``blocks`` contiguous blocks of equal duration;
2. for each block, the base parameters are fitted (WLS) on the rows of the other blocks and the
   torques of the held-back block are predicted;
3. every candidate is scored at one **common rate** (the grid's highest decimated rate): the rows
   of W and Y are decimated to it whatever the candidate's own decimation, so the held-back
   torque Y is the same signal for every candidate (its noise is common: no candidate is rewarded
   or punished for the noise its own filter lets through), while the noise the candidate's
   cut-off lets into its prediction counts; the score of joint j is 100 ||Y_j - W_j beta|| /
   ||Y_j|| over every held-back block, the candidate's score the mean over joints. (An earlier
   version low-passed prediction and torque at the lowest cut-off: it hid the prediction noise of
   the high cut-offs, and on the Panda twin kept 20 Hz where 5 Hz was 5x better.)

The grid is small: the knee times (0.5, 0.7, 1, 1.4, 2), within [2 Hz, 40 % of Nyquist], each
decimated to max(2.5 fc, 25 Hz), and the default processing (the automatic cut-off with the
default decimation). Where the fit leaves the rest policy open, every policy that keeps the rest
rows (:data:`SCORED_REST`: zero-coulomb, presliding, none, and any later one of
``REST_POLICIES``) is first scored at the knee, and each joint takes the policy of its lowest
per-joint score (the Coulomb column of joint j enters joint j's rows only: the choice is nearly
separable); the cut-offs are then scored with that per-joint policy.

**The default unless clearly beaten**: a policy replaces zero-coulomb on a joint, and a candidate
replaces the default processing, only when its held-back error is lower by more than the standard
error of the paired difference over the blocks (or, for the processing, by more than
:data:`CLEAR_MARGIN` of the default's score); a smaller difference keeps the default (on the
TX40, 26.6 and 20 Hz score 9.562 and 9.575 % while the held-out error of joint 1 is 2.196 and
1.806 N·m: the scores cannot tell them apart). Cut-offs are scored from the knee outwards and no
further one is started once the candidates scored have processed ``row_cap`` observation rows
(recorded samples x joints, one pass of a candidate over the recordings; those left are listed as
not scored): a cap on the work, not on the clock, so that the same log gets the same choice on any
machine under any load (a 60 s wall-clock cap scored 5 of 5 cut-offs of one 10.5 min log in one run
and 4 of 5 in another). ``time_cap`` adds a wall-clock cap on request. The rest policies and the
first cut-off are always scored. Bridged samples and rest rows follow the fit's rules (the
same rows as W). :func:`select_processing` is this selection whatever scores the candidates (in
memory here; block by block in :mod:`identify.estimation.stream_cv`).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any, Callable, Sequence

import numpy as np

import rx90sym

from identify.observation.matrix import (DECIMATION_PASSBAND, DEFAULT_MIN_VELOCITY, automatic_cutoff, column_regressor,
                                         filtered_motions, stack_rows)
from identify.observation.processing import DEFAULT_REST, REST_POLICIES, RestPolicy, drops_rest
from identify.signal.filtering import choose_cutoff
from identify.observation.candidates import CLEAR_MARGIN, DEFAULT_LABEL, Candidate, ProcessingChoice

__all__ = ["Candidate", "ProcessingChoice", "GRID_FACTORS", "DEFAULT_BLOCKS", "SCORED_REST",
           "candidate_grid", "grid_around", "choose_processing", "select_processing", "scoring_rate", "time_folds",
           "time_blocks", "fold_wls", "clearly_better", "block_factors", "block_scores", "DEFAULT_ROW_CAP", "Budget",
           "observation_rows"]

#: Cut-offs of the grid, as multiples of the position-spectrum knee.
GRID_FACTORS = (0.5, 0.7, 1.0, 1.4, 2.0)
#: Contiguous blocks of the cross-validation.
DEFAULT_BLOCKS = 5
#: Lowest rate a candidate decimates to, Hz (enough rows per block for the fits and the scores).
MIN_DECIMATED_RATE = 25.0
#: Observation rows (recorded samples x joints: one candidate's pass over the recordings) after which
#: no further cut-off is started. A count, not seconds: the choice is the same on any machine. 3e7 is
#: about 60 s of passes block by block on the 2-core reference machine (a 3.5 min 7-joint log at 1 kHz,
#: 1.5e6 rows, takes 3 s a pass), where logs held in memory (under 1e7 rows) never reach it.
DEFAULT_ROW_CAP = 30_000_000
#: The rest policies scored where the fit leaves it open: every one that keeps the rest rows (a
#: dropped row is not predicted the way it is scored), predicts a long rest from more than the
#: sign of noise ("none" does not: a joint held still in new data would flip by ±FS) and carries
#: no magnitude fitted on the rests of the fitted rows ("presliding": on the TX40 it scores 2-11 %
#: better per joint inside the first 6 s, yet takes joint 1's held-out error from 1.82 to 3.39 N·m
#: and joint 5's while moving up 5 %; choose_processing(policies=...) scores it on request).
SCORED_REST = tuple(r for r in REST_POLICIES if r not in ("drop", "none", "presliding"))



def candidate_grid(recordings: Sequence[Any], default_decimate: float | None = 50.0) -> tuple[float, list[Candidate]]:
    """(knee [Hz], candidates in scoring order: the knee first, the default (labelled, the
    automatic cut-off with ``default_decimate``), then outwards from the knee)."""
    rate = min(1.0 / float(np.median(np.diff(np.asarray(p.t)))) for r in recordings for p in r.pieces())
    knee = max(choose_cutoff(np.asarray(p.q), rate) for r in recordings for p in r.pieces()
               if p.n_samples >= 64)
    return knee, grid_around(knee, rate, automatic_cutoff(recordings, default_decimate), default_decimate)


def grid_around(knee: float, rate: float, default_cutoff: float, default_decimate: float | None) -> list[Candidate]:
    """The candidates around the position-spectrum ``knee`` [Hz] at the recordings' ``rate`` [Hz]
    (the knee first, the default processing (``default_cutoff`` [Hz], ``default_decimate`` [Hz]),
    then outwards): what :func:`candidate_grid` returns, from numbers a streamed scan also gives."""
    top = 0.4 * rate / 2.0
    cuts = sorted({min(max(2.0, f * knee), top) for f in GRID_FACTORS}, key=lambda c: abs(math.log(c / knee)))
    out = []
    for fc in cuts:
        target = max(fc / DECIMATION_PASSBAND, MIN_DECIMATED_RATE)  # pass band >= fc
        factor = max(1, int(math.floor(rate / target)))
        out.append(Candidate(fc, rate / factor if factor > 1 else None))
    default = Candidate(default_cutoff, default_decimate, label=DEFAULT_LABEL)
    out = [c for c in out if abs(c.cutoff - default_cutoff) > 1e-9 * default_cutoff or c.decimate_to != default_decimate]
    return out[:1] + [default] + out[1:]


def scoring_rate(grid: Sequence[Candidate]) -> float | None:
    """The common rate every candidate is scored at [Hz]: the highest decimated rate of the grid
    (None: one candidate is not decimated), so that every held-back torque is the same signal."""
    return None if any(c.decimate_to is None for c in grid) else max(c.decimate_to for c in grid)


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
    out = {}
    for b in range(blocks):
        rows = [m.rows(drop) & (i == b)[:, None] for m, i in zip(motions, ids)]
        W, Y, joint, _ = stack_rows([m.Phi for m in motions], [m.Y for m in motions], masks=rows)
        out.update(block_factors(W, Y, joint, np.full(joint.size, b), [b], n))
    return out


def block_factors(W: np.ndarray, Y: np.ndarray, joint: np.ndarray, ids: np.ndarray, blocks: Sequence[int],
                  n: int) -> dict[tuple[int, int], tuple[np.ndarray, int]]:
    """(block, joint) -> (the triangular factor of [W | Y] over the rows of that block (``ids``) and
    joint, their number), for the ``blocks`` listed: what :func:`fold_wls` solves from."""
    A = np.column_stack([W, Y])
    return {(b, j): (np.linalg.qr(A[m], mode="r"), int(m.sum())) for b in blocks for j in range(n)
            if (m := (ids == b) & (joint == j)).any()}


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
        x, *_ = np.linalg.lstsq(stacked[:, :c], stacked[:, c], rcond=None)
        resid = np.linalg.norm(stacked[:, :c] @ x - stacked[:, c])
        if rows <= c or resid == 0:
            return None
        systems.append(stacked / (resid / np.sqrt(rows - c)))  # sigma_j as in eq. 12, per joint
    R = np.vstack(systems)
    c = R.shape[1] - 1
    beta, *_ = np.linalg.lstsq(R[:, :c], R[:, c], rcond=None)
    return beta


def _score(robot: rx90sym.Robot, recordings: Sequence[Any], cand: Candidate, base: Any, reference: float | None,
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


def choose_processing(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any = None,
                      min_velocity: float | None = DEFAULT_MIN_VELOCITY, rest: RestPolicy | None = None,
                      spring: bool = True, blocks: int = DEFAULT_BLOCKS, row_cap: int | None = DEFAULT_ROW_CAP,
                      time_cap: float | None = None, default_decimate: float | None = 50.0,
                      candidates: Sequence[Candidate] | None = None, policies: Sequence[str] = SCORED_REST,
                      delay: float = 0.0) -> ProcessingChoice:
    """Score the candidate processings (module docstring) and choose the lowest held-back error.

    min_velocity [rad/s], spring: the fit's rest threshold (None: no rest handling) and spring (the
    rows of W); rest: the fit's rest policy, one or one per joint, or None (open: chosen per joint
    among ``policies``, default :data:`SCORED_REST`); blocks: contiguous blocks (>= 2); row_cap: no cut-off is
    started once the candidates scored have processed that many observation rows (None: no cap; the
    first is always scored); time_cap [s]: the same on the wall clock, on request (None: off, the
    default: the choice then never depends on the machine's speed); candidates: another grid (default
    :func:`candidate_grid`); delay [s]: the torque lag the fit compensates (every candidate is scored
    with it, as the fit will use it).
    """
    if blocks < 2:
        raise ValueError(f"cross-validation needs at least 2 blocks, got {blocks}")
    base = base if base is not None else rx90sym.base_parameters(robot)
    knee, grid = candidate_grid(recordings, default_decimate)
    grid = list(candidates) if candidates is not None else grid
    reference = scoring_rate(grid)
    options = {"min_velocity": min_velocity, "spring": spring, "delay": delay}
    budget = Budget(observation_rows(robot, recordings), row_cap, time_cap)
    return select_processing(lambda cand: _score(robot, recordings, cand, base, reference, blocks, options),
                             knee, grid, reference, blocks, min_velocity, rest, budget, policies)


def observation_rows(robot: rx90sym.Robot, recordings: Sequence[Any]) -> int:
    """Observation rows of one pass over ``recordings``: recorded samples x joints (every piece)."""
    return robot.n * sum(p.n_samples for r in recordings for p in r.pieces())


@dataclass(frozen=True)
class Budget:
    """What the cross-validated choices may spend: ``rows`` observation rows a candidate's pass costs
    (:func:`observation_rows`), no candidate started beyond ``row_cap`` rows processed (None: no
    cap), nor after ``time_cap`` seconds of wall clock (None, the default: off, so that nothing
    depends on the machine's speed or load)."""

    rows: int
    row_cap: int | None = DEFAULT_ROW_CAP
    time_cap: float | None = None

    def spent(self, scored: int, start: float) -> str | None:
        """Why no further candidate is started after ``scored`` passes begun at ``start``
        (time.perf_counter()), or None."""
        if self.row_cap is not None and scored * self.rows > self.row_cap:
            return f"row cap: {scored * self.rows:,} rows processed > {self.row_cap:,}"
        if self.time_cap is not None and time.perf_counter() - start > self.time_cap:
            return f"time cap: {self.time_cap:g} s"
        return None


Scorer = Callable[[Candidate], tuple[float, tuple[float, ...], tuple[tuple[float, ...], ...]]]  # as _score's


def select_processing(score: Scorer, knee: float, grid: Sequence[Candidate], reference: float | None, blocks: int,
                      min_velocity: float | None, rest: RestPolicy | None, budget: Budget,
                      policies: Sequence[str] = SCORED_REST) -> ProcessingChoice:
    """The selection of :func:`choose_processing` (and of the block-by-block choice,
    :mod:`identify.estimation.stream_cv`) whatever computes the scores: the rest policy per joint at
    the knee where it is open, the cut-offs from the knee outwards within the ``budget``, the
    default unless clearly beaten. ``grid``: the knee's candidate first, the default among them;
    ``reference``: the common scoring rate [Hz] (None: not decimated)."""
    start = time.perf_counter()
    first: list[Candidate] = []
    rest_scores: tuple[tuple[str, tuple[float, ...]], ...] = ()
    if min_velocity is None:
        rest = None
    elif rest is None:
        # First stage, at the knee: every policy that keeps the rest rows; each joint takes its best.
        first = _run(score, [replace(grid[0], rest=r) for r in policies], start, Budget(budget.rows, None, None))
        valid = [c for c in first if c.per_joint]
        rest_scores = tuple((str(c.rest), c.per_joint) for c in valid)
        rest = _per_joint_rest(valid) if valid else DEFAULT_REST
    done = {(f.cutoff, f.decimate_to, f.rest) for f in first}
    todo = [replace(c, rest=rest) for c in grid if (c.cutoff, c.decimate_to, rest) not in done]
    second = _run(score, todo, start, budget, always_first=True, scored_before=len(first))
    scored = first + second
    # Only candidates with the rest policy chosen above: a first-stage candidate (one policy for all
    # joints) must not override the per-joint rule that kept zero-coulomb where it was not beaten.
    chosen = _best([c for c in scored if c.rest == rest])
    default = next((c for c in second if c.label == DEFAULT_LABEL and c.per_block), None)
    if default is not None and not (clearly_better(chosen, default)
                                    or chosen.score < (1 - CLEAR_MARGIN) * default.score):
        chosen = default
    ordered = tuple(sorted(scored, key=lambda c: c.cutoff))
    return ProcessingChoice(ordered, chosen, knee, reference, blocks, time.perf_counter() - start, rest_scores)


def clearly_better(a: Candidate, b: Candidate, joint: int | None = None) -> bool:
    """Whether ``a``'s held-back error is below ``b``'s by more than the standard error of their
    paired difference over the blocks (of the mean over joints, or of ``joint``'s): a difference
    the blocks' spread can explain keeps ``b``, the default."""
    pa, pb = np.asarray(a.per_block), np.asarray(b.per_block)
    if pa.shape != pb.shape or pa.size == 0:
        return a.score < b.score
    d = pa - pb if joint is None else (pa - pb)[:, joint:joint + 1]
    d = np.array([row[np.isfinite(row)].mean() for row in d if np.isfinite(row).any()])  # blocks scored
    if d.size < 2:
        return bool(d.size and d[0] < 0)
    return bool(d.mean() + d.std(ddof=1) / math.sqrt(d.size) < 0)


def _per_joint_rest(scored: Sequence[Candidate]) -> RestPolicy:
    """Each joint's policy: the one of lowest per-joint score where it is clearly better
    (:func:`clearly_better` on that joint) than the default policy, else the default (one name
    when they all agree)."""
    n = len(scored[0].per_joint)
    default = next((c for c in scored if c.rest == DEFAULT_REST), None)
    policies = []
    for j in range(n):
        best = min(scored, key=lambda c: c.per_joint[j])
        keep = default is not None and best is not default and not clearly_better(best, default, j)
        policies.append(DEFAULT_REST if keep else str(best.rest))
    return policies[0] if len(set(policies)) == 1 else tuple(policies)


def _best(scored: Sequence[Candidate]) -> Candidate:
    valid = [c for c in scored if not math.isnan(c.score)]
    if not valid:  # each reason once (a recording without torques fails every candidate alike)
        reasons = dict.fromkeys(c.label.partition("not scored: ")[2] or c.label for c in scored)
        raise ValueError(next(iter(reasons)) if len(reasons) == 1 else
                         "no candidate processing could be fitted: " + "; ".join(reasons))
    return min(valid, key=lambda c: c.score)


def _run(score: Scorer, grid: Sequence[Candidate], start: float, budget: Budget, always_first: bool = False,
         scored_before: int = 0) -> list[Candidate]:
    """Score ``grid`` in order; none is started once the ``budget`` is spent (counting the passes
    ``scored_before``), but the first with ``always_first``; ``start``: time.perf_counter() of the choice."""
    scored: list[Candidate] = []
    passes = scored_before
    for cand in grid:
        spent = budget.spent(passes, start)
        if spent and (scored or not always_first):
            scored.append(replace(cand, label=f"{cand.label} not scored ({spent})".strip()))
            continue
        t0 = time.perf_counter()
        passes += 1
        try:
            value, per_joint, per_block = score(cand)
        except ValueError as exc:  # too few rows left to fit (a low rate on a short recording)
            scored.append(replace(cand, label=f"{cand.label} not scored: {str(exc).splitlines()[0]}".strip()))
            continue
        scored.append(replace(cand, score=value, per_joint=per_joint, per_block=per_block,
                              seconds=time.perf_counter() - t0))
    return scored
