"""Friction form chosen by the blocked cross-validation, where the fit leaves it open (issue 21, item 4).

After :func:`identify.observation.cross_validation.choose_processing` has fixed the cut-off, the
decimation and the rest policy, each friction form of :data:`DEFAULT_FORMS` (Coulomb sign(q̇), the
smooth tanh(q̇/vs); Stribeck on request) is scored the same way, on the same contiguous blocks
(:func:`~identify.observation.cross_validation.time_blocks`: cut by time over the recordings'
common span):

1. one observation matrix of the fit's processing whose Coulomb columns hold the filtered,
   decimated driver speed v (:class:`~identify.observation.friction_model.FrictionBase` form
   "probe"), built once: the speeds the scale search needs;
2. for each held-back block, the velocity scales of a smooth form are searched **on the other
   blocks only** (separable least squares, :func:`identify.estimation.separable.scales_from_observation`),
   the base parameters fitted (WLS, eq. 11's weights, the processing's fold solver) on those rows,
   the held-back torques predicted;
3. every form is scored with the fit's **exact** columns (its own observation matrix: one for
   Coulomb, one per fold for a smooth form at that fold's scales). Evaluating the forms on the
   probe's decimated speed (sign(Dv), tanh(Dv/vs)) handicapped Coulomb against the fit's smooth
   D·sign(v) (TX40: 10.655 % instead of 8.427 %) and chose tanh where the held-out errors got worse.

**Coulomb unless clearly beaten**: a form replaces Coulomb only when its held-back error (mean over
joints of 100 ||Y_j - W_j beta|| / ||Y_j||) is lower by more than the standard error of the paired
difference over the blocks (the rest policy's rule, ``clearly_better``), and never when a fold's
search stopped on the upper bound of the scales (a second viscous term, the scale not identified;
on the lower bound the form is a sign on that joint, Coulomb's column: allowed) or did not converge. Forms after the first are not started once ``time_cap`` seconds are spent.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.observation.cross_validation import (DEFAULT_BLOCKS, Candidate, block_factors, block_scores,
                                                   clearly_better, fold_wls, time_blocks)
from identify.observation.friction import DEFAULT_FRICTION, FRICTION_FORMS
from identify.observation.friction_model import FrictionBase, coulomb_terms, own_terms
from identify.observation.matrix import Observation, observation_matrix

__all__ = ["DEFAULT_FORMS", "FRICTION_TIME_CAP", "FrictionChoice", "choose_friction"]

#: Forms scored where the fit leaves the friction open. Stribeck is scored on request only
#: (``forms=FRICTION_FORMS``): on the UR10e its fit gives FS1 < 0 (ill-posed on real data).
DEFAULT_FORMS = ("coulomb", "tanh")
#: Seconds after which no further form is scored (Coulomb, the first, always is).
FRICTION_TIME_CAP = 60.0


@dataclass(frozen=True)
class FrictionChoice:
    """The forms scored (``Candidate.label`` the form; its score, per joint and per block in %),
    the form chosen, why any form could not be chosen (``notes``: form -> reason), the number of
    blocks and the seconds spent."""

    candidates: tuple[Candidate, ...]
    chosen: str
    notes: tuple[tuple[str, str], ...]
    blocks: int
    seconds: float

    def table(self) -> str:
        n = max((len(c.per_joint) for c in self.candidates), default=0)
        lines = [f"friction form chosen by {self.blocks}-block cross-validation (velocity scales searched on the "
                 f"fitting blocks)\n  form       held-back error [%]" + "".join(f"{'j' + str(j + 1):>7}" for j in range(n))]
        notes = dict(self.notes)
        for c in self.candidates:
            score = "-" if math.isnan(c.score) else f"{c.score:.3f}"   # the note says why
            joints = "".join(f"{v:7.2f}" for v in c.per_joint)
            mark = " <- chosen" if c.label == self.chosen else ""
            note = f"  ({notes[c.label]})" if c.label in notes else ""
            lines.append(f"  {c.label:<9}  {score:>19}{joints}{note}{mark}")
        return "\n".join(lines + ["  " + self.reason()])

    def reason(self) -> str:
        scored = {c.label: c for c in self.candidates if not math.isnan(c.score)}
        chosen = scored.get(self.chosen)
        if self.chosen != DEFAULT_FRICTION:
            return (f"chosen: {self.chosen}, held-back error {chosen.score:.3f} % below coulomb's "
                    f"{scored[DEFAULT_FRICTION].score:.3f} % by more than the blocks' spread")
        others = [c for k, c in scored.items() if k != DEFAULT_FRICTION and k not in dict(self.notes)]
        if not others or chosen is None:
            return "chosen: coulomb (no other form could be chosen)"
        best = min(others, key=lambda c: c.score)
        return (f"chosen: coulomb, the default: {best.label}'s held-back error ({best.score:.3f} %) is not below "
                f"coulomb's ({chosen.score:.3f} %) by more than the blocks' spread")

    def to_dict(self) -> dict[str, Any]:
        return {"method": "blocked cross-validation", "blocks": self.blocks, "seconds": self.seconds,
                "chosen": self.chosen, "reason": self.reason(), "not_chosen": dict(self.notes),
                "candidates": [dict(c.to_dict(), form=c.label) for c in self.candidates], "table": self.table()}


def _exact(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any, options: dict[str, Any], probe: Observation,
           form: str, scales: Sequence[float] | None) -> np.ndarray:
    """W of ``form`` at ``scales`` with the fit's exact (parallel-filtered) columns, on the probe's rows."""
    from identify.observation.friction_model import friction_base

    columns = base if form == DEFAULT_FRICTION else friction_base(base, coulomb_terms(robot, base.names), form, scales)
    obs = observation_matrix(robot, recordings, base=columns, **options)
    if obs.W.shape[0] != probe.W.shape[0] or not np.array_equal(obs.joint, probe.joint):
        raise RuntimeError(f"friction choice: the observation of form {form!r} has other rows than the probe's")
    return obs.W


def _score_form(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any, options: dict[str, Any],
                obs: Observation, terms: Sequence[Any], form: str, ids: np.ndarray,
                blocks: int) -> tuple[Candidate, str | None]:
    """(the form scored, why it cannot be chosen or None); ``obs`` the probe observation."""
    n = robot.n
    from identify.estimation.separable import SCALE_BOUNDS, scales_from_observation

    err2, ref2 = np.zeros((blocks, n)), np.zeros((blocks, n))
    bound, failed = set(), set()
    W = None
    for b in range(blocks):
        fit_rows, held = ids != b, ids == b
        scales = None
        if form != DEFAULT_FRICTION:  # searched on the fitting blocks only: the held-back block is unseen
            sub = replace(obs, W=obs.W[fit_rows], Y=obs.Y[fit_rows], joint=obs.joint[fit_rows],
                          samples=obs.samples[fit_rows])
            found = scales_from_observation(sub, terms, form, n)
            scales = found.scales
            # The upper bound: the form is a second viscous term there, its scale not identified (on
            # the lower one it is a sign on that joint, Coulomb's own column: no reason to refuse it).
            bound.update(j + 1 for j, v in enumerate(found.scales) if v >= SCALE_BOUNDS[1] * (1 - 1e-3))
            if not found.converged:
                failed.add(b + 1)
        if W is None or scales is not None:  # Coulomb's columns (and their factors) do not depend on the fold
            W = _exact(robot, recordings, base, options, obs, form, scales)
            factors = block_factors(W, obs.Y, obs.joint, ids, range(blocks), n)
        beta = fold_wls(factors, b, n)  # eq. 11's per-joint weights, as the processing's folds
        if beta is None:
            raise ValueError(f"friction choice: too few rows to fit without block {b + 1}")
        res = obs.Y[held] - W[held] @ beta
        np.add.at(err2[b], obs.joint[held], res ** 2)
        np.add.at(ref2[b], obs.joint[held], obs.Y[held] ** 2)
    cand = Candidate(obs.cutoffs[0], None, obs.rest, *block_scores(err2, ref2), label=form)
    why = ([f"velocity scale on its upper bound {SCALE_BOUNDS[1]:g} rad/s for joint(s) {', '.join(map(str, sorted(bound)))}"] if bound else []) + \
          ([f"scale search not converged in fold(s) {', '.join(map(str, sorted(failed)))}"] if failed else [])
    return cand, "; ".join(why) or None


def choose_friction(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any, options: dict[str, Any],
                    forms: Sequence[str] = DEFAULT_FORMS, blocks: int = DEFAULT_BLOCKS,
                    time_cap: float = FRICTION_TIME_CAP) -> FrictionChoice:
    """Score the friction ``forms`` (Coulomb first, the default) by blocked cross-validation with the
    fit's observation ``options`` (cutoff, decimate_to, min_velocity, rest, spring, delay) and choose
    (module docstring). time_cap [s]: no form is started after it."""
    unknown = [f for f in forms if f not in FRICTION_FORMS]
    if unknown or DEFAULT_FRICTION not in forms:
        raise ValueError(f"friction choice: forms must include {DEFAULT_FRICTION!r} and be among "
                         f"{FRICTION_FORMS}, got {tuple(forms)!r}")
    if blocks < 2:
        raise ValueError(f"cross-validation needs at least 2 blocks, got {blocks}")
    start = time.perf_counter()
    inner = base.base if isinstance(base, FrictionBase) else base
    terms = own_terms(coulomb_terms(robot, inner.names))
    asymmetric = any(rx90sym.parameters.split_name(t.name)[0] in ("FSP", "FSN") for t in terms)
    if not terms or asymmetric:
        why = "asymmetric Coulomb joints keep the Coulomb form" if terms else "no Coulomb parameter"
        return FrictionChoice((), DEFAULT_FRICTION, tuple((f, why) for f in forms if f != DEFAULT_FRICTION),
                              blocks, 0.0)
    probe = FrictionBase(inner, tuple((t.row, t.column, t.driver) for t in terms), "probe")
    try:
        obs = observation_matrix(robot, recordings, base=probe, **options)
    except ValueError as exc:  # the fit's own observation then says what is wrong, in its words
        return FrictionChoice((), DEFAULT_FRICTION, tuple((f, f"not scored: {str(exc).splitlines()[0]}")
                                                          for f in forms if f != DEFAULT_FRICTION), blocks, 0.0)
    ids = time_blocks([obs.t], blocks)[0][obs.samples]  # the processing choice's folds, by time
    ordered = [DEFAULT_FRICTION] + [f for f in forms if f != DEFAULT_FRICTION]
    scored, notes = [], {}
    for form in ordered:
        if scored and time.perf_counter() - start > time_cap:
            scored.append(Candidate(obs.cutoffs[0], None, obs.rest, label=form))
            notes[form] = "not scored: time cap"
            continue
        t0 = time.perf_counter()
        try:
            cand, why = _score_form(robot, recordings, inner, options, obs, terms, form, ids, blocks)
        except ValueError as exc:  # too few rows in a fold, a form's columns rank deficient on the fitting blocks
            cand, why = Candidate(obs.cutoffs[0], None, obs.rest, label=form), f"not scored: {str(exc).splitlines()[0]}"
        scored.append(replace(cand, decimate_to=options.get("decimate_to"), seconds=time.perf_counter() - t0))
        if why:
            notes[form] = why
    default = scored[0]
    eligible = [c for c in scored[1:] if not math.isnan(c.score) and c.label not in notes]
    best = min(eligible, key=lambda c: c.score, default=None)
    clear = best is not None and not math.isnan(default.score) and clearly_better(best, default)
    chosen = best.label if clear else DEFAULT_FRICTION
    return FrictionChoice(tuple(scored), chosen, tuple(notes.items()), blocks, time.perf_counter() - start)
