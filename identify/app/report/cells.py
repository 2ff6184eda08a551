"""Numbers as a reader wants them in a table: a few significant digits, never ``None`` or a float repr.

A missing value (None, NaN) is an en dash; an infinite one is ``∞``; everything else has
``digits`` significant digits in plain notation between 1e-3 and 1e6 and in scientific notation
(with a true superscript) outside. The sort key of a cell is its number (data-sort attribute).
"""
from __future__ import annotations

import math
from typing import Any

MISSING = "–"


def number(value: Any) -> float | None:
    """The value as a float, None when it is missing or not a number."""
    if value is None or isinstance(value, bool):
        return None
    try:
        x = float(value)
    except (TypeError, ValueError):
        return None
    return None if math.isnan(x) else x


def fmt(value: Any, digits: int = 4) -> str:
    """``value`` with ``digits`` significant digits (plain text, no trailing float noise)."""
    x = number(value)
    if x is None:
        return MISSING if value is None or isinstance(value, float) else str(value)
    if math.isinf(x):
        return "∞" if x > 0 else "−∞"
    if x == 0:
        return "0"
    if 1e-3 <= abs(x) < 1e6:
        text = f"{x:.{digits}g}"
        if "e" in text:  # .g chose scientific for e.g. 123456 with 4 digits: write it out
            text = f"{x:.0f}"
        return text.replace("-", "−")
    mantissa, exponent = f"{x:.{max(digits - 1, 0)}e}".split("e")
    exp = int(exponent)
    sup = str(exp).translate(str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹"))
    return f"{mantissa.replace('-', '−')}×10{sup}"


def fixed(value: Any, decimals: int = 1) -> str:
    """``value`` with a fixed number of decimals (percentages, shares)."""
    x = number(value)
    if x is None:
        return MISSING
    if math.isinf(x):
        return "∞"
    return f"{x:.{decimals}f}".replace("-", "−")
