"""Defaults of the drive-gain identification (standard library only: ``rx90 gains --help`` shows
them without importing the method)."""
from __future__ import annotations

__all__ = ["GAIN_METHODS", "DEFAULT_METHOD", "FLAG_PCT"]

GAIN_METHODS = ("same-motion", "global")
#: The default method, chosen on the UR10e pair (docs/drive-gains.md, benchmarks/ur10e_windows.py).
DEFAULT_METHOD = "same-motion"
#: Relative sigma [%] above which a gain is flagged. A gain scales every parameter identified on its
#: joint. Where the payload acts on a joint through its (known) mass, the gain's relative sigma (the
#: larger of eq. 13's and the segment bootstrap's) is 0.1-0.8 % on the twin and 1.4-3 % on half of
#: the UR10e pair (benchmarks/ur10e_windows.py); a gain worse than 5 % is seen only through the
#: payload's unknown inertia (joint 1 of the UR10e: 11-13 % on half the pair): flag it.
FLAG_PCT = 5.0
