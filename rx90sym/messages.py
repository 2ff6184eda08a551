"""Plain numbers in messages: ``1.5``, not ``np.float64(1.5)``.

``repr`` of a NumPy scalar (and of a list or tuple holding some) prints the type; users read
error messages, so numbers are formatted with ``:g`` and everything else keeps its repr.
"""
from __future__ import annotations

import numbers
from typing import Any

import numpy as np

__all__ = ["plain"]


def plain(value: Any) -> str:
    """``value`` for a message: numbers with ``:g``, sequences and arrays of numbers as
    ``[1, 2.5]``, strings and anything else as their repr."""
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return f"{float(value):g}"
    if isinstance(value, np.ndarray) or (isinstance(value, (list, tuple)) and value):
        items = np.asarray(value, dtype=object).ravel() if isinstance(value, np.ndarray) else value
        body = ", ".join(plain(v) for v in items)
        return f"({body})" if isinstance(value, tuple) else f"[{body}]"
    return repr(value)
