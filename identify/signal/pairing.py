"""Pairing an empty and a loaded run of the same trajectory logged separately (payload method 3).

Two real runs of one trajectory start at different instants of the controller's clock and have
different lengths. :func:`pair_runs` finds the time lag from the positions (cross-correlation
of the normalised positions, refined to a fraction of a sample by minimising the position gap),
puts the loaded run on the empty run's time grid, keeps the common part and reports the lag and
the largest position gap; beyond ``position_tol`` the runs are refused (not the same motion).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from rx90sym.recording import Recording

from identify.io.resampling import interpolate
from identify.signal.defaults import POSITION_TOLERANCE

__all__ = ["PairedRuns", "pair_runs", "POSITION_TOLERANCE", "accepting_tolerance"]

# A lag below this fraction of a sample is taken as none: the samples are used as they are.
_NO_SHIFT = 1e-3


@dataclass(frozen=True, eq=False)
class PairedRuns:
    """An empty and a loaded run on one time grid (the empty run's samples).

    lag: loaded-run clock minus empty-run clock at the same point of the motion, s;
    gap: largest |q_empty − q_loaded| over the common part, rad, and ``gap_joint`` (1-based);
    dropped: samples of the empty run outside the common part (start, end).
    """

    empty: Recording
    loaded: Recording
    lag: float
    gap: float
    gap_joint: int
    dropped: tuple[int, int]

    def summary(self) -> str:
        return (f"paired {self.empty.source} with {self.loaded.source}: lag {self.lag:.6g} s, "
                f"{self.empty.n_samples} common samples ({self.dropped[0]} + {self.dropped[1]} dropped), "
                f"largest position gap {self.gap:.3g} rad (joint {self.gap_joint})")


def _uniform(rec: Recording, step: float) -> np.ndarray:
    """Positions resampled on a grid of ``step`` s from the recording's first sample."""
    t = rec.t - rec.t[0]
    grid = np.arange(0.0, t[-1] + 1e-12, step)
    return np.stack([np.interp(grid, t, rec.q[:, j]) for j in range(rec.n_joints)], axis=1)


def _coarse_lag(empty: Recording, loaded: Recording, step: float) -> float:
    """Lag (s), to the sample, that minimises the mean squared gap of the normalised positions
    over the overlap (sums by FFT cross-correlation and cumulative sums)."""
    a, b = _uniform(empty, step), _uniform(loaded, step)
    scale = a.std(axis=0)
    moving = scale > 1e-6  # a joint at rest carries no timing information
    if not np.any(moving):
        raise ValueError(f"{empty.source}: no joint moves; the runs cannot be paired in time")
    a, b = a[:, moving] / scale[moving], b[:, moving] / scale[moving]
    lags = np.arange(-(len(a) - 1), len(b))   # b[n + lag] against a[n]
    from scipy.signal import correlate  # SciPy when pairing runs, not when the command line starts

    cross = sum(correlate(b[:, j], a[:, j], mode="full", method="fft") for j in range(a.shape[1]))
    ca = np.concatenate([[0.0], np.cumsum(np.sum(a**2, axis=1))])
    cb = np.concatenate([[0.0], np.cumsum(np.sum(b**2, axis=1))])
    n0 = np.maximum(0, -lags)
    n1 = np.minimum(len(a), len(b) - lags)
    overlap = n1 - n0
    ssd = (ca[n1] - ca[n0]) + (cb[n1 + lags] - cb[n0 + lags]) - 2 * cross
    # Overlaps shorter than half the shorter run do not count: short ends match by chance.
    ssd = np.where(overlap >= 0.5 * min(len(a), len(b)), ssd / np.maximum(overlap, 1), np.inf)
    k = int(np.argmin(ssd))
    return float(lags[k] * step + loaded.t[0] - empty.t[0])


# [rad^2] mismatch of a lag with too little overlap: above any real mean squared gap, and finite
# (an infinite value makes Brent's parabolic step inf - inf).
_NO_OVERLAP = 1e6


def accepting_tolerance(gap: float) -> float:
    """A round position tolerance (2 significant digits, rad) that accepts a gap of ``gap`` rad."""
    scale = 10.0 ** (math.floor(math.log10(gap)) - 1)
    return math.ceil(gap / scale * (1 + 1e-12)) * scale


def pair_runs(empty: Recording, loaded: Recording, position_tol: float = POSITION_TOLERANCE,
              max_lag: float | None = None, instead: str = "--method 4") -> PairedRuns:
    """Put a loaded run on the empty run's time grid (eq. 28 needs both at the same instants).

    Args:
        empty, loaded: two runs of the same trajectory, uniform time steps, any clocks and lengths.
        position_tol: largest position gap accepted over the common part, rad.
        max_lag: refuse a lag larger than this, s (None: any).
        instead: the method that needs no pairing, named by the refusal of a position gap.

    Returns:
        :class:`PairedRuns`; the loaded run's samples are interpolated at t_empty + lag (not at all
        when the lag is a whole number of samples to within 1e-3 of a sample).

    Raises:
        ValueError: joints differ, no common part, lag beyond ``max_lag``, or a position gap
            beyond ``position_tol`` (the message gives the lag and the gap).
    """
    if empty.n_joints != loaded.n_joints:
        raise ValueError(f"{empty.source} has {empty.n_joints} joints and {loaded.source} {loaded.n_joints}")
    for rec in (empty, loaded):
        if rec.n_segments > 1:
            raise ValueError(f"{rec.source}: {rec.n_segments} segments (gaps too long to bridge): paired runs are "
                             f"compared sample by sample; bridge the gaps (convert --max-gap) or select a window "
                             f"without them (--rows)")
    from scipy.interpolate import CubicSpline
    from scipy.optimize import minimize_scalar

    step = float(np.median(np.diff(empty.t)))
    coarse = _coarse_lag(empty, loaded, step)
    spline = CubicSpline(loaded.t, loaded.q, axis=0)

    def mismatch(lag: float) -> float:
        t = empty.t + lag
        inside = (t >= loaded.t[0]) & (t <= loaded.t[-1])
        if inside.sum() < 0.5 * min(empty.n_samples, loaded.n_samples):
            return _NO_OVERLAP
        return float(np.mean((spline(t[inside]) - empty.q[inside]) ** 2))

    # Sub-sample refinement: the position gap is smooth in the lag near its minimum.
    lag = float(minimize_scalar(mismatch, bounds=(coarse - 1.5 * step, coarse + 1.5 * step), method="bounded",
                                options={"xatol": 1e-4 * step}).x)
    if max_lag is not None and abs(lag) > max_lag:
        raise ValueError(f"{loaded.source}: lag {lag:.6g} s to {empty.source} exceeds {max_lag:g} s")
    shift = (lag - (loaded.t[0] - empty.t[0])) / step
    whole = round(shift)
    t_l = empty.t + lag
    inside = np.flatnonzero((t_l >= loaded.t[0] - 1e-9 * step) & (t_l <= loaded.t[-1] + 1e-9 * step))
    if inside.size < 5:
        raise ValueError(f"{empty.source} and {loaded.source} have no common part at lag {lag:.6g} s")
    first, last = int(inside[0]), int(inside[-1])
    e = empty.select(slice(first, last + 1))
    if abs(shift - whole) < _NO_SHIFT and np.allclose(np.diff(loaded.t), step, rtol=1e-6, atol=0):
        start = int(np.argmin(np.abs(loaded.t - t_l[first])))
        rows = slice(start, start + e.n_samples)
        l_rec = loaded.select(rows)
        values = {"q": l_rec.q, "tau": l_rec.tau, "dq": l_rec.dq, "current": l_rec.current, "aux": l_rec.aux,
                  "measured": l_rec.measured}
    else:
        r = interpolate(loaded, np.clip(t_l[first:last + 1], loaded.t[0], loaded.t[-1]))
        values = {"q": r.q, "tau": r.tau, "dq": r.dq, "current": r.current, "aux": r.aux, "measured": r.measured}
    l_new = replace(loaded, t=e.t, meta={**loaded.meta, "paired_with": empty.source, "lag_s": lag},
                    **values)
    diff = np.abs(e.q - l_new.q)
    gap = float(diff.max())
    gap_joint = int(np.unravel_index(np.argmax(diff), diff.shape)[1]) + 1
    if gap > position_tol:
        raise ValueError(f"{empty.source} and {loaded.source}: after the lag {lag:.6g} s the positions still "
                         f"differ by up to {gap:.3g} rad on joint {gap_joint}, more than --position-tol "
                         f"{position_tol:g} rad: not the same motion, or one run drifted; --position-tol "
                         f"{accepting_tolerance(gap):g} accepts this pair (position_tol= in Python), {instead} "
                         f"needs no pairing")
    return PairedRuns(e, l_new, lag, gap, gap_joint, (first, empty.n_samples - 1 - last))
