"""Block-wise filtering: the whole-signal filters of :mod:`identify.signal.filtering` on overlapping blocks.

A zero-phase IIR filter (forward–backward) started inside a signal leaves a transient that decays
like the filter's impulse response. A block read with a margin of M samples on each side, filtered
whole, and cut back to its core therefore equals the whole-signal result on the core up to the
impulse response's envelope after M samples. :func:`settling_samples` finds M numerically for a
given tolerance (:data:`BLOCK_TOLERANCE`, relative to the impulse response's peak), for the
Butterworth low-pass of eq. 20's derivatives and for every stage of the parallel decimation
filter; :func:`motion_margins` adds them up. At the two true ends of a recording the block reaches
the end, so the edge handling (odd extension, trimmed edges) is the whole-signal one exactly.

:class:`WelchAccumulator` streams the Welch spectrum behind :func:`identify.choose_cutoff`, so the
automatic cut-off is chosen on all of a long log without holding it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from identify.signal.filtering import _stages

__all__ = ["BLOCK_TOLERANCE", "Window", "WelchAccumulator", "decimation_margin", "lowpass_margin",
           "motion_windows", "settling_samples"]

#: Relative size of the impulse-response tail ignored at a block edge. The error on a filtered
#: sample is at most this times the signal's range times the response's L1 norm (≈ 1-3 for these
#: filters), so 1e-12 keeps block-wise W and Y equal to the whole-signal ones to ~1e-11 relative,
#: far below the 1e-8 asked of the estimates and below the noise of any recording.
BLOCK_TOLERANCE = 1e-12


@lru_cache(maxsize=64)
def settling_samples(b: tuple[float, ...], a: tuple[float, ...], tol: float = BLOCK_TOLERANCE) -> int:
    """Samples after which the impulse response of the filter ``b/a`` stays below ``tol`` × its peak.

    The response is computed until its envelope (running maximum from the end) falls below ``tol``;
    the forward–backward filter's transient decays like the same response, so this is the margin.
    """
    from scipy import signal  # imported when filtering, not when a command starts

    length = 1024
    while True:
        impulse = np.zeros(length)
        impulse[0] = 1.0
        h = np.abs(signal.lfilter(b, a, impulse))
        peak = h.max()
        above = np.flatnonzero(h > tol * peak)
        if above[-1] < length // 2 or length >= 1 << 24:
            return int(above[-1]) + 1
        length *= 4


def lowpass_margin(rate: float, cutoff: float, order: int = 4, tol: float = BLOCK_TOLERANCE) -> int:
    """Margin (samples) for the zero-phase Butterworth of :func:`identify.lowpass` at ``cutoff`` Hz."""
    from scipy import signal

    b, a = signal.butter(int(order), cutoff, btype="low", fs=rate)
    return settling_samples(tuple(b), tuple(a), tol)


def decimation_margin(factor: int, tol: float = BLOCK_TOLERANCE) -> int:
    """Margin (input samples, a multiple of ``factor``) for :func:`identify.decimate` by ``factor``.

    Stage after stage, as scipy's IIR decimation filter (Chebyshev I, order 8, 0.05 dB, cut-off
    0.8/stage) runs: a stage's margin counts in the samples of its own rate.
    """
    from scipy import signal

    total, scale = 0, 1
    for stage in _stages(int(factor)):
        b, a = signal.cheby1(8, 0.05, 0.8 / stage)
        total += (settling_samples(tuple(b), tuple(a), tol) + 1) * scale
        scale *= stage
    return int(math.ceil(total / factor) * factor) if factor > 1 else 0


@dataclass(frozen=True)
class Window:
    """One block of a recording of ``n`` samples.

    raw: [r0, r1) samples read (core plus margins); span: [d0, d1) samples fed to the decimation
    filter (``d0 ≡ edge mod factor``); core: [c0, c1) decimated samples this block contributes
    (global indices in the recording's decimated motion).
    """

    raw: tuple[int, int]
    span: tuple[int, int]
    core: tuple[int, int]


def motion_windows(n: int, edge: int, factor: int, block: int, lp_margin: int, dec_margin: int) -> list[Window]:
    """The blocks that cover a recording's decimated motion, each with its margins.

    The whole-signal pipeline keeps raw samples [edge, n − edge) after differentiation and
    decimates them by ``factor`` (decimated sample j is raw sample edge + j·factor). Block cores
    hold ``block // factor`` decimated samples; a block reads its core plus ``dec_margin`` for the
    decimation filter, plus ``lp_margin + 2`` for the low-pass and the two central differences.
    A block that reaches an end of the recording starts (or stops) exactly as the whole signal does.
    """
    kept = n - 2 * edge
    if kept < 1:
        raise ValueError(f"{n} samples are too few to drop {edge} at each end")
    total = -(-kept // factor)
    per = max(1, block // factor)
    out = []
    for c0 in range(0, total, per):
        c1 = min(total, c0 + per)
        d0 = edge + c0 * factor - dec_margin
        r0 = d0 - lp_margin - 2
        if r0 <= 0:
            r0, d0 = 0, edge
        d1 = edge + (c1 - 1) * factor + 1 + dec_margin
        r1 = d1 + lp_margin + 2
        if r1 >= n:
            r1, d1 = n, n - edge
        out.append(Window((r0, r1), (d0, d1), (c0, c1)))
    return out


class WelchAccumulator:
    """Welch's averaged periodogram of a signal fed in pieces (equal to ``scipy.signal.welch`` on the whole).

    Segments of ``nperseg`` samples start every ``nperseg // 2`` samples from the signal's start,
    as scipy's defaults (Hann window, constant detrend, density scaling) place them; each finished
    segment's periodogram is added, and :meth:`result` is their mean.
    """

    def __init__(self, rate: float, nperseg: int, columns: int) -> None:
        self.rate, self.nperseg, self.step = float(rate), int(nperseg), int(nperseg) - int(nperseg) // 2
        self._buffer = np.empty((0, columns))
        self._sum: np.ndarray | None = None
        self._count = 0
        self._freqs: np.ndarray | None = None

    def feed(self, x: np.ndarray) -> None:
        """Append samples (m, columns) and add the periodograms of the segments they complete."""
        self._buffer = np.concatenate([self._buffer, np.asarray(x, dtype=float)])
        segments = (self._buffer.shape[0] - self.nperseg) // self.step + 1 if self._buffer.shape[0] >= self.nperseg else 0
        if segments < 1:
            return
        used = (segments - 1) * self.step + self.nperseg
        from scipy import signal

        # Column by column, as choose_cutoff computes it (same FFT calls, same rounding).
        spectra = [signal.welch(self._buffer[:used, j], fs=self.rate, window="hann", nperseg=self.nperseg,
                                noverlap=self.nperseg - self.step, detrend="constant")
                   for j in range(self._buffer.shape[1])]
        self._freqs = spectra[0][0]
        p = np.column_stack([s[1] for s in spectra])
        self._sum = p * segments if self._sum is None else self._sum + p * segments
        self._count += segments
        self._buffer = self._buffer[segments * self.step:]

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        """(frequencies Hz, mean PSD per column)."""
        if self._sum is None:
            raise ValueError(f"fewer than {self.nperseg} samples: no Welch segment")
        return self._freqs, self._sum / self._count
