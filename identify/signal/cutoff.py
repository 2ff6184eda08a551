"""The cut-off frequency of the derivatives' low-pass, chosen from the positions themselves.

* :func:`choose_cutoff` — where noise starts to dominate the acceleration (the rule below);
* :func:`crossover_frequencies` — the per-joint figures behind it;
* :func:`cutoff_from_spectrum` — the same rule from a Welch spectrum computed elsewhere (a long
  log's, streamed by :class:`identify.signal.blocks.WelchAccumulator`).
"""
from __future__ import annotations

import numpy as np

from identify.signal._checks import _as_samples, _check_rate

__all__ = ["choose_cutoff", "crossover_frequencies", "cutoff_from_spectrum", "welch_segment"]


def _band_spectrum(a: np.ndarray, rate: float, seconds: float, per_octave: int) -> tuple[np.ndarray, np.ndarray]:
    """Welch PSD of ``a`` averaged in log-spaced bands: (band centre frequencies Hz, mean PSD)."""
    from scipy import signal  # imported when filtering, not when a command starts
    nperseg = welch_segment(a.size, rate, seconds)
    f, psd = signal.welch(a, fs=rate, window="hann", nperseg=nperseg, detrend="constant")
    return _bands(f, psd, rate, per_octave)


def welch_segment(samples: int, rate: float, seconds: float) -> int:
    """Samples per Welch segment of :func:`crossover_frequencies` (``seconds`` long, at most all)."""
    return min(samples, max(16, int(round(seconds * rate))))


def _bands(f: np.ndarray, psd: np.ndarray, rate: float, per_octave: int) -> tuple[np.ndarray, np.ndarray]:
    """A Welch PSD averaged in 1/``per_octave`` octave bands: (band centres Hz, mean PSD).

    Averaging in log-spaced bands steadies the estimate at high frequency (many bins per band)
    while keeping the resolution of the Welch estimate at low frequency.
    """
    df = f[1] - f[0]
    n_bands = int(np.floor(np.log2((rate / 2.0) / (2.0 * df)) * per_octave)) + 1
    edges = 2.0 * df * 2.0 ** (np.arange(n_bands + 1) / per_octave)
    centres, values = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        inside = (f >= lo) & (f < hi)
        if inside.any():
            centres.append(np.sqrt(lo * hi))
            values.append(psd[inside].mean())
    return np.asarray(centres), np.asarray(values)


def _crossover(x: np.ndarray, rate: float, seconds: float, per_octave: int, snr_min: float,
               floor_ratio: float = 4.0) -> float | None:
    """Frequency (Hz) where the acceleration spectrum of ``x`` turns from signal to noise.

    ``a`` is the raw (unfiltered) second central difference of ``x``. Its spectrum falls
    with frequency where the motion dominates and rises (white noise: as f⁴) or stays flat
    (coloured noise, vibrations) where noise dominates; the minimum above the motion's main
    frequency is the crossover. Returns None when the joint does not move (position spectrum at
    its peak less than ``snr_min`` times its value at the crossover).
    """
    a = (x[2:] - 2.0 * x[1:-1] + x[:-2]) * rate**2
    f, s_acc = _band_spectrum(a, rate, seconds, per_octave)
    return _crossover_of_bands(f, s_acc, rate, snr_min, floor_ratio)


def _crossover_of_bands(f: np.ndarray, s_acc: np.ndarray, rate: float, snr_min: float,
                        floor_ratio: float = 4.0) -> float | None:
    """The crossover of :func:`_crossover` from the band spectrum of the acceleration."""
    # Position spectrum seen through the exact gain of the second difference, |2·rate·sin(πf/rate)|⁴.
    s_pos = s_acc / (2.0 * rate * np.sin(np.pi * f / rate)) ** 4
    peak = int(np.argmax(s_pos))  # the motion's main frequency: positions are dominated by it
    # The knee, not the minimum: a flat noise floor (servo, ripple) has its minimum anywhere along
    # it, so the first band within floor_ratio of the lowest level is the stable choice.
    floor = float(np.min(s_acc[peak:]))
    cross = peak + int(np.flatnonzero(s_acc[peak:] <= floor_ratio * floor)[0])
    if s_pos[peak] < snr_min * s_pos[cross]:
        return None
    return float(f[cross])


def cutoff_from_spectrum(f: np.ndarray, psd: np.ndarray, rate: float, *, min_cutoff: float = 2.0,
                         max_fraction: float = 0.4, bands_per_octave: int = 6, snr_min: float = 100.0) -> float:
    """:func:`choose_cutoff` from the Welch PSD (columns: joints) of the raw accelerations, computed elsewhere
    (e.g. streamed over a long log by :class:`identify.signal.blocks.WelchAccumulator`)."""
    found = []
    for j in range(psd.shape[1]):
        fb, sb = _bands(f, psd[:, j], rate, bands_per_octave)
        found.append(_crossover_of_bands(fb, sb, rate, snr_min))
    return _bounded_cutoff(np.array([np.nan if x is None else x for x in found]), rate, min_cutoff, max_fraction)


def _bounded_cutoff(found: np.ndarray, rate: float, min_cutoff: float, max_fraction: float) -> float:
    ceiling = max_fraction * rate / 2.0
    if np.all(np.isnan(found)):
        return float(min(min_cutoff, ceiling))
    return float(min(max(np.nanmax(found), min_cutoff), ceiling))


def crossover_frequencies(
    q: np.ndarray, rate: float, *, segment: float = 4.0, bands_per_octave: int = 6, snr_min: float = 100.0,
) -> np.ndarray:
    """Per-joint frequency (Hz) where noise starts to dominate the acceleration (rule of :func:`choose_cutoff`).

    Args:
        q: (N,) or (N, n) joint positions, rad, uniformly sampled, N ≥ 64.
        rate: sampling rate, Hz.
        segment: Welch segment length, s (resolution 1/segment Hz).
        bands_per_octave: spectral smoothing, bands per octave.
        snr_min: peak-to-crossover ratio of the position spectrum below which a joint is still.

    Returns:
        (n,) frequencies, Hz; NaN for a joint that does not move.
    """
    rate = _check_rate(rate)
    if not (segment > 0.0):
        raise ValueError(f"segment must be a positive duration in s, got {segment!r}")
    a = _as_samples(q, "q", min_rows=64)  # fewer samples give no usable spectrum
    columns = a.reshape(a.shape[0], -1)
    found = [_crossover(columns[:, j], rate, segment, bands_per_octave, snr_min) for j in range(columns.shape[1])]
    return np.array([np.nan if f is None else f for f in found])


def choose_cutoff(
    q: np.ndarray, rate: float, *, min_cutoff: float = 2.0, max_fraction: float = 0.4,
    segment: float = 4.0, bands_per_octave: int = 6, snr_min: float = 100.0,
) -> float:
    """Cut-off frequency (Hz) for :func:`lowpass` / :func:`derivatives`, chosen from the positions.

    Rule: *cut where noise starts to dominate the acceleration*. For each joint:

    1. ``a(k) = [q(k+1) − 2·q(k) + q(k−1)] / T²``, the raw (unfiltered) second central difference;
    2. its power spectral density (Welch, Hann window, segments of ``segment`` s → resolution
       1/segment Hz), averaged in 1/6-octave bands;
    3. the motion's main frequency ``f_peak`` is the peak of the position spectrum (the
       acceleration spectrum divided by the gain of the second difference);
    4. ``f_j`` is the knee of the acceleration spectrum above ``f_peak``: the first band whose level
       is within 4× of the lowest level above ``f_peak``. Below it the motion's acceleration
       dominates (the spectrum falls); above it the noise does (the spectrum rises as f⁴ for white
       position noise, or stays flat for coloured noise, servo noise and vibrations). The knee, not
       the minimum itself: on a flat floor the minimum lands anywhere along it (the first design
       gave 3.36 Hz on one 250 Hz twin recording and 50 Hz on another of the same robot, 42.7 Hz
       and 101.5 Hz on the two parts of the TX40 record); the knee gives 2.1–2.4 Hz over five twin
       seeds and 19.0 / 20.1 Hz on the TX40's first 6 s / last 3 s.
       Cutting at ``f_j`` keeps the motion's acceleration and rejects the noise that
       differentiation amplifies. Joints that do not move (peak less than ``snr_min`` = 100
       times the crossover level in the position spectrum) are skipped.
       :func:`crossover_frequencies` returns these ``f_j``.

    Then ``cutoff = max_j f_j`` — the largest, so that no joint's acceleration is filtered away
    (the parallel decimation filter, applied to Y and W alike, removes the remaining noise) — bounded
    to ``[min_cutoff, max_fraction · rate/2]`` (2 Hz and 40 % of Nyquist): the floor keeps a very
    slow or very noisy motion from losing the closed-loop dynamics seen in the torques; the ceiling
    keeps the filter well defined. When the bounds cross (very low rates) the ceiling wins. If no
    joint moves, the floor (bounded likewise) is returned.

    Why not a rule on the position spectrum alone (e.g. 5 × the frequency holding 99 % of the
    position power, as a first design had it): on the real TX40 recording it gives 7.8 Hz, which
    changes q̈ by 12–21 % RMS compared with a 30 Hz cut-off; motions from a controller's
    interpolator have acceleration content well above the position's bandwidth.

    Args:
        q: (N,) or (N, n) joint positions, rad, uniformly sampled, N ≥ 64.
        rate: sampling rate, Hz.
        min_cutoff: lower bound, Hz.
        max_fraction: upper bound as a fraction of the Nyquist frequency ``rate/2``.
        segment, bands_per_octave, snr_min: see :func:`crossover_frequencies`.

    Returns:
        The cut-off frequency, Hz.
    """
    rate = _check_rate(rate)
    if not (0.0 < max_fraction < 1.0):
        raise ValueError(f"max_fraction must lie in (0, 1), got {max_fraction!r}")
    found = crossover_frequencies(q, rate, segment=segment, bands_per_octave=bands_per_octave, snr_min=snr_min)
    return _bounded_cutoff(found, rate, min_cutoff, max_fraction)
