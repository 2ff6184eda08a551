"""Defaults of the model that a command's help shows: the tolerances URDF joint origins are snapped
with (standard library only: ``rx90 --help`` shows them without importing NumPy or the URDF reader)."""
from __future__ import annotations

__all__ = ["SNAP_RAD", "SNAP_LENGTH_M", "MAX_SNAP_RAD", "MAX_SNAP_LENGTH_M"]

#: Default angle tolerance [rad] of :mod:`rx90sym.urdf_snap`. Catches every multiple of pi/2 up to
#: 2 pi written with two decimals or more (1.57: 8.0e-4 off; 3.14: 1.6e-3; 4.71: 2.4e-3; 6.28:
#: 3.2e-3; 1.571: 2.0e-4; 1.5708: 3.7e-6); an axis snapped wrongly moves by at most 4 mrad
#: (0.23 deg). docs/urdf.md.
SNAP_RAD = 4e-3
#: Default length tolerance [m]: residues such as 1e-6 m are zeros; 10 um is below any drawn offset.
SNAP_LENGTH_M = 1e-5
#: Largest accepted angle tolerance [rad] (beyond it a deliberate angle could be snapped).
MAX_SNAP_RAD = 0.01
#: Largest accepted length tolerance [m] (beyond it a drawn offset could be zeroed).
MAX_SNAP_LENGTH_M = 1e-3
