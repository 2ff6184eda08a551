"""The flags of columns a fit cannot estimate on their own: the rank of the model and of the fitted rows.

- A model whose base-parameter rank depends on the rank threshold is never silent: it is fitted and
  carries an error flag (the terminal, the fit file's ``flags`` and the report's verdict show it),
  naming the joints, the columns and the gap in singular values (rx90sym.near_dependent_columns). Its cause is the
  model's geometry, not the motion.
- Columns the fitted rows cannot separate (identify.estimation.dependent_columns: a joint that never
  moves, one that moves one way only, a joint whose torque is left out of the fit) are left out or
  merged by the fit, never refused: a warning each, naming the columns, why, and what a merged
  column's estimate holds.
"""
from __future__ import annotations

import re
from typing import Any, Sequence

from rx90sym.near_dependent_columns import rank_gap

from identify import Flag
from identify.estimation.dependent_columns import ColumnReduction

__all__ = ["CODE", "LEFT_OUT", "MERGED", "column_flags", "has_rank_flag", "rank_flags"]

#: The flag's code (identify.app.flags.HINTS gives its command-line option).
CODE = "rank_threshold"
#: Codes of a column left out (0 on every fitted row) and of columns merged into one.
LEFT_OUT = "column_left_out"
MERGED = "columns_merged"
#: A parameter's name: its kind (FS, OFF, ZZ, ...) and joint, an optional R (grouped) or _k suffix.
_NAME = re.compile(r"^([A-Z]+?)(\d+)R?(?:_\d+)?$")
#: The friction and drive columns of a joint, 0 on every row when it never moves.
_MOTION = ("FS", "FSP", "FSN", "FST", "FV", "IA", "FVM", "FSM")
_AT_REST = "FP"  # presliding magnitude: 0 on every row when the joint never rests after a motion


def rank_flags(base: Any) -> list[Flag]:
    """[the error flag] when ``base`` (base parameters, or a base with spring or friction columns
    around them) has near-dependent columns; [] otherwise."""
    gap = rank_gap(base)
    if gap is None:
        return []
    return [Flag(CODE, "error", gap.message(),
                 "make the geometry exact (a URDF's joint origins written 1.5708 for pi/2 are snapped by "
                 "default: a larger snap tolerance, or exact angles in the file); no motion identifies "
                 "these columns and their estimates are meaningless",
                 joint=gap.joints[0] if len(gap.joints) == 1 else None, parameter=gap.columns[0])]


def has_rank_flag(flags: Any) -> bool:
    """Whether ``flags`` (Flag objects or their JSON dicts) hold the rank-threshold error."""
    return any((f.get("code") if isinstance(f, dict) else getattr(f, "code", None)) == CODE for f in flags)


def _kind(name: str) -> tuple[str, int | None]:
    """(kind, 1-based joint) of a parameter's name (("", None) when it names no joint)."""
    m = _NAME.match(name)
    return (m.group(1), int(m.group(2))) if m else ("", None)


def column_flags(reduction: ColumnReduction | None, left_out: Sequence[int] = ()) -> list[Flag]:
    """A warning per column left out and per column kept that holds others (``reduction`` of
    :func:`identify.estimation.dependent_columns.reduce_columns`; None: none), with the likely cause;
    ``left_out``: the joints (1-based) whose torque the fit left out."""
    if reduction is None:
        return []
    action = "a prediction counts it as 0; a motion that excites it (or a prior) estimates it"
    out = []
    for name in reduction.zero:
        kind, joint = _kind(name)
        if joint in left_out:
            why = f"joint {joint}'s torque is left out of the fit and no other joint's rows see {name}"
        elif kind in _MOTION:
            why = f"joint {joint} never moves in the fitted rows: {name} is 0 on every row"
        elif kind == _AT_REST:
            why = f"joint {joint} never rests after a motion in these recordings: {name} is 0 on every row"
        else:
            why = f"{name} is 0 on every fitted row"
        out.append(Flag(LEFT_OUT, "warning", f"{name} left out: {why}", action, joint=joint, parameter=name))
    for m in reduction.merged:
        kind, joint = _kind(m.name)
        others = [_kind(a) for a, _ in m.absorbed]
        if kind in ("FS", "FST") and others == [("OFF", joint)]:
            why = (f"joint {joint} moves one way only: its Coulomb term and offset are one column "
                   f"({m.name} holds {m.holds()})")
        else:
            why = (f"{', '.join([m.name] + [a for a, _ in m.absorbed])} are one column on the fitted rows "
                   f"({m.name} holds {m.holds()})")
        out.append(Flag(MERGED, "warning", why,
                        "the estimate is their sum as written; a motion that separates them (the joint moving both "
                        "ways, resting) estimates each", joint=joint, parameter=m.name))
    return out
