"""A twin recording as a host PC logs a real-time stream: lost packets, stale rows, clock jitter.

The twin (:mod:`rx90sym.twin`) samples on a perfect clock. A host PC that records a 1 kHz
stream does not: it time-stamps each packet when it arrives (jitter of a fraction of a period),
loses bursts of packets now and then, and writes the last packet again when a new one is late (a
*stale* row: every signal identical, the time stamp advancing). :func:`host_log` turns a
recording into such a log (a table and its column map) so that the toolkit's reader can be
tested against the known truth; :func:`write_host_log` writes it as CSV.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .files import atomic_write
from .recording import Recording

__all__ = ["HostFaults", "host_log", "write_host_log"]


@dataclass(frozen=True)
class HostFaults:
    """What the host does to the stream.

    stale_fraction: share of rows written again as stale copies of the previous row;
    gap_every_s: (shortest, longest) time between two bursts of lost packets, s (uniform draw);
    gap_periods: (fewest, most) packets lost in one burst; jitter: half-width of the uniform
    time-stamp jitter, as a fraction of the period; long_gaps: times (s from the start) where
    ``long_gap_s`` seconds of packets are lost (a gap too long to bridge).
    """

    stale_fraction: float = 0.05
    gap_every_s: tuple[float, float] = (2.0, 4.0)
    gap_periods: tuple[int, int] = (5, 40)
    jitter: float = 0.15
    long_gaps: tuple[float, ...] = ()
    long_gap_s: float = 0.2


def host_log(rec: Recording, faults: HostFaults, seed: int) -> tuple[np.ndarray, list[int], np.ndarray]:
    """The rows a host would log of ``rec`` (model angles), with the faults drawn from ``seed``.

    Returns:
        (table, kept, stale): table (M, 1 + 3n) columns t, q1..qn, qd1..qdn, tau1..taun; kept:
        the index in ``rec`` of each row's sample (a stale row: the sample it repeats); stale:
        (M,) bool, the stale rows. Velocities are the central differences of ``rec.q``.
    """
    rng = np.random.default_rng(seed)
    t = np.asarray(rec.t, dtype=float)
    period = float(np.median(np.diff(t)))
    lost = np.zeros(t.size, dtype=bool)
    at = t[0] + rng.uniform(*faults.gap_every_s)
    while at < t[-1]:
        k = int(np.searchsorted(t, at))
        lost[k:k + int(rng.integers(faults.gap_periods[0], faults.gap_periods[1] + 1))] = True
        at += rng.uniform(*faults.gap_every_s)
    for start in faults.long_gaps:
        lost[(t >= t[0] + start) & (t < t[0] + start + faults.long_gap_s)] = True
    lost[[0, -1]] = False
    kept = np.flatnonzero(~lost)
    stale = rng.random(kept.size) < faults.stale_fraction
    stale[0] = False
    source = kept.copy()
    for i in np.flatnonzero(stale):  # a run of stale rows repeats the last fresh one
        source[i] = source[i - 1]
    dq = np.gradient(np.asarray(rec.q), t, axis=0)
    stamps = t[kept] + rng.uniform(-faults.jitter, faults.jitter, kept.size) * period
    table = np.column_stack([stamps, rec.q[source], dq[source], rec.torques[source]])
    return table, [int(k) for k in source], stale


def write_host_log(path: str | os.PathLike[str], table: np.ndarray) -> str:
    """Write the table of :func:`host_log` as a headerless CSV; returns its column map."""
    n = (table.shape[1] - 1) // 3
    atomic_write(Path(path), lambda fh: np.savetxt(fh, table, fmt="%.17g", delimiter=","), binary=False)
    return f"t,q1..q{n},qd1..qd{n},tau1..tau{n}"
