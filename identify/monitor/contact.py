"""Contact detection on the momentum residual: thresholds, events, and the online monitor.

:class:`ContactMonitor` is the controller-loop side: ``update(t, q, qd, effort)`` makes one call
of the compiled observer step (:mod:`identify.monitor.observer`) on preallocated buffers and
returns the residual [N·m] and whether a contact is on. A joint is active once |r_j| exceeds its
threshold T_j and until |r_j| falls below ``RELEASE``·T_j (hysteresis); a contact is on once some
joint has been active for ``MIN_DURATION_S`` without a break. Events (start, end, joints, peak
per joint) are kept in ``history``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from identify.monitor.observer import DEFAULT_GAIN, ObserverModel, observer_model

__all__ = ["CALIBRATION_MARGIN", "CALIBRATION_QUANTILE", "ContactEvent", "ContactMonitor", "DETECTION_WINDOW_S",
           "EventTracker", "MIN_DURATION_S", "RELEASE", "detectable_sizes", "gain_vector", "threshold_vector"]

#: Hysteresis: a joint stays active until |r| < RELEASE · T.
RELEASE = 0.5
#: A contact is declared after this long above threshold [s] (single-sample spikes are ignored).
MIN_DURATION_S = 0.01
#: Thresholds from contact-free data: this quantile of |r_j| times the margin (docs/contact-monitor.md).
CALIBRATION_QUANTILE = 0.999
CALIBRATION_MARGIN = 2.5
#: The detection budget the detectable size refers to [s].
DETECTION_WINDOW_S = 0.05


@dataclass(frozen=True)
class ContactEvent:
    """One contact: start_s, end_s [s] from the recording's first sample (start: first sample over
    threshold; end: first sample with no joint active, or the last sample), joints (1-based) over
    threshold, peak_nm (n,) the residual of largest magnitude per joint during the event [N·m],
    signed; detected_s: when the contact was declared (start + :data:`MIN_DURATION_S` or later)."""

    start_s: float
    end_s: float
    joints: tuple[int, ...]
    peak_nm: tuple[float, ...]
    detected_s: float = float("nan")

    def to_json(self) -> dict[str, Any]:
        return {"start_s": self.start_s, "end_s": self.end_s, "joints": list(self.joints),
                "peak_nm": [float(v) for v in self.peak_nm], "detected_s": self.detected_s}


def gain_vector(gain: float | Sequence[float] | None, n: int) -> np.ndarray:
    """K_O per joint [rad/s] from one number or n (None: :data:`DEFAULT_GAIN`)."""
    K = np.full(n, DEFAULT_GAIN) if gain is None else np.broadcast_to(np.asarray(gain, dtype=float), (n,)).copy()
    if not np.all(np.isfinite(K) & (K > 0)):
        raise ValueError(f"observer gain K_O must be positive rad/s, got {K.tolist()}")
    return K


def threshold_vector(threshold: float | Sequence[float], n: int) -> np.ndarray:
    """Thresholds per joint [N·m] from one number or n; positive and finite."""
    T = np.asarray(threshold, dtype=float).reshape(-1)
    if T.size not in (1, n) or not np.all(np.isfinite(T) & (T > 0)):
        raise ValueError(f"thresholds must be one or {n} positive numbers in N·m, got {T.tolist()}")
    return np.broadcast_to(T, (n,)).copy()


def detectable_sizes(thresholds: np.ndarray, gain: np.ndarray, slack: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(moving, rest) smallest step of external torque [N·m] per joint that the monitor reports
    within :data:`DETECTION_WINDOW_S`: the residual follows K_O/(s + K_O), so a step A crosses a
    level L after −ln(1 − L/A)/K_O; with the minimum duration, A ≥ L / (1 − e^{−K_O (window − min
    duration)}). Moving, L = T; at rest the threshold rides on the slack d (up to 1.25 FS) and the
    unknown static friction (up to d) may oppose the push: L = T + 2 d (``slack``: d per joint)."""
    reach = 1 - np.exp(-gain * (DETECTION_WINDOW_S - MIN_DURATION_S))
    return thresholds / reach, (thresholds + 2 * slack) / reach


class EventTracker:
    """Events from the observer's states, fed block by block (or sample by sample)."""

    def __init__(self, n: int, min_duration: float = MIN_DURATION_S) -> None:
        self.n, self.min_duration = n, float(min_duration)
        self.events: list[ContactEvent] = []
        self._open = False
        self._start = 0.0
        self._peak = np.zeros(n)
        self._joints = np.zeros(n, dtype=bool)
        self._reached = False
        self._detected = float("nan")
        self._last_t = 0.0

    @property
    def open(self) -> bool:
        return self._open

    def feed(self, t: np.ndarray, r: np.ndarray, active: np.ndarray, elapsed: np.ndarray) -> None:
        """t (N,) [s]; r (N, n) [N·m]; active (N, n) 0/1; elapsed (N,) [s] (−1: nothing active)."""
        if t.shape[0] == 0:
            return
        inrun = elapsed >= 0
        flags = np.concatenate([[self._open], inrun]).astype(np.int8)
        edges = np.flatnonzero(np.diff(flags))
        bounds = list(edges)
        if self._open:
            bounds = [0] + bounds  # the run goes on from before this block (its start is recorded)
        for k in range(0, len(bounds), 2):
            s = bounds[k]
            e = bounds[k + 1] if k + 1 < len(bounds) else t.shape[0]
            if not self._open:
                self._open, self._start = True, float(t[s])
                self._peak[:] = 0.0
                self._joints[:] = False
                self._reached = False
                self._detected = float("nan")
            seg = r[s:e]
            if seg.shape[0]:
                i = np.argmax(np.abs(seg), axis=0)
                cand = seg[i, np.arange(self.n)]
                bigger = np.abs(cand) > np.abs(self._peak)
                self._peak[bigger] = cand[bigger]
                self._joints |= active[s:e].astype(bool).any(axis=0)
                if not self._reached:
                    over = np.flatnonzero(elapsed[s:e] >= self.min_duration)
                    if over.size:
                        self._reached, self._detected = True, float(t[s + over[0]])
            if e < t.shape[0]:
                self._close(float(t[e]))
        self._last_t = float(t[-1])

    def _close(self, end: float) -> None:
        if self._reached:
            self.events.append(ContactEvent(self._start, end, tuple(int(j) + 1 for j in np.flatnonzero(self._joints)),
                                            tuple(float(v) for v in self._peak), self._detected))
        self._open = False

    def finish(self) -> None:
        """Close an event still open at the last sample (its end: the last sample's time)."""
        if self._open:
            self._close(self._last_t)


class ContactMonitor:
    """Contact monitor for a controller loop on an identified model.

    fit: a :class:`identify.Fit` (e.g. :func:`identify.load_fit`); rate_hz: the loop's rate [Hz]
    (the fit's torque delay is compensated by delaying q, q̇ round(delay·rate) samples);
    thresholds: per joint [N·m] (None: the fit file's ``contact_thresholds_nm``); gain: K_O
    [rad/s], one or per joint (None: :data:`DEFAULT_GAIN`); effort: "torque" or "current" (None:
    current when the fit has drive gains).
    """

    def __init__(self, fit: Any, rate_hz: float, thresholds: float | Sequence[float] | None = None,
                 gain: float | Sequence[float] | None = None, effort: str | None = None,
                 model: ObserverModel | None = None) -> None:
        if not (math.isfinite(rate_hz) and rate_hz > 0):
            raise ValueError(f"rate_hz must be a positive rate in Hz, got {rate_hz!r}")
        self.model = model if model is not None else observer_model(fit, effort)
        n = self.n = self.model.n
        if thresholds is None:
            thresholds = getattr(fit, "contact_thresholds", None)
            if thresholds is None:
                raise ValueError("the fit has no contact thresholds (written before they were stored): give "
                                 "thresholds, or calibrate them on contact-free data (identify.monitor.log.calibrate)")
        self.thresholds = threshold_vector(thresholds, n)
        self.gain = gain_vector(gain, n)
        self.rate_hz = float(rate_hz)
        self.delay_samples = int(round(max(fit.delay, 0.0) * rate_hz))
        self._params = self.model.params(self.gain, self.thresholds, RELEASE)
        self._run, self._iw, self._w = self.model.runner()
        self._state = self.model.initial_state()
        self._out = np.zeros((1, self.model.state_size))
        self._dt = np.zeros(1)
        self._ring = np.zeros((self.delay_samples + 1, 2, n))
        self._e = np.zeros((1, n))
        self._ptrs = None
        self.history: list[ContactEvent] = []
        self.reset()

    def reset(self) -> None:
        """Back to the state before the first sample (residual 0); ``history`` kept."""
        self._state[:] = self.model.initial_state()
        self._k = 0
        self._t0 = self._t_prev = 0.0
        self._tracker = EventTracker(self.n)
        self._tracker.events = self.history

    def update(self, t: float, q: Sequence[float], qd: Sequence[float], effort: Sequence[float]) -> tuple[np.ndarray, bool]:
        """One sample: time t [s], q [rad] (model angles), q̇ [rad/s], effort (torque [N·m] or current
        [A]); returns (residual r (n,) [N·m], contact on)."""
        m = self.delay_samples
        slot = self._ring[self._k % (m + 1)]
        slot[0], slot[1] = q, qd
        if self._k == 0:
            self._ring[:] = slot
            self._t0 = self._t_prev = t
        kin = self._ring[(self._k + 1) % (m + 1)] if m else slot
        self._e[0] = effort
        self._dt[0] = t - self._t_prev if self._k else 0.0
        if self._run(1, self.n, kin[0].ctypes.data, kin[1].ctypes.data, self._e.ctypes.data, self._dt.ctypes.data,
                     self._params.ctypes.data, self._state.ctypes.data, self._out.ctypes.data,
                     self._iw.ctypes.data, self._w.ctypes.data):
            raise RuntimeError("ContactMonitor: compiled observer step failed")
        self._k += 1
        self._t_prev = t
        out = self._out[0]
        n = self.n
        if out[-1] >= 0 or self._tracker.open:
            self._tracker.feed(np.array([t - self._t0]), self._out[:, 2 * n:3 * n], self._out[:, 3 * n:4 * n],
                               self._out[:, -1])
        return out[2 * n:3 * n].copy(), bool(out[-1] >= MIN_DURATION_S)
