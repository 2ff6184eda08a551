"""The error flag of a model whose base-parameter rank depends on the rank threshold.

Such a fit is never silent: it is fitted and carries this flag (severity "error"; the terminal,
the fit file's ``flags`` and the report's verdict show it), naming the joints, the columns and the
gap in singular values (rx90sym.rank_gap). Its cause is the model's geometry, not the motion.
"""
from __future__ import annotations

from typing import Any

from rx90sym.rank_gap import rank_gap

from identify import Flag

#: The flag's code (identify.app.flags.HINTS gives its command-line option).
CODE = "rank_threshold"


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
