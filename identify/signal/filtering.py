"""Filtering of recorded signals: low-pass, cut-off choice, derivatives, parallel decimation.

Plain functions on arrays (time along axis 0), in the manner of ``scipy.signal``.

* :func:`lowpass` — zero-phase Butterworth (forward–backward), as in §III-A of the paper.
* :func:`choose_cutoff` — the cut-off frequency derived from the position signal itself
  (:func:`crossover_frequencies` gives the per-joint figures behind it).
* :func:`derivatives` — filtered q, q̇, q̈ by central differences (eq. 20), edges trimmed.
* :func:`decimate` / :func:`decimation_factor` — the "parallel filtering" of Gautier: the torque
  vector Y and **every column** of the observation matrix W are low-pass filtered and
  down-sampled by the same filter, so that the high-frequency content that the model does not
  explain (noise, torque ripple, unmodelled modes) is removed from both sides of Y = W·χ alike.
  Applying it to Y only, or with a different factor to W, biases the estimate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rx90sym.messages import plain

from identify.io.gaps import EDGE_PERIODS  # defined where the log reader sizes its segments
from identify.signal._checks import _as_samples, _check_rate
from identify.signal.cutoff import choose_cutoff, crossover_frequencies, cutoff_from_spectrum, welch_segment

__all__ = [
    "Derivatives",
    "lowpass",
    "choose_cutoff",
    "crossover_frequencies",
    "cutoff_from_spectrum",
    "welch_segment",
    "derivatives",
    "decimate",
    "decimation_factor",
    "decimation_plan",
    "DecimationPlan",
    "EDGE_PERIODS",
]



def lowpass(x: np.ndarray, rate: float, cutoff: float, order: int = 4) -> np.ndarray:
    """Zero-phase Butterworth low-pass filter along axis 0.

    The filter of order ``order`` runs forward then backward (``scipy.signal.sosfiltfilt``), so
    it has no phase lag and its magnitude is squared: ``|H(f)|² = 1 / (1 + (f/cutoff)^(2·order))``
    (−6 dB at ``cutoff``; for order 4, a component at cutoff/5 loses 3e-6 of its amplitude, one
    at cutoff/2 loses 0.4 %).

    Args:
        x: (N, ...) samples, any unit.
        rate: sampling rate, Hz.
        cutoff: cut-off frequency, Hz, 0 < cutoff < rate/2.
        order: order of the Butterworth prototype (4 in the paper).

    Returns:
        Filtered array, same shape as ``x``.
    """
    from scipy import signal  # imported when filtering, not when a command starts
    rate = _check_rate(rate)
    if not (0.0 < cutoff < rate / 2.0):
        raise ValueError(f"cutoff must lie in (0, {rate / 2:g}) Hz (Nyquist), got {plain(cutoff)}")
    if int(order) != order or order < 1:
        raise ValueError(f"order must be a positive integer, got {plain(order)}")
    a = _as_samples(x, "x", min_rows=2)
    # Second-order sections: numerically safe even when cutoff << rate (e.g. 20 Hz at 5 kHz).
    sos = signal.butter(int(order), cutoff, btype="low", fs=rate, output="sos")
    return signal.sosfiltfilt(sos, a, axis=0)


@dataclass(frozen=True, eq=False)
class Derivatives:
    """Filtered positions and their derivatives, trimmed of the filter's edge transients.

    Attributes:
        t: (M,) time of the kept samples, s.
        q: (M, ...) filtered positions, rad.
        dq: (M, ...) velocities, rad/s (eq. 20 on the filtered positions).
        ddq: (M, ...) accelerations, rad/s² (eq. 20 applied to dq).
        cutoff: cut-off frequency used, Hz.
        rate: sampling rate, Hz.
        kept: slice of the input samples that were kept; apply it to the torques
            (``tau[d.kept]``) so that every row of Y and W refers to the same instant.
    """

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    cutoff: float
    rate: float
    kept: slice


def _uniform_step(t: np.ndarray, rtol: float = 0.01) -> float:
    dt = np.diff(t)
    step = float(np.median(dt))
    if step <= 0.0 or np.any(dt <= 0.0):
        raise ValueError("t: time must increase strictly")
    if np.any(np.abs(dt - step) > rtol * step):
        k = int(np.flatnonzero(np.abs(dt - step) > rtol * step)[0]) + 1
        raise ValueError(f"t: irregular time step at sample {k + 1} (1-based); derivatives need a uniform rate")
    return step


def _central_difference(x: np.ndarray, step: float) -> np.ndarray:
    """eq. 20: ẋ(k) = [x(k+1) − x(k−1)] / 2T; the first and last samples are NaN (undefined)."""
    out = np.full_like(x, np.nan)
    out[1:-1] = (x[2:] - x[:-2]) / (2.0 * step)
    return out


def derivatives(
    t: np.ndarray, q: np.ndarray, cutoff: float | None = None, order: int = 4, edge: int | None = None,
    kept: slice | None = None,
) -> Derivatives:
    """Estimate q̇ and q̈ from sampled positions (§III-A: low-pass then central differences).

    The positions are filtered by :func:`lowpass` (zero-phase Butterworth), then differentiated
    by eq. 20 once for q̇ and once more, on q̇, for q̈. Both ends are dropped: ``edge`` samples at
    each end, so that the filter's start-up transients and the undefined differences are gone.

    Args:
        t: (N,) time, s, uniform step.
        q: (N,) or (N, n) positions, rad.
        cutoff: cut-off frequency, Hz; ``None`` uses :func:`choose_cutoff` (reported in the result).
        order: Butterworth order (4 in the paper).
        edge: samples dropped at each end (≥ 2); ``None`` uses
            ``max(2, ceil(EDGE_PERIODS · rate / cutoff))``, three periods of the cut-off.
        kept: the samples to keep instead (a block of a longer signal, whose ends are margins:
            :mod:`identify.signal.blocks`); at least 2 from each end.

    Returns:
        :class:`Derivatives` on the kept samples.
    """
    t_a = _as_samples(t, "t", min_rows=5)
    if t_a.ndim != 1:
        raise ValueError(f"t must be 1-D, got shape {t_a.shape}")
    q_a = _as_samples(q, "q")
    if q_a.shape[0] != t_a.size:
        raise ValueError(f"q has {q_a.shape[0]} samples but t has {t_a.size}")
    step = _uniform_step(t_a)
    rate = 1.0 / step
    fc = choose_cutoff(q_a, rate) if cutoff is None else float(cutoff)
    if edge is None:
        edge = max(2, math.ceil(EDGE_PERIODS * rate / fc))
    if int(edge) != edge or edge < 2:
        raise ValueError(f"edge must be an integer >= 2 (central differences need it), got {edge!r}")
    edge = int(edge)
    n = t_a.size
    if n - 2 * edge < 1:
        raise ValueError(f"{n} samples are too few to drop {edge} at each end (cut-off {fc:g} Hz)")
    if kept is not None and not (kept.step in (None, 1) and 2 <= kept.start < kept.stop <= n - 2):
        raise ValueError(f"kept must be a slice within [2, {n - 2}) of the {n} samples, got {kept}")
    q_f = lowpass(q_a, rate, fc, order)
    dq = _central_difference(q_f, step)   # eq. 20
    ddq = _central_difference(dq, step)   # eq. 20 again, on q̇
    kept = slice(edge, n - edge) if kept is None else kept
    return Derivatives(t=t_a[kept], q=q_f[kept], dq=dq[kept], ddq=ddq[kept], cutoff=fc, rate=rate, kept=kept)


def decimation_factor(rate: float, target_rate: float) -> int:
    """Integer down-sampling factor from ``rate`` to ``target_rate`` (both Hz).

    Raises:
        ValueError: when ``rate / target_rate`` is below 1 or not an integer (within 1e-9).
            :func:`decimation_plan` takes the nearest achievable rate instead.
    """
    rate = _check_rate(rate)
    target = _check_rate(target_rate)
    ratio = rate / target
    k = round(ratio)
    if ratio < 1.0 - 1e-9:
        raise ValueError(f"target rate {target:g} Hz is above the sampling rate {rate:g} Hz: cannot decimate")
    if abs(ratio - k) > 1e-9 * max(1.0, ratio):
        raise ValueError(
            f"rate {rate:g} Hz / target {target:g} Hz = {ratio:.6g} is not an integer; "
            f"choose a target rate that divides the sampling rate (e.g. {rate / max(1, math.floor(ratio)):g} Hz)"
        )
    return int(k)


@dataclass(frozen=True)
class DecimationPlan:
    """How a recording is down-sampled: factor, achieved rate (Hz) and a note when it differs from the target."""

    factor: int
    rate: float
    note: str = ""


def decimation_plan(rate: float, target_rate: float | None) -> DecimationPlan:
    """The integer factor that brings ``rate`` nearest to ``target_rate`` (both Hz).

    A clock off by 0.005 % or jittered time stamps give ratios such as 4.99998: the factor is then
    the nearest integer and the achieved rate ``rate / factor`` is reported in ``note`` when it
    differs from the target by more than 1e-9 relative. ``target_rate`` None or 0 turns decimation
    off (factor 1). A target above the sampling rate is an error.
    """
    rate = _check_rate(rate)
    if target_rate is None or target_rate == 0:
        return DecimationPlan(1, rate)
    target = _check_rate(target_rate)
    ratio = rate / target
    if ratio < 1.0 - 1e-6:
        raise ValueError(f"target rate {target:g} Hz is above the sampling rate {rate:g} Hz: cannot decimate "
                         f"(give a lower rate, or 0 for no decimation)")
    k = max(1, int(round(ratio)))
    achieved = rate / k
    note = ""
    if abs(ratio - k) > 1e-9 * max(1.0, ratio):
        note = (f"rate {rate:.6g} Hz / target {target:g} Hz = {ratio:.6g} is not an integer: "
                f"decimating by {k} to {achieved:.6g} Hz")
    return DecimationPlan(k, achieved, note)


def _stages(factor: int) -> list[int]:
    """Split ``factor`` into stages ≤ 13 where possible (scipy's advice for the IIR filter)."""
    stages, rest = [], factor
    while rest > 1:
        d = next((d for d in range(min(rest, 13), 1, -1) if rest % d == 0), rest)
        stages.append(d)
        rest //= d
    return stages


def decimate(x: np.ndarray, factor: int, ftype: str = "iir") -> np.ndarray:
    """Parallel filtering: zero-phase low-pass and down-sampling by ``factor`` along axis 0.

    Apply it with the same ``factor`` and ``ftype`` to the torque vector Y **and** to every column
    of the observation matrix W (e.g. a regressor batch of shape (N, n, nb) in one call: time
    is axis 0), and keep ``t[::factor]`` as their time. With ``ftype="iir"`` (default) each stage
    is scipy's order-8 Chebyshev I filter with cut-off 0.8·(rate/2)/stage, the ``0.8·ωs/(2·nd)``
    of Gautier's parallel filter, run forward–backward (no phase lag); its passband ripple
    (0.05 dB per pass, so up to 0.1 dB ≈ 1.2 % per stage) is harmless for identification because
    Y and W see the same gain. ``ftype="fir"`` (Hamming-window FIR, 20·stage+1 taps) has a flat
    passband. Factors above 13 are done in stages of at most 13 when they factor so; the samples
    kept are still ``x[::factor]``.

    Args:
        x: (N, ...) samples.
        factor: integer ≥ 1 (see :func:`decimation_factor`); 1 returns a copy.
        ftype: ``"iir"`` or ``"fir"`` (scipy.signal.decimate).

    Returns:
        (ceil(N / factor), ...) array.
    """
    from scipy import signal  # imported when filtering, not when a command starts
    if int(factor) != factor or factor < 1:
        raise ValueError(f"factor must be an integer >= 1, got {plain(factor)}")
    if ftype not in ("iir", "fir"):
        raise ValueError(f"ftype must be 'iir' or 'fir', got {ftype!r}")
    a = _as_samples(x, "x")
    flat = a.reshape(a.shape[0], -1)
    # A column of zeros stays zeros through the filter (half a regressor's entries: a joint's row
    # holds no parameter of the links before it): only the others are filtered.
    live = np.flatnonzero(np.any(flat != 0.0, axis=0))
    # Column groups of about DECIMATE_CHUNK_BYTES: the filter's padded copies and passes then take
    # that much memory, not several copies of a wide W (each column is filtered alone either way).
    step = max(1, DECIMATE_CHUNK_BYTES // (8 * max(1, flat.shape[0])))
    out = np.zeros((len(range(0, flat.shape[0], int(factor))), flat.shape[1]))
    for c0 in range(0, live.size, step):
        cols = live[c0:c0 + step]
        y = np.array(flat[:, cols], dtype=float, copy=True)
        for stage in _stages(int(factor)):
            y = signal.decimate(y, stage, ftype=ftype, zero_phase=True, axis=0)
        out[:, cols] = y
    return out.reshape((out.shape[0],) + a.shape[1:])


#: Bytes of the input filtered at once by :func:`decimate` (column groups of a wide array).
DECIMATE_CHUNK_BYTES = 32 << 20
