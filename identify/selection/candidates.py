"""A candidate processing of the cross-validated choice and the choice's record (table, reason, JSON):
:mod:`identify.selection.cross_validation` scores them."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

from identify.observation.processing import DEFAULT_REST, RestPolicy, rest_label

__all__ = ["CLEAR_MARGIN", "DEFAULT_LABEL", "Candidate", "ProcessingChoice", "joint_cells"]

#: A cut-off also replaces the default's when its score is lower by this share of the default's.
CLEAR_MARGIN = 0.02
#: Label of the default processing's candidate (the automatic cut-off and decimation).
DEFAULT_LABEL = "(default)"


@dataclass(frozen=True)
class Candidate:
    """One processing: cut-off [Hz], decimation target [Hz] (None: none), rest policy, one or one per
    joint (None: no rest threshold, every row a moving one), its cross-validated
    score (mean over joints of the relative held-back error, %; nan: not scored), per joint (%),
    and the seconds it took."""

    cutoff: float
    decimate_to: float | None
    rest: RestPolicy | None = None
    score: float = math.nan
    per_joint: tuple[float, ...] = ()
    per_block: tuple[tuple[float, ...], ...] = ()
    seconds: float = 0.0
    label: str = ""

    def to_dict(self) -> dict[str, Any]:
        rest = list(self.rest) if isinstance(self.rest, tuple) else self.rest
        return {"cutoff_hz": self.cutoff, "decimate_to_hz": self.decimate_to, "rest": rest,
                "score_pct": None if math.isnan(self.score) else self.score,
                "per_joint_pct": _finite(self.per_joint), "seconds": self.seconds, "label": self.label}


@dataclass(frozen=True)
class ProcessingChoice:
    """The candidates scored, the chosen one (lowest score), the knee [Hz], the common scoring rate
    [Hz] (None: not decimated; "raw": scored against the raw measured torques), the number of blocks, the time spent [s] and, where the rest policy was open,
    the per-joint scores [%] of each policy at the knee (``rest_scores``); the joints given a torque offset
    (``offsets``, 0-based), the chosen processing scored with offsets (``offset_candidate``) and the joints
    not offered one because the fitted rows cannot separate it from their other columns
    (``inseparable_offsets``); ``skipped``: why no candidate was scored (a recording too short for the
    blocks: how long it is and must be), the fixed defaults then ``chosen``, '' when scored."""

    candidates: tuple[Candidate, ...]
    chosen: Candidate
    knee: float
    reference_hz: float | str | None
    blocks: int
    seconds: float
    rest_scores: tuple[tuple[str, tuple[float, ...]], ...] = ()
    offsets: tuple[int, ...] = ()
    offset_candidate: Candidate | None = None
    inseparable_offsets: tuple[int, ...] = ()
    skipped: str = ""

    def table(self) -> str:
        if self.skipped:
            c = self.chosen
            dec = "no decimation" if c.decimate_to is None else f"decimation to {c.decimate_to:.4g} Hz"
            return (f"processing not cross-validated: {self.skipped}; the fixed defaults: cut-off {c.cutoff:.4g} Hz "
                    f"(position spectrum), {dec}, rest {_rest_text(c.rest)}, no torque offsets")
        n = max((len(c.per_joint) for c in self.candidates), default=0)
        scored = ("against the raw measured torques, at the recordings' own time stamps" if self.reference_hz == "raw"
                  else "at the full rate" if self.reference_hz is None else f"at {self.reference_hz:.4g} Hz")
        head = (f"processing chosen by {self.blocks}-block cross-validation (scored {scored}; "
                f"knee {self.knee:.3g} Hz)\n  cut-off [Hz]  decimate to [Hz]  "
                f"held-back error [%]" + "".join(f"{'j' + str(j + 1):>7}" for j in range(n)) + "  rest policy")
        lines = [head]
        for c in self.candidates:
            mark = " <- chosen" if c is self.chosen else ""
            score = (("-" if "not scored" in c.label else "not scored") if math.isnan(c.score) else f"{c.score:.3f}")
            dec = "none" if c.decimate_to is None else f"{c.decimate_to:.4g}"
            joints = joint_cells(c.per_joint) if c.per_joint else " " * 7 * n
            lines.append(f"  {c.cutoff:12.4g}  {dec:>16}  {score:>19}{joints}  {_rest_text(c.rest)}"
                         f"{' ' + c.label if c.label else ''}{mark}")
        if self.offset_candidate is not None:
            c = self.offset_candidate
            joints = joint_cells(c.per_joint) if c.per_joint else ""
            score = "-" if math.isnan(c.score) else f"{c.score:.3f}"
            what = ("the offsets kept scored together" if c.label == "offsets kept" else
                    "an offset on every joint allowed one")
            lines.append(f"  {'with offsets':>12}  {'':>16}  {score:>19}{joints}  (the chosen processing, {what})")
        return "\n".join(lines + ["  " + self.reason()])

    def reason(self) -> str:
        """Why the chosen processing: its score against the others, and each joint's rest policy."""
        c = self.chosen
        if self.skipped:
            return f"the fixed defaults: {self.skipped}"
        scored = [x for x in self.candidates if not math.isnan(x.score)]
        dec = "no decimation" if c.decimate_to is None else f"decimation to {c.decimate_to:.4g} Hz"
        best = min(scored, key=lambda x: x.score)
        why = (f"the lowest held-back error ({c.score:.3f} %) of {len(scored)} candidates scored, clearly below "
               f"the default's" if c is best and c.label != DEFAULT_LABEL else
               f"the default: the lowest held-back error ({best.score:.3f} %, cut-off {best.cutoff:.4g} Hz) is not "
               f"below it ({c.score:.3f} %) by more than the blocks' spread nor by {100 * CLEAR_MARGIN:g} %"
               if c is not best else
               f"the default, the lowest held-back error ({c.score:.3f} %) of {len(scored)} candidates scored")
        out = f"chosen: cut-off {c.cutoff:.4g} Hz, {dec}, rest {_rest_text(c.rest)}: {why}"
        if self.rest_scores:
            out += (f"; rest per joint: the policy of lowest per-joint score at the knee where clearly below "
                    f"{DEFAULT_REST}'s, else {DEFAULT_REST} ("
                    + "; ".join(f"j{j + 1} " + ", ".join(f"{name} {v[j]:.2f}" for name, v in self.rest_scores)
                                for j in range(len(self.rest_scores[0][1]))) + " %)")
        if self.inseparable_offsets:
            out += ("; no torque offset offered on joint(s) " + ", ".join(str(j + 1) for j in self.inseparable_offsets)
                    + " (the fitted rows cannot tell it from the joint's other columns: a joint that moves one way "
                      "only, its Coulomb term and offset one column)")
        if self.offset_candidate is not None:
            out += ("; torque offsets on joints " + (", ".join(str(j + 1) for j in self.offsets) or "none")
                    + " (where they lower that joint's held-back error by more than the blocks' spread, and together "
                      "the mean over joints)")
        return out

    def to_dict(self) -> dict[str, Any]:
        raw = self.reference_hz == "raw"
        return {"method": "blocked cross-validation", "blocks": self.blocks,
                "scored_against": "raw measured torques" if raw else "torques filtered as the candidate's rows",
                "scoring_rate_hz": None if raw else self.reference_hz,
                "knee_hz": self.knee, "seconds": self.seconds, "chosen": self.chosen.to_dict(),
                "reason": self.reason(), "rest_scores_pct": {name: _finite(v) for name, v in self.rest_scores},
                "candidates": [c.to_dict() for c in self.candidates], "table": self.table(),
                "offsets": [j + 1 for j in self.offsets],
                "offset_candidate": None if self.offset_candidate is None else self.offset_candidate.to_dict(),
                "offsets_inseparable": [j + 1 for j in self.inseparable_offsets], "skipped": self.skipped or None}


def _finite(values: Sequence[float]) -> list[float | None]:
    """Per-joint figures for JSON: None for a joint not scored (NaN)."""
    return [float(v) if math.isfinite(v) else None for v in values]


def joint_cells(values: Sequence[float]) -> str:
    """A table's per-joint cells (7 characters each), "-" for a joint not scored (its torque left out)."""
    return "".join(f"{v:7.2f}" if math.isfinite(v) else f"{'-':>7}" for v in values)


def _rest_text(rest: RestPolicy | None) -> str:
    return "no threshold" if rest is None else rest_label(rest)
