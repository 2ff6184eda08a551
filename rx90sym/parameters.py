"""Names and layout of the dynamic parameters (eq. 4)."""
from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

from .messages import plain

# eq. 4: standard parameters of link j, in this order.
LINK_PARAMETERS: tuple[str, ...] = (
    "XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M", "IA", "FS", "FV",
)
INERTIAL: tuple[str, ...] = LINK_PARAMETERS[:10]
# Payload parameters, frame n about its origin: they add to link n's first ten parameters.
PAYLOAD_NAMES: tuple[str, ...] = tuple(f"{p}c" for p in INERTIAL)


def link_parameter_names(n: int) -> list[str]:
    """Standard parameter names of links 1..n (13 per link, eq. 3-4)."""
    return [f"{p}{j}" for j in range(1, n + 1) for p in LINK_PARAMETERS]


def link_index(n_params_per_link: int = 13) -> dict[str, int]:
    """Position of each parameter kind inside one link's block."""
    return {p: i for i, p in enumerate(LINK_PARAMETERS[:n_params_per_link])}


def split_name(name: str) -> tuple[str, int]:
    """'XX2' -> ('XX', 2); 'FVM6' -> ('FVM', 6); 'OFF3' -> ('OFF', 3)."""
    i = len(name)
    while i > 0 and name[i - 1].isdigit():
        i -= 1
    if i == len(name) or i == 0:
        raise ValueError(f"parameter name {name!r} has no kind or no link number")
    return name[:i], int(name[i:])


def checked_values(table: Any, names: Sequence[str], where: str, what: str = "parameter") -> dict[str, float]:
    """``table`` as {name: float} for exactly ``names``: all present, none unknown, all finite.

    Errors name the source (``where``) and the offending field."""
    if not isinstance(table, Mapping):
        raise ValueError(f"{where}: expected a mapping of {what} names to numbers, got {type(table).__name__}")
    unknown = sorted(set(table) - set(names))
    if unknown:  # first: a file of another robot (or a typo) names what this robot does not have
        more = f" and {len(unknown) - 6} more" if len(unknown) > 6 else ""
        raise ValueError(f"{where}: unknown {what}(s) {unknown[:6]}{more}: not {what}s of this robot (its "
                         f"{len(names)}: {', '.join(list(names)[:4])}, ..., {names[-1]})")
    missing = [p for p in names if p not in table]
    if missing:
        raise ValueError(f"{where}: missing {what}(s) {missing[:6]}")
    out = {}
    for p in names:
        v = table[p]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ValueError(f"{where}: {what} {p!r} must be a finite number, got {plain(v)}")
        out[p] = float(v)
    return out
