"""Defaults of the signal stage (standard library only: ``rx90 --help`` shows them without
importing the filters)."""
from __future__ import annotations

__all__ = ["POSITION_TOLERANCE"]

#: Largest position gap [rad] of an empty and a loaded run paired as one trajectory
#: (identify.signal.pairing). The paper measured < 1e-3 rad between the empty and loaded runs with
#: 7 kg on the CS8. The twin's 10 Hz servo loop without payload feed-forward drifts up to ~0.012 rad
#: with 7 kg; past 0.02 rad the path difference alone changes the RX90's gravity torques by a few
#: N m, the size of a light payload's effect.
POSITION_TOLERANCE = 0.02  # rad
