"""Processing chosen by blocked cross-validation (identify.selection.cross_validation), judged
against the noise-free torques of a twin run that the choice never sees."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import rx90sym
from identify import Processing, fit, predict, split
import identify.selection.processing_choice as scv
from identify.selection.processing_choice import choose_processing
from identify.selection.candidates import Candidate
from motions import multisine


def _held_out(robot, base, fit_part, clean_test, cand: Candidate) -> float:
    """Mean relative error (%) of the held-out prediction against the noise-free torques."""
    fit_ = fit(robot, [fit_part], Processing(cutoff=cand.cutoff, decimate_to=cand.decimate_to,
                                            rest=cand.rest or "zero-coulomb",
                                            min_velocity=0.05 if cand.rest else None, estimate_delay=False),
               base=base)
    val = predict(robot, fit_.result, clean_test, base=base, cutoff=cand.cutoff, decimate_to=None,
                  min_velocity=fit_.min_velocity, rest=fit_.rest)
    return float(np.mean(100 * np.linalg.norm(val.predicted - val.measured, axis=0)
                         / np.linalg.norm(val.measured, axis=0)))


@pytest.mark.slow
def test_the_cross_validated_choice_is_near_the_best_of_its_grid(rx90, rx90_base):
    profile = replace(rx90sym.twin.profiles()["quantised"], torque_noise=0.05)
    motion = multisine(rx90, 7)
    rec = rx90sym.twin.simulate(rx90, motion, duration=20.0, noise=profile, seed=7)
    clean = rx90sym.twin.simulate(rx90, motion, duration=20.0, noise=replace(profile, torque_noise=0.0), seed=7)
    fit_part, _ = split(rec, 2 / 3)
    _, clean_test = split(clean, 2 / 3)
    choice = choose_processing(rx90, [fit_part], base=rx90_base, blocks=3)
    scored = [c for c in choice.candidates if np.isfinite(c.score)]
    assert {c.rest for c in scored} >= {"zero-coulomb", "crossing"}
    assert any(c.label == "(default)" for c in choice.candidates) and "<- chosen" in choice.table()
    truth = {(c.cutoff, c.decimate_to, c.rest): _held_out(rx90, rx90_base, fit_part, clean_test, c) for c in scored}
    best = min(truth.values())
    # The twin's friction is Coulomb with no static part: Coulomb = 0 at rest is a model error that
    # the cross-validation sees in the torques; the rows below the threshold are reversals, which
    # "crossing" keeps as motions.
    assert choice.chosen.rest == "crossing", choice.reason()
    # Scored against the raw torques (5 % noise), candidates whose model errors differ by less than
    # 0.05 % of the torque are not told apart by the blocks: measured 1.10 x the best (0.372 % against
    # 0.338 %), where a zero-coulomb candidate is 5 x or more.
    assert truth[(choice.chosen.cutoff, choice.chosen.decimate_to, choice.chosen.rest)] <= 1.25 * best, truth
    zero = [v for (c, d, r), v in truth.items() if r == "zero-coulomb"]
    assert truth[(choice.chosen.cutoff, choice.chosen.decimate_to, "crossing")] < 0.2 * min(zero)


def test_a_given_cutoff_and_cross_validation_are_refused_together():
    with pytest.raises(ValueError, match="a cut-off is given and cross_validate asks to choose one"):
        Processing(cutoff=10.0, cross_validate=True)


def test_a_uniform_first_stage_policy_does_not_override_the_per_joint_rule(rx90, rx90_base, monkeypatch):
    """The rest policy is decided per joint (kept zero-coulomb where another is not clearly better);
    the cut-off is then chosen among candidates with that policy only. Scores are given by hand
    (the fits are tested above): crossing is lower on average at the knee but within the blocks'
    spread, so zero-coulomb stays, and the chosen candidate must carry it."""
    import identify.selection.cross_validation as cv

    blocks = {"zero-coulomb": (5.0, 5.5, 4.5, 5.2, 4.8), "crossing": (4.2, 5.9, 4.0, 5.6, 4.8)}
    default = (5.2, 5.4, 4.7, 5.3, 4.9)

    def fake_score(cand, context):
        per = default if cand.label == cv.DEFAULT_LABEL else blocks[cand.rest]
        per_block = tuple((v,) * context.robot.n for v in per)
        return float(np.mean(per)), (float(np.mean(per)),) * context.robot.n, per_block

    monkeypatch.setattr(scv, "_score", fake_score)
    rec = rx90sym.twin.simulate(rx90, multisine(rx90, 3), duration=4.0, noise="realistic", seed=3)
    grid = [Candidate(10.0, 25.0), Candidate(20.0, 50.0, label=cv.DEFAULT_LABEL)]
    choice = choose_processing(rx90, [rec], base=rx90_base, candidates=grid)
    assert choice.chosen.rest == "zero-coulomb", choice.table()
    # Crossing at the knee scored 4.90 (below the default's 5.10 by more than 2 %): before the rule
    # was kept it won the cut-off stage.
    assert any(c.rest == "crossing" and c.score < 0.98 * 5.1 for c in choice.candidates)


def _fake_scores(cand, context):
    """A scorer by hand (the fits are tested above): every candidate scores by its cut-off."""
    n = context.robot.n
    per = tuple(4.0 + 0.01 * cand.cutoff + 0.1 * b for b in range(context.span.blocks))
    return float(np.mean(per)), (float(np.mean(per)),) * n, tuple((v,) * n for v in per)


def test_the_choice_does_not_depend_on_the_wall_clock(rx90, rx90_base, monkeypatch):
    """A slow or loaded machine scores the same candidates and makes the same choice: the default cap
    counts observation rows, not seconds (the former 60 s wall-clock cap scored 5 of 5 cut-offs of one
    10.5 min log in one run and 4 of 5 in another). Here the clock jumps 1000 s at every reading."""
    import identify.selection.cross_validation as cv

    monkeypatch.setattr(scv, "_score", _fake_scores)
    rec = rx90sym.twin.simulate(rx90, multisine(rx90, 3), duration=4.0, noise="realistic", seed=3)
    calm = choose_processing(rx90, [rec], base=rx90_base)
    clock = iter(range(0, 10 ** 9, 1000))
    monkeypatch.setattr(cv.time, "perf_counter", lambda: float(next(clock)))
    slow = choose_processing(rx90, [rec], base=rx90_base)
    assert [c.score for c in slow.candidates] == [c.score for c in calm.candidates]
    assert all(np.isfinite(c.score) for c in calm.candidates), calm.table()
    assert (slow.chosen.cutoff, slow.chosen.decimate_to, slow.chosen.rest) == \
        (calm.chosen.cutoff, calm.chosen.decimate_to, calm.chosen.rest)
    # The wall-clock cap stays available on request, and then says so.
    capped = choose_processing(rx90, [rec], base=rx90_base, time_cap=60.0)
    assert any("not scored (time cap: 60 s)" in c.label for c in capped.candidates), capped.table()


def test_the_row_cap_stops_the_cut_offs_after_the_rest_policies_and_the_first(rx90, rx90_base, monkeypatch):
    """With a cap below two passes, the rest policies (always scored) and the first cut-off are scored,
    the others listed as not scored with the count that stopped them; without a cap, all are."""
    import identify.selection.cross_validation as cv

    monkeypatch.setattr(scv, "_score", _fake_scores)
    rec = rx90sym.twin.simulate(rx90, multisine(rx90, 3), duration=4.0, noise="realistic", seed=3)
    rows = rx90.n * rec.n_samples  # observation rows of one pass
    capped = choose_processing(rx90, [rec], base=rx90_base, row_cap=rows)
    policies = len(cv.SCORED_REST)
    scored = [c for c in capped.candidates if np.isfinite(c.score)]
    left = [c for c in capped.candidates if not np.isfinite(c.score)]
    assert len(scored) == policies + 1 and left, capped.table()
    assert all(f"not scored (row cap: {(policies + 1) * rows:,} rows processed > {rows:,})" in c.label
               for c in left), capped.table()
    free = choose_processing(rx90, [rec], base=rx90_base, row_cap=None)
    assert all(np.isfinite(c.score) for c in free.candidates)
