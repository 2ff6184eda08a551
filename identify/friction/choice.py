"""The friction form chosen per joint by the blocked cross-validation, where the fit leaves it open.

Once the processing is chosen (:mod:`identify.selection.processing_choice`: the cut-off, the decimation
and the rest policy), each friction form of :data:`DEFAULT_FORMS` (Coulomb sign(q̇), the smooth
tanh(q̇/vs); Stribeck on request) is scored on the same contiguous time blocks, reading the fit's rows in
passes block by block (:mod:`identify.friction.folds`: everything from per-(time block, joint) triangular
factors, so the choice does not depend on the blocks):

1. the probe columns, whose own Coulomb columns hold the filtered, decimated driver speed v
   (:class:`~identify.friction.columns.FrictionBase` form "probe"): the speeds the scale
   search needs, tabulated on grids of scales (:mod:`identify.friction.scale_search`, two passes);
2. for each held-back block, the velocity scales of a smooth form are searched **on the other
   blocks only** (separable least squares, :func:`identify.friction.folds.fold_scales_of`),
   the base parameters fitted (the fit's weighted least squares) on those rows, the held-back torques
   predicted;
3. every form is scored with the fit's **exact** columns (one pass for Coulomb, one per smooth form
   holding every fold's columns at that fold's scales, :class:`~identify.friction.folds.FoldColumns`),
   not with the forms evaluated on the probe's decimated speed (sign(Dv) handicaps Coulomb against the
   fit's D·sign(v)).

**Per joint, Coulomb unless clearly beaten on that joint**: a real arm has different drives per
joint, so each joint takes the form of lowest held-back error on that joint (100 ||Y_j - W_j beta||
/ ||Y_j||) where it is lower than Coulomb's by more than the standard error of the paired
difference over the blocks on that joint (``clearly_better(a, b, joint)``, the rest policy's rule;
the Coulomb column of joint j enters joint j's rows only, so the choice is nearly separable), else
Coulomb. A form is not taken on a joint whose scale stopped on a bound in a fold: on the upper
one it is a second viscous term, the scale not identified; on the lower one it is a sign on that
joint, Coulomb's own column, so Coulomb, the simpler form, is kept. Nor is a form taken anywhere when
a fold's search did not converge.

**One joint-combined check**: the joints share the other parameters, so when the per-joint forms
mix, they are scored together (the scales of their smooth joints only searched on the fitting
blocks, the Coulomb joints keep sign(q̇)); the mix is kept when that score is not above the best
single form's (Coulomb unless a form clearly beats it on the mean over joints), else that single
form is chosen and the record says why (``FrictionChoice.fallback``). Forms after the first, and
the combined check, are not started once the passes scored exceed the processing choice's row cap
(:class:`~identify.selection.cross_validation.Budget`: a count of observation rows, never the
wall clock unless asked).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.friction.columns import friction_probe
from identify.friction.folds import FoldRows
from identify.friction.forms import DEFAULT_FRICTION, FRICTION_FORMS
from identify.observation.processing import FrictionForm, friction_label, has_smooth_friction, uniform
from identify.selection.candidates import joint_cells
from identify.selection.candidates import Candidate
from identify.selection.cross_validation import DEFAULT_ROW_CAP, Budget, clearly_better
from identify.selection.folds import block_scores

__all__ = ["DEFAULT_FORMS", "FrictionChoice", "choose_friction"]

#: Forms scored where the fit leaves the friction open. Stribeck is scored on request only
#: (``forms=FRICTION_FORMS``): on the UR10e its fit gives FS1 < 0 (ill-posed on real data).
DEFAULT_FORMS = ("coulomb", "tanh")


@dataclass(frozen=True)
class FrictionChoice:
    """The forms scored (``Candidate.label`` the form; its score, per joint and per block in %),
    the form chosen (one, or one per joint), why any form could not be chosen (``notes``: form ->
    reason), the number of blocks and the seconds spent; the per-joint rule's forms
    (``per_joint``: each joint's form of lowest score where clearly below Coulomb's on that joint),
    their joint-combined score (``combined``, scored when they mix forms; None otherwise) and,
    when the mix was not kept, why (``fallback``: the best single form is chosen instead)."""

    candidates: tuple[Candidate, ...]
    chosen: str | tuple[str, ...]
    notes: tuple[tuple[str, str], ...]
    blocks: int
    seconds: float
    per_joint: tuple[str, ...] = ()
    combined: Candidate | None = None
    fallback: str = ""

    def table(self) -> str:
        n = max((len(c.per_joint) for c in self.candidates), default=0)
        rate = self.candidates[0].decimate_to if self.candidates else None
        lines = [f"friction form chosen per joint by {self.blocks}-block cross-validation (velocity scales searched "
                 f"on the fitting blocks; scored on the fit's own rows, "
                 f"{'not decimated' if rate is None else f'at {rate:.4g} Hz'}, not at the processing table's "
                 f"common rate)\n  form       held-back error [%]" + "".join(f"{'j' + str(j + 1):>7}" for j in range(n))]
        notes = dict(self.notes)
        rows = self.candidates + ((self.combined,) if self.combined is not None else ())
        for c in rows:
            score = "-" if math.isnan(c.score) else f"{c.score:.3f}"   # the note says why
            joints = joint_cells(c.per_joint)
            mark = " <- chosen" if c.label == self.chosen or (c is self.combined and not self.fallback) else ""
            note = f"  ({notes[c.label]})" if c.label in notes else ""
            lines.append(f"  {c.label:<9}  {score:>19}{joints}{note}{mark}")
        if self.per_joint:
            lines.append(f"  per joint: {friction_label(self.per_joint)}")
        return "\n".join(lines + ["  " + self.reason()])

    def reason(self) -> str:
        scored = {c.label: c for c in self.candidates if not math.isnan(c.score)}
        rule = ("each joint takes the form of lowest held-back error on that joint where it is below coulomb's by "
                f"more than the blocks' spread, else coulomb")
        if isinstance(self.chosen, tuple):
            single = _single_choice(self.candidates, dict(self.notes))
            return (f"chosen per joint: {friction_label(self.chosen)} ({rule}); their joint-combined held-back error "
                    f"{self.combined.score:.3f} % is not above the best single form's ({single.label}, "
                    f"{single.score:.3f} %)")
        if self.fallback:
            return (f"{self._single_reason(scored)}; the per-joint forms ({friction_label(self.per_joint)}) were "
                    f"not kept: {self.fallback}")
        if self.per_joint and self.chosen != DEFAULT_FRICTION:
            return (f"chosen: {self.chosen} on every joint ({rule}), held-back error {scored[self.chosen].score:.3f} % "
                    f"against coulomb's {scored[DEFAULT_FRICTION].score:.3f} %")
        return f"{self._single_reason(scored)} ({rule})" if self.per_joint else self._single_reason(scored)

    def _single_reason(self, scored: dict[str, Candidate]) -> str:
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
        chosen = self.chosen if isinstance(self.chosen, str) else list(self.chosen)
        combined = None if self.combined is None else dict(self.combined.to_dict(), form=list(self.per_joint))
        return {"method": "blocked cross-validation", "blocks": self.blocks, "seconds": self.seconds,
                "chosen": chosen, "reason": self.reason(), "not_chosen": dict(self.notes),
                "per_joint": list(self.per_joint), "combined": combined, "fallback": self.fallback or None,
                "candidates": [dict(c.to_dict(), form=c.label) for c in self.candidates], "table": self.table()}


@dataclass(frozen=True)
class _Scored:
    """One form scored: the candidate, the joints (1-based) whose scale reached the upper bound in
    some fold, those whose scale reached the lower bound in some fold (``floor``: the form is
    Coulomb's sign there), the folds (1-based) whose search did not converge."""

    candidate: Candidate
    bound: frozenset[int] = frozenset()
    failed: frozenset[int] = frozenset()
    floor: frozenset[int] = frozenset()

    def why(self) -> str | None:
        """Why the form cannot be chosen for the whole robot (None: it can)."""
        from identify.friction.scales import SCALE_BOUNDS

        why = ([f"velocity scale on its upper bound {SCALE_BOUNDS[1]:g} rad/s for joint(s) "
                f"{', '.join(map(str, sorted(self.bound)))}"] if self.bound else []) + \
              ([f"scale search not converged in fold(s) {', '.join(map(str, sorted(self.failed)))}"] if self.failed else [])
        return "; ".join(why) or None


def _score_form(rows: Any, robot: rx90sym.Robot, inner: Any, probe: Any, terms: Sequence[Any], form: FrictionForm,
                label: str) -> _Scored:
    """``form`` (one, or one per joint) scored on the folds of ``rows`` (:mod:`identify.friction.folds`):
    each fold's scales searched on its fitting blocks only (the held-back block unseen), the form's exact
    columns at them, the held-back errors."""
    from identify.friction.folds import fold_scales_of, held_back_errors
    from identify.friction.scales import SCALE_BOUNDS

    n = robot.n
    bound, failed, floor = set(), set(), set()
    per_fold = fold_scales_of(rows, probe, terms, form, n) if has_smooth_friction(form) else None
    for b, found in enumerate(per_fold or ()):
        # The upper bound: the form is a second viscous term there, its scale not identified; on
        # the lower one it is a sign on that joint, Coulomb's own column: Coulomb is kept there.
        top = [v >= SCALE_BOUNDS[1] * (1 - 1e-3) for v in found.scales]
        bound.update(j + 1 for j, high in enumerate(top) if high)
        floor.update(j + 1 for j, (low, high) in enumerate(zip(found.at_bound, top)) if low and not high)
        if not found.converged:
            failed.add(b + 1)
    err2, ref2 = held_back_errors(rows, inner, terms, form, None if per_fold is None else [f.scales for f in per_fold], n)
    cand = Candidate(rows.processing.cutoff, None, rows.processing.rest, *block_scores(err2, ref2), label=label)
    return _Scored(cand, frozenset(bound), frozenset(failed), frozenset(floor))


def _per_joint_forms(scored: dict[str, _Scored], rows: Sequence[int], n: int) -> tuple[str, ...]:
    """Each joint's form: the one of lowest held-back error on that joint where it is clearly below
    Coulomb's on that joint (:func:`clearly_better`, paired blocks), else Coulomb. A form is not
    taken on a joint whose scale reached a bound in a fold (the upper: a second viscous term; the
    lower: Coulomb's sign, kept as Coulomb), nor anywhere when a fold's search failed;
    a joint without a Coulomb term (``rows``: those with one, 0-based) keeps Coulomb."""
    default = scored[DEFAULT_FRICTION].candidate
    forms = []
    for j in range(n):
        eligible = [x.candidate for x in scored.values() if x.candidate.per_joint and not x.failed
                    and j + 1 not in x.bound | x.floor and np.isfinite(x.candidate.per_joint[j])]
        best = min(eligible, key=lambda c: c.per_joint[j], default=default)
        take = j in rows and best.label != DEFAULT_FRICTION and clearly_better(best, default, j)
        forms.append(best.label if take else DEFAULT_FRICTION)
    return tuple(forms)


def choose_friction(robot: rx90sym.Robot, rows: FoldRows, base: Any, total_rows: int,
                    forms: Sequence[str] = DEFAULT_FORMS, row_cap: int | None = DEFAULT_ROW_CAP,
                    time_cap: float | None = None) -> FrictionChoice:
    """Score the friction ``forms`` (Coulomb first, the default) by blocked cross-validation on the fit's
    ``rows`` (:class:`~identify.friction.folds.FoldRows`: its processing, time blocks and columns ``base``)
    and choose per joint (module docstring). total_rows: the observation rows of one pass (the row cap's
    unit); row_cap: no form is started once the forms scored have processed that many observation rows
    (None: no cap); time_cap [s]: the same on the wall clock, on request (None, the default: off)."""
    unknown = [f for f in forms if f not in FRICTION_FORMS]
    if unknown or DEFAULT_FRICTION not in forms:
        raise ValueError(f"friction choice: forms must include {DEFAULT_FRICTION!r} and be among "
                         f"{FRICTION_FORMS}, got {tuple(forms)!r}")
    blocks = rows.blocks
    if blocks < 2:
        raise ValueError(f"cross-validation needs at least 2 blocks, got {blocks}")
    start = time.perf_counter()
    budget, passes = Budget(total_rows, row_cap, time_cap), 0
    inner, probe, terms, asymmetric = friction_probe(robot, base)
    if not terms or asymmetric:
        why = "asymmetric Coulomb joints keep the Coulomb form" if terms else "no Coulomb parameter"
        return FrictionChoice((), DEFAULT_FRICTION, tuple((f, why) for f in forms if f != DEFAULT_FRICTION),
                              blocks, 0.0)
    try:
        # Coulomb's rows first: a processing the fit cannot use is said by the fit's own observation, in its words.
        coulomb = _score_form(rows, robot, inner, probe, terms, DEFAULT_FRICTION, DEFAULT_FRICTION)
    except ValueError as exc:
        return FrictionChoice((), DEFAULT_FRICTION, tuple((f, f"not scored: {str(exc).splitlines()[0]}")
                                                          for f in forms if f != DEFAULT_FRICTION), blocks, 0.0)
    passes = 1

    def score(form: FrictionForm, label: str) -> tuple[_Scored, str | None]:
        """The form scored (or not: the budget spent, too few rows) and why it cannot be chosen (None: it can)."""
        nonlocal passes
        spent = budget.spent(passes, start)
        if label != DEFAULT_FRICTION and spent:
            return _Scored(Candidate(rows.processing.cutoff, None, rows.processing.rest, label=label)), f"not scored: {spent}"
        t0 = time.perf_counter()
        passes += 1
        try:
            done = _score_form(rows, robot, inner, probe, terms, form, label)
        except ValueError as exc:  # too few rows in a fold, a form's columns rank deficient on the fitting blocks
            return _Scored(Candidate(rows.processing.cutoff, None, rows.processing.rest, label=label)), \
                f"not scored: {str(exc).splitlines()[0]}"
        return _with_rate(done, rows, time.perf_counter() - t0), done.why()

    ordered = [DEFAULT_FRICTION] + [f for f in forms if f != DEFAULT_FRICTION]
    scored, notes = {}, {}
    for form in ordered:
        scored[form], why = (_with_rate(coulomb, rows, time.perf_counter() - start), None) \
            if form == DEFAULT_FRICTION else score(form, form)
        if why:
            notes[form] = why
    single = _single_choice([x.candidate for x in scored.values()], notes)
    per_joint = _per_joint_forms(scored, sorted({t.row for t in terms}), robot.n)
    chosen, combined, fallback = _check_mix(per_joint, single, scored, score)
    return FrictionChoice(tuple(x.candidate for x in scored.values()), chosen, tuple(notes.items()), blocks,
                          time.perf_counter() - start, per_joint, combined, fallback)


def _with_rate(done: _Scored, rows: Any, seconds: float) -> _Scored:
    """The scored form's candidate with the rows' decimated rate and the seconds it took."""
    return replace(done, candidate=replace(done.candidate, decimate_to=rows.processing.decimate_to, seconds=seconds))


def _single_choice(candidates: Sequence[Candidate], notes: dict[str, str]) -> Candidate:
    """The best single form for the whole robot: Coulomb (the first) unless clearly beaten
    (:func:`clearly_better` on the mean over joints) by the best form that can be chosen."""
    default = candidates[0]
    eligible = [c for c in candidates[1:] if not math.isnan(c.score) and c.label not in notes]
    best = min(eligible, key=lambda c: c.score, default=None)
    clear = best is not None and not math.isnan(default.score) and clearly_better(best, default)
    return best if clear else default


def _check_mix(per_joint: tuple[str, ...], single: Candidate, scored: dict[str, _Scored],
               score: Any) -> tuple[FrictionForm, Candidate | None, str]:
    """(the form chosen, the joint-combined candidate, why the per-joint forms were not kept): the
    per-joint forms when their joint-combined held-back error is not above the best single form's
    (scored here when they mix forms: the joints share the other parameters), else that single form."""
    mixed = uniform(per_joint)
    if isinstance(mixed, str):   # one form on every joint: its own score is the combined one
        combined, why = scored[mixed].candidate, scored[mixed].why()
        if mixed == single.label:
            return mixed, None, ""
    else:
        found, why = score(per_joint, "per joint")
        combined = found.candidate
    if why:
        return single.label, (None if isinstance(mixed, str) else combined), f"scored together, {why}"
    if math.isnan(combined.score) or math.isnan(single.score) or combined.score > single.score:
        return single.label, (None if isinstance(mixed, str) else combined), (
            f"their joint-combined held-back error ({combined.score:.3f} %) is above {single.label}'s "
            f"({single.score:.3f} %)")
    return mixed, (None if isinstance(mixed, str) else combined), ""
