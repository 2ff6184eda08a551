"""Real measurements shipped with the package (with their attribution and licence).

``tx40()``: the Stäubli TX40 record of the FIGAROH examples (Apache-2.0), motor-side positions
and torques at 5 kHz; read it with ``identify.read_motor_recording(d.positions, d.torques,
rx90sym.load_robot("tx40"), period=d.period)``. The README and LICENSE beside the files give
the source, the units and the conversion facts.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = ["TX40Record", "tx40"]

_DATA = Path(__file__).resolve().parent / "data"


@dataclass(frozen=True)
class TX40Record:
    """Paths of the TX40 record: motor positions [rad], motor torques [N m], sampling period [s]."""

    positions: Path
    torques: Path
    period: float
    readme: Path
    license: Path


def tx40() -> TX40Record:
    """The bundled TX40 record (45,000 samples at 0.2 ms, one excitation motion, no payload)."""
    root = _DATA / "tx40"
    rec = TX40Record(root / "pos_read_data.csv", root / "curr_data.csv", 2e-4,
                     root / "README.md", root / "LICENSE")
    missing = [p.name for p in (rec.positions, rec.torques) if not p.exists()]
    if missing:
        raise FileNotFoundError(f"TX40 record incomplete in {root}: missing {', '.join(missing)} "
                                f"(reinstall the package)")
    return rec
