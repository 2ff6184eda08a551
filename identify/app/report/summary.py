"""Pieces of every report's summary: held-out error against thresholds, flags, what to do next.

Thresholds (documented in docs/reports.md): the held-out relative error of a joint, 100·‖τ − τ̂‖/‖τ‖
on samples the fit did not see, is marked

- ok (✓) at or below ``HELDOUT_OK_PCT`` (10 %): the model predicts that joint's torque well enough
  for feed-forward and monitoring;
- check (!) up to ``HELDOUT_POOR_PCT`` (20 %);
- poor (✗) above.

The mark that decides the verdict is the one *while moving*: at rest static friction lies anywhere
in [−FS, FS], so the all-samples figure of a joint that rests often is high for a sound model.
"""
from __future__ import annotations

from dataclasses import asdict, is_dataclass
from typing import Any, Iterable, Mapping, Sequence

from .cells import number
from .page import Cell, Column, Table

HELDOUT_OK_PCT = 10.0
HELDOUT_POOR_PCT = 20.0
#: Relative σ (eq. 15) above which a parameter is called weakly identified, %.
WEAK_REL_STD_PCT = 10.0
#: cond(W) above which the excitation is called poor.
COND_CHECK = 1e4
#: Bootstrap σ over eq. 13's σ (median) above which the residuals are called coloured.
COLOURED_RATIO = 1.5
#: Share of samples at rest (any joint) above which the data are called mostly static.
REST_SHARE_CHECK = 0.5


def mark(value: Any, ok: float = HELDOUT_OK_PCT, poor: float = HELDOUT_POOR_PCT) -> str:
    """"ok", "check" or "poor" for a percentage (lower is better); "" when missing."""
    x = number(value)
    if x is None:
        return ""
    return "ok" if x <= ok else "check" if x <= poor else "poor"


def flag(code: str, severity: str, message: str, action: str = "", joint: int | None = None) -> dict:
    """A flag as the page shows it (the same keys as the library's plausibility flags)."""
    return {"code": code, "severity": severity, "joint": joint, "message": message, "action": action}


def as_flag(item: Any) -> dict:
    """A flag from a dict or a dataclass (code, severity, joint, message, action / what_to_do)."""
    d = asdict(item) if is_dataclass(item) else dict(item)
    action = d.get("action") or d.get("what_to_do") or d.get("todo") or ""
    return flag(str(d.get("code", "")), str(d.get("severity", "warning")), str(d.get("message", "")),
                str(action), d.get("joint"))


def next_steps(flags: Iterable[Mapping[str, Any]]) -> tuple[str, ...]:
    """The flags' actions, errors first, each once."""
    order = {"error": 0, "warning": 1, "info": 2}
    steps: list[str] = []
    for f in sorted(flags, key=lambda f: order.get(str(f.get("severity")), 3)):
        action = str(f.get("action") or "")
        if action and action not in steps:
            steps.append(action)
    return tuple(steps)


def heldout_table(validation: Mapping[str, Any], table_id: str = "summary-heldout") -> Table:
    """Per joint: relative error on all samples and while moving (marked), RMS while moving."""
    all_pct = validation.get("relative_error_pct") or []
    moving = validation.get("relative_error_pct_moving") or all_pct
    rms_moving = validation.get("rms_error_moving") or validation.get("rms_error") or []
    share = validation.get("moving_fraction") or [None] * len(all_pct)
    rows = tuple((j + 1, Cell(a, mark(a)), Cell(m, mark(m)), r, None if s is None else 100 * s)
                 for j, (a, m, r, s) in enumerate(zip(all_pct, moving, rms_moving, share)))
    return Table(table_id, f"Held-out error on {validation.get('source', 'the validation recording')}",
                 (Column("joint", decimals=0), Column("all", "%", decimals=1),
                  Column("moving", "%", decimals=1), Column("RMS moving", "N·m", digits=3),
                  Column("share moving", "%", decimals=0)), rows,
                 note=f"Relative error 100·‖τ − τ̂‖/‖τ‖ on all samples and while the joint moves: "
                      f"✓ ≤ {HELDOUT_OK_PCT:g} %, ! ≤ {HELDOUT_POOR_PCT:g} %, ✗ above (docs/reports.md).")


def heldout_flags(validation: Mapping[str, Any]) -> list[dict]:
    """A flag per joint whose held-out error while moving is above the thresholds."""
    out = []
    all_pct = validation.get("relative_error_pct") or []
    moving = validation.get("relative_error_pct_moving") or all_pct
    for j, (a, m) in enumerate(zip(all_pct, moving), start=1):
        level = mark(m)
        if level == "poor":
            out.append(flag("heldout-poor", "error", f"held-out error while moving {m:.1f} % "
                            f"(above {HELDOUT_POOR_PCT:g} %)", "look at this joint's torque figure: "
                            "a missing friction or coupling term, a wrong gain or a delay shows there", j))
        elif level == "check":
            out.append(flag("heldout-high", "warning", f"held-out error while moving {m:.1f} % "
                            f"(above {HELDOUT_OK_PCT:g} %)", "compare with a richer excitation or "
                            "another friction form (--asymmetric-coulomb, --coulomb-sign)", j))
        elif mark(a) == "poor" and level == "ok":
            out.append(flag("heldout-rest", "info", f"held-out error {a:.1f} % on all samples but "
                            f"{m:.1f} % while moving: the error is at rest (static friction)", "", j))
    return out


#: A held-out RMS above this many times the better yardstick's is flagged (the project's "never worse": 2 %).
YARDSTICK_MARGIN = 1.02


def yardstick_flags(validation: Mapping[str, Any]) -> list[dict]:
    """A warning per joint whose held-out RMS on all samples is above YARDSTICK_MARGIN x the better yardstick's
    (the plain OLS, the model the user had: the JSON's yardstick_ratio and better_yardstick)."""
    ratio, better = validation.get("yardstick_ratio") or [], validation.get("better_yardstick") or []
    out = []
    for j, (r, b) in enumerate(zip(ratio, better), start=1):
        if r is not None and r > YARDSTICK_MARGIN:
            what = "the model the user had (the description's bodies, friction fitted)" if b == "user model" \
                else "a plain OLS fit (10 Hz, rigid bodies and friction)"
            out.append(flag("worse-than-yardstick", "warning", f"held-out RMS {r:.3f}x that of {what}",
                            "compare the processing (cross-validation table) and the description's bodies; "
                            "a longer or richer recording helps the fit most where the data sees little", j))
    return out


def parameter_flags(names: Sequence[str], rel_std_pct: Sequence[Any], boot: Sequence[Any] | None,
                    std: Sequence[Any], cond: Any, model_cause: bool = False) -> list[dict]:
    """Weakly identified parameters, coloured residuals (bootstrap σ ≫ eq. 13), a poor cond(W).
    model_cause: the fit's rank depends on the rank threshold (its error flag): weak parameters
    and a poor cond(W) come from the model's geometry, and the motion is not blamed."""
    out = []
    weak = [n for n, p in zip(names, rel_std_pct) if number(p) is None or number(p) > WEAK_REL_STD_PCT]
    if weak:
        out.append(flag("weak-parameters", "info", f"{len(weak)} of {len(names)} parameters have σr > "
                        f"{WEAK_REL_STD_PCT:g} % (weakly identified): {', '.join(weak[:8])}"
                        + (" …" if len(weak) > 8 else ""),
                        "use --essential for a model without them" + (
                            ", and make the model's geometry exact (see the rank error)" if model_cause
                            else ", or excite them more (rx90 excite)")))
    if boot:
        ratios = sorted(b / s for b, s in zip(map(number, boot), map(number, std)) if b and s)
        if ratios and ratios[len(ratios) // 2] > COLOURED_RATIO:
            out.append(flag("coloured-residuals", "warning", f"bootstrap σ is {ratios[len(ratios) // 2]:.1f}× "
                            "eq. 13's σ (median): the residuals are coloured",
                            "read the bootstrap σ, not eq. 13's, as the parameters' uncertainty"))
    c = number(cond)
    if c is not None and c > COND_CHECK:
        out.append(flag("cond", "warning", f"cond(W) = {c:.3g} (above {COND_CHECK:.0e})",
                        "the model's geometry makes some columns almost dependent (see the rank error): no "
                        "motion fixes it" if model_cause else
                        "the motion excites some parameters little: optimise one (rx90 excite)"))
    return out
