"""Torque (or current) channels that hold one value over a whole log: a channel not logged.

A logger that does not log a channel writes a constant in its column (the Kinova Gen3 logs' joint 1
torque sensor column holds 0 on every row). Fitted, such a column would say that the joint needs no
torque whatever it does; scored, it would make every candidate's error infinite. The rule:

**a channel is constant when its largest and smallest values over the whole log differ by at most**
:data:`CONSTANT_SHARE` **x max(1, its largest magnitude)** (one value, up to the rounding of a
resampling or of a unit conversion). A live sensor is never that: its noise and quantisation steps
(0.01-0.1 N·m on joint torque sensors, a count of a current's ADC) are many orders above, and a joint
at rest with a live sensor still reads the noise and the coupling torques of the other joints'
motion. A quantised sensor whose reading never changes over a whole log would carry nothing to fit
either: the rule is not a threshold on the noise (a standard deviation below the quantisation would
also flag a live sensor at rest between two counts), only on the number of values.

``rx90 convert`` and :func:`identify.read_log` warn of such a column, naming it and its joint; a fit
leaves the joint's torque out (its rows out of W, not scored in the choices, not predicted:
:mod:`identify.fitting.passes`).
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ["CONSTANT_SHARE", "ColumnRange", "constant_channels", "constant_message"]

#: Largest spread of a constant channel over a whole log, as a share of max(1, its largest magnitude).
CONSTANT_SHARE = 1e-9


def constant_channels(lo: np.ndarray, hi: np.ndarray) -> list[int]:
    """The channels (0-based) whose smallest ``lo`` and largest ``hi`` values over a whole log are one
    value (module docstring)."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    scale = np.maximum(1.0, np.maximum(np.abs(lo), np.abs(hi)))
    return [int(j) for j in np.flatnonzero(hi - lo <= CONSTANT_SHARE * scale)]


def constant_message(source: str, joints: Sequence[int], values: Sequence[float], what: str = "torque",
                     columns: Sequence[str] | None = None) -> str:
    """The warning of constant channels: ``joints`` (0-based) of ``source``, their one value each (N·m or A
    for ``what`` "current"), and their columns' names in the file (None: the joints' own)."""
    unit = "A" if what == "current" else "N·m"
    named = [f"{columns[k] if columns is not None else f'{what} {j + 1}'} (joint {j + 1}, {values[k]:.6g} {unit})"
             for k, j in enumerate(joints)]
    return (f"{source}: {what} column{'s' if len(named) > 1 else ''} {', '.join(named)} "
            f"{'hold' if len(named) > 1 else 'holds'} one value on every row: a channel not logged? rx90 identify "
            f"leaves {'these joints' if len(named) > 1 else 'the joint'} out of the fit (not fitted, not scored, "
            f"not predicted)")


class ColumnRange:
    """The smallest and largest value of each column over consecutive blocks (``value()`` None: no block had
    any)."""

    def __init__(self) -> None:
        self.lo: np.ndarray | None = None
        self.hi: np.ndarray | None = None

    def add(self, x: np.ndarray | None) -> None:
        """A block's values (m, n); None or empty: nothing."""
        if x is not None and len(x):
            lo, hi = np.min(x, axis=0), np.max(x, axis=0)
            self.lo = lo if self.lo is None else np.minimum(self.lo, lo)
            self.hi = hi if self.hi is None else np.maximum(self.hi, hi)

    def value(self) -> np.ndarray | None:
        """(2, n): the smallest and the largest value of each column (None: no values)."""
        return None if self.lo is None else np.vstack([self.lo, self.hi])
