"""Processing chosen on the torques: the cut-off and decimation by blocked cross-validation.

The position-spectrum knee (:func:`identify.signal.filtering.choose_cutoff`) looks at the positions
only; nothing checks it against the torques. Here every candidate processing (a cut-off ``fc`` of
the position filter, with the decimation to about 2.5 fc so that the parallel filter's pass band,
0.4 x the decimated rate, is the cut-off) is scored *inside the fitted data*:

1. the recordings' time span is cut into ``blocks`` contiguous blocks of equal duration;
2. for each block, the base parameters are fitted (WLS) on the rows of the other blocks and the
   torques of the held-back block are predicted;
3. every candidate is scored against the **raw measured torques** (:mod:`identify.selection.raw_torque_scores`):
   its held-back prediction, at its own cut-off and decimation, is interpolated (linearly) onto the
   recordings' own time stamps and compared with the torques the log holds, unfiltered, on the same
   samples for every candidate (measured, beyond the edges of the grid's lowest cut-off): no
   candidate is judged on its own filtered torques, the noise of the torques is common to all, the
   noise a cut-off lets into the prediction counts. The score of joint j is 100 ||tau_j - tau^_j|| /
   ||tau_j|| over every held-back block, the candidate's score the mean over joints. (Torques filtered
   for the scoring would hide the prediction noise of the high cut-offs: docs/real-logs.md.)

The grid is small: the knee times (0.5, 1, 2), within [10 Hz (:data:`MIN_GRID_CUTOFF`, the plain
baseline's cut-off: a knee is the fitted motion's, and a prediction of another motion filtered below
it loses that motion's acceleration), 40 % of Nyquist], each
decimated to max(2.5 fc, 25 Hz), the knee without decimation, and the default processing (the
automatic cut-off with the default decimation). Where the fit allows torque offsets (``offsets``:
not beside the robot's own offsets nor on a joint with asymmetric Coulomb friction, collinear with
an offset), the chosen processing is scored once more with an offset on each allowed joint, and a
joint keeps its offset where it lowers that joint's held-back error by more than the blocks' spread
(the offset of joint j enters joint j's rows only). Where the fit leaves the rest policy open, every policy that keeps the rest
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
same rows as W). :func:`select_processing` is this selection whatever scores the candidates; the
choice itself, on recordings in memory or read block by block (one implementation), is
:mod:`identify.selection.processing_choice` (``choose_processing``).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any, Callable, Sequence

import numpy as np

import rx90sym

from identify.observation.matrix import DECIMATION_PASSBAND
from identify.observation.processing import DEFAULT_REST, REST_POLICIES, RestPolicy
from identify.selection.candidates import CLEAR_MARGIN, Candidate, DEFAULT_LABEL, ProcessingChoice
from identify.selection.folds import block_scores, time_blocks, time_folds

__all__ = ["GRID_FACTORS", "DEFAULT_BLOCKS", "SCORED_REST", "RAW", "NO_DECIMATION",
           "grid_around", "select_processing", "score_candidates", "clearly_better", "DEFAULT_ROW_CAP", "Budget",
           "observation_rows", "NoCandidateScored"]

#: Cut-offs of the grid, as multiples of the position-spectrum knee. (0.5, 0.7, 1, 1.4, 2) until the
#: candidates without decimation and with offsets came: 0.7 and 1.4 were dropped to keep the choice's
#: cost (scored against the raw torques, neighbouring cut-offs at one decimation scored alike).
GRID_FACTORS = (0.5, 1.0, 2.0)
#: Lowest cut-off of the grid [Hz] (or 40 % of Nyquist where lower): the plain baseline's. The knee is a
#: property of the fitted motion; a prediction of another motion filtered below it loses that motion's
#: acceleration (twin trial, tests/twin_logs.py: a chirp up to 1 Hz fitted, knee 2.1 Hz, chosen in 2 of 5
#: seeds; the trapezoidal motion predicted 1.46-1.67x the baseline's error while moving on joints 1-3).
MIN_GRID_CUTOFF = 10.0
#: ``reference`` of a choice scored against the raw measured torques (ProcessingChoice.reference_hz).
RAW = "raw"
#: Label of the candidate without decimation (grid_around).
NO_DECIMATION = "no decimation"
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



class NoCandidateScored(ValueError):
    """No candidate processing could be scored (each one's reason in the message): the fit falls back on the
    fixed defaults (:func:`identify.fitting.passes.fit_streamed`)."""


def grid_around(knee: float, rate: float, default_cutoff: float, default_decimate: float | None) -> list[Candidate]:
    """The candidates around the position-spectrum ``knee`` [Hz] at the recordings' ``rate`` [Hz]
    (lowest segment rate) in scoring order: the knee first, the default processing (``default_cutoff``
    [Hz], the automatic cut-off raised to the grid's floor :data:`MIN_GRID_CUTOFF`, ``default_decimate``
    [Hz]), the knee without decimation (:data:`NO_DECIMATION`), then outwards from the knee."""
    top = 0.4 * rate / 2.0
    floor = min(MIN_GRID_CUTOFF, top)
    cuts = sorted({min(max(floor, f * knee), top) for f in GRID_FACTORS}, key=lambda c: abs(math.log(c / knee)))
    default_cutoff = max(default_cutoff, floor)  # without decimation the automatic cut-off is the knee itself
    out = []
    for fc in cuts:
        target = max(fc / DECIMATION_PASSBAND, MIN_DECIMATED_RATE)  # pass band >= fc
        factor = max(1, int(math.floor(rate / target)))
        out.append(Candidate(fc, rate / factor if factor > 1 else None))
    default = Candidate(default_cutoff, default_decimate, label=DEFAULT_LABEL)
    out = [c for c in out if abs(c.cutoff - default_cutoff) > 1e-9 * default_cutoff or c.decimate_to != default_decimate]
    out = out[:1] + [default] + out[1:]
    # No decimation, at the knee: the rows at the recordings' own rate (scored against the raw torques like the
    # others). Third, after the knee and the default.
    if out[0].decimate_to is not None:
        out.insert(2, Candidate(out[0].cutoff, None, label=NO_DECIMATION))
    return out


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


Scorer = Callable[[Candidate], tuple[float, tuple[float, ...], tuple[tuple[float, ...], ...]]]  # (score, per joint, per held-back block)


def select_processing(score: Scorer, knee: float, grid: Sequence[Candidate], reference: float | None, blocks: int,
                      min_velocity: float | None, rest: RestPolicy | None, budget: Budget,
                      policies: Sequence[str] = SCORED_REST) -> ProcessingChoice:
    """The selection of the cross-validated choice (:mod:`identify.selection.processing_choice`) whatever
    computes the scores: the rest policy per joint at the knee where it is open, the cut-offs from
    the knee outwards within the ``budget``, the default unless clearly beaten. ``grid``: the knee's
    candidate first, the default among them; ``reference``: what the candidates were scored against
    (:data:`RAW`: the raw measured torques; a rate [Hz]: rows decimated to it; None: not decimated)."""
    start = time.perf_counter()
    first: list[Candidate] = []
    rest_scores: tuple[tuple[str, tuple[float, ...]], ...] = ()
    if min_velocity is None:
        rest = None
    elif rest is None:
        # First stage, at the knee: every policy that keeps the rest rows; each joint takes its best.
        first = score_candidates(score, [replace(grid[0], rest=r) for r in policies], start, Budget(budget.rows, None, None))
        valid = [c for c in first if c.per_joint]
        rest_scores = tuple((str(c.rest), c.per_joint) for c in valid)
        rest = _per_joint_rest(valid) if valid else DEFAULT_REST
    done = {(f.cutoff, f.decimate_to, f.rest) for f in first}
    todo = [replace(c, rest=rest) for c in grid if (c.cutoff, c.decimate_to, rest) not in done]
    second = score_candidates(score, todo, start, budget, always_first=True, scored_before=len(first))
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
        raise NoCandidateScored(next(iter(reasons)) if len(reasons) == 1 else
                                "no candidate processing could be fitted: " + "; ".join(reasons))
    return min(valid, key=lambda c: c.score)


def score_candidates(score: Scorer, grid: Sequence[Candidate], start: float, budget: Budget, always_first: bool = False,
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
