"""The contact monitor run over a recording, block by block (memory flat in the log's duration).

The same compiled observer step as :class:`identify.monitor.contact.ContactMonitor`, run on each
block in one C loop: the residual of a log equals the online monitor's, sample for sample. Times
count from the recording's first sample; no edge is trimmed. A recording without velocities gets
them by central differences of q (``numpy.gradient`` on the whole record, one-sided at its two
ends; blocks overlap so that the result does not depend on the block size).
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Iterator, Sequence

import numpy as np

from identify.monitor.contact import (CALIBRATION_MARGIN, CALIBRATION_QUANTILE, MIN_DURATION_S, RELEASE, ContactEvent,
                                      EventTracker, detectable_sizes, gain_vector, threshold_vector)
from identify.monitor.defaults import DEFAULT_MONITOR_BLOCK
from identify.monitor.observer import ObserverModel, observer_model

__all__ = ["DEFAULT_MONITOR_BLOCK", "MonitorLog", "MonitorInputError", "calibrate", "check_fit", "monitor_log"]

#: Residual envelope kept for the report: the signed extremes per this span [s] (memory: 1 h at
#: 1 kHz, 7 joints, about 12 MB).
ENVELOPE_S = 0.05


class MonitorInputError(ValueError):
    """A recording or fit the monitor cannot judge (the command line exits 2)."""


@dataclass(frozen=True, eq=False)
class MonitorLog:
    """What the monitor found on one recording: events; thresholds_nm, gain (K_O, rad/s) per joint;
    n_samples, duration_s; t, residual (S, n) [N·m] and contact (S,) when kept (``keep=True``);
    envelope: (t (B,), lo (B, n), hi (B, n), threshold (B, n), contact (B,)) per
    :data:`ENVELOPE_S` (for the report), the threshold with the friction slack;
    slack (S, n): the friction slack d_j [N·m], when kept;
    detectable_moving_nm, detectable_rest_nm: per joint (:func:`detectable_sizes`)."""

    source: str
    events: tuple[ContactEvent, ...]
    thresholds_nm: np.ndarray
    gain: np.ndarray
    n_samples: int
    duration_s: float
    detectable_moving_nm: np.ndarray
    detectable_rest_nm: np.ndarray
    envelope: tuple[np.ndarray, ...] | None = None
    t: np.ndarray | None = None
    residual: np.ndarray | None = None
    contact: np.ndarray | None = None
    slack: np.ndarray | None = None

    def table(self) -> str:
        head = f"{self.source}: {len(self.events)} contact event(s) in {self.duration_s:.3f} s ({self.n_samples} samples)"
        if not self.events:
            return head
        rows = [f"{'start [s]':>10} {'end [s]':>10}  joints      peak per joint [N·m]"]
        for e in self.events:
            peaks = " ".join(f"{v:8.2f}" for v in e.peak_nm)
            rows.append(f"{e.start_s:10.3f} {e.end_s:10.3f}  {','.join(map(str, e.joints)):<10}  {peaks}")
        return "\n".join([head, *rows])

    def to_json(self, fit_sha256: str | None = None) -> dict[str, Any]:
        return {"source": self.source, "events": [e.to_json() for e in self.events],
                "thresholds_nm": self.thresholds_nm.tolist(), "gain": self.gain.tolist(),
                "release": RELEASE, "min_duration_s": MIN_DURATION_S,
                "detectable_moving_nm": self.detectable_moving_nm.tolist(),
                "detectable_rest_nm": self.detectable_rest_nm.tolist(),
                "n_samples": self.n_samples, "duration_s": self.duration_s, "fit_sha256": fit_sha256}


def check_fit(fit: Any) -> None:
    """Refuse a fit the monitor cannot use: no friction terms (the friction would read as an
    external torque), or columns it does not model."""
    from identify.monitor.observer import _kind, supported

    why = supported(fit)
    if why:
        raise MonitorInputError(why)
    values = dict(zip(fit.result.names, fit.result.values))
    if not any(_kind(nm) in ("FS", "FV", "FSP", "FSN", "FSM", "FVM") and v != 0.0 for nm, v in values.items()):
        raise MonitorInputError(
            f"the fit of robot {fit.robot.name!r} has no friction terms (FSj, FVj): every real joint has friction, "
            f"which the monitor would report as an external torque; identify the robot with its friction")


def _blocks(fit: Any, recording: Any, block: int) -> Iterator[tuple[Any, bool]]:
    """(block recording, is the last) with one block of look-ahead."""
    from identify.io.blocks import block_source

    src = block_source(recording, fit.robot, fit.model.convention, fit.gains)
    it = iter(src.scan(block))
    try:
        cur = next(it)
    except StopIteration:
        raise MonitorInputError(f"{getattr(src, 'source', recording)}: no samples") from None
    for nxt in it:
        yield cur, False
        cur = nxt
    yield cur, True


def monitor_log(fit: Any, recording: Any, thresholds: float | Sequence[float] | None = None,
                gain: float | Sequence[float] | None = None, *, block: int = DEFAULT_MONITOR_BLOCK,
                keep: bool = False, residual_csv: str | Path | None = None, envelope: bool = False,
                model: ObserverModel | None = None) -> MonitorLog:
    """Run the contact monitor over ``recording`` (a Recording, or a CSV/NPZ path of the toolkit's
    format; currents through the fit's gains), block by block.

    thresholds [N·m] (None: the fit's ``contact_thresholds``); gain K_O [rad/s] (None: default);
    keep: return the residual arrays (memory then grows with the log); residual_csv: write t [s]
    from the first sample, r1..rn [N·m] and contact (0/1) there, block by block (atomically).
    """
    check_fit(fit)
    n = fit.robot.n
    if thresholds is None:
        thresholds = getattr(fit, "contact_thresholds", None)
        if thresholds is None:
            raise MonitorInputError("the fit file has no contact thresholds (contact_thresholds_nm; written before "
                                    "they were stored): calibrate them on contact-free data (--calibrate) or give "
                                    "--threshold")
    T, K = threshold_vector(thresholds, n), gain_vector(gain, n)
    model = model if model is not None else observer_model(fit, "torque")
    params = model.params(K, T, RELEASE)
    tracker = EventTracker(n)
    state = model.initial_state()
    m = 0
    tmp = None if residual_csv is None else Path(str(residual_csv) + ".part")
    fh: IO | None = None
    kept: list[tuple[np.ndarray, ...]] = []
    env: list[tuple[np.ndarray, ...]] = []
    done, seen, t0, t_prev = 0, 0, None, None
    hist: np.ndarray | None = None
    source = str(getattr(recording, "source", recording))
    try:
        if tmp is not None:
            fh = open(tmp, "w")
            fh.write(",".join(["t"] + [f"r{j + 1}" for j in range(n)] + [f"threshold{j + 1}" for j in range(n)])
                     + ",contact\n")
        for rec, last in _blocks(fit, recording, block):
            source = rec.source or source
            if rec.q.shape[1] != n:
                raise MonitorInputError(f"{rec.source}: {rec.q.shape[1]} joints, the fit's robot {fit.robot.name!r} "
                                        f"has {n}")
            new = int(rec.meta.get("new_from", 0))
            first_abs = seen - new   # absolute index of the block's first row
            seen += rec.n_samples - new
            if rec.dq is None and seen < 3:
                if last:
                    raise MonitorInputError(f"{rec.source}: no velocities and {seen} sample(s): at least 3 are "
                                            f"needed to differentiate q")
            stop = seen if (last or rec.dq is not None) else seen - 1
            rows = slice(done - first_abs, stop - first_abs)
            t = np.asarray(rec.t, dtype=float)
            qd_all = (np.asarray(rec.dq, dtype=float) if rec.dq is not None
                      else np.gradient(np.asarray(rec.q, dtype=float), t, axis=0))
            Q, QD, E, tb = rec.q[rows], qd_all[rows], rec.torques[rows], t[rows]
            if tb.shape[0] == 0:
                continue
            if t0 is None:
                t0 = t_prev = float(tb[0])
                m = int(round(max(fit.delay, 0.0) * rec.rate)) if fit.delay and rec.n_samples > 1 else 0
                hist = np.repeat(np.concatenate([Q[:1], QD[:1]], axis=1), m, axis=0)
            DT = np.diff(np.concatenate([[t_prev], tb]))
            kin = np.concatenate([hist, np.concatenate([Q, QD], axis=1)])
            hist = kin[kin.shape[0] - m:] if m else hist
            kin = kin[:tb.shape[0]]
            out = model.run(kin[:, :n], kin[:, n:], E, DT, params, state)
            ts = tb - t0
            r, active, elapsed = out[:, 2 * n:3 * n], out[:, 3 * n:4 * n], out[:, -1]
            level = T + out[:, 4 * n:5 * n]   # the thresholds with the friction slack
            tracker.feed(ts, r, active, elapsed)
            contact = elapsed >= MIN_DURATION_S
            if fh is not None:
                np.savetxt(fh, np.column_stack([ts, r, level, contact]), fmt=["%.6f"] + ["%.6g"] * (2 * n) + ["%d"],
                           delimiter=",")
            if keep:
                kept.append((ts, r.copy(), contact, out[:, 4 * n:5 * n].copy()))
            if envelope:
                env.append(_envelope(ts, r, level, contact, max(1, int(round(ENVELOPE_S * rec.rate)))))
            done, t_prev = stop, float(tb[-1])
        tracker.finish()
        if fh is not None:
            fh.close()
            fh = None
            os.replace(tmp, residual_csv)
    finally:
        if fh is not None:
            fh.close()
        if tmp is not None and tmp.exists():
            tmp.unlink()
    moving, rest = detectable_sizes(T, K, model.fs)
    ts_all = np.concatenate([k[0] for k in kept]) if keep else None
    return MonitorLog(source, tuple(tracker.events), T, K, done, float(t_prev - t0), moving, rest,
                      tuple(np.concatenate(x) for x in zip(*env)) if envelope else None,  # type: ignore[arg-type]
                      ts_all, np.concatenate([k[1] for k in kept]) if keep else None,
                      np.concatenate([k[2] for k in kept]) if keep else None,
                      np.concatenate([k[3] for k in kept]) if keep else None)


def _envelope(ts: np.ndarray, r: np.ndarray, level: np.ndarray, contact: np.ndarray, k: int) -> tuple[np.ndarray, ...]:
    starts = np.arange(0, ts.shape[0], k)
    return (ts[starts], np.minimum.reduceat(r, starts, axis=0), np.maximum.reduceat(r, starts, axis=0),
            np.maximum.reduceat(level, starts, axis=0), np.maximum.reduceat(contact.astype(np.int8), starts))


def calibrate(fit: Any, recordings: Sequence[Any], gain: float | Sequence[float] | None = None,
              quantile: float = CALIBRATION_QUANTILE, margin: float = CALIBRATION_MARGIN,
              block: int = DEFAULT_MONITOR_BLOCK) -> np.ndarray:
    """Thresholds per joint [N·m] from contact-free recordings: ``quantile`` of |r_j| above the
    friction slack d_j over all their samples, times ``margin`` (docs/contact-monitor.md)."""
    if not recordings:
        raise MonitorInputError("calibrate: no contact-free recording given")
    n = fit.robot.n
    big = np.full(n, 1e300)
    runs = [monitor_log(fit, rec, big, gain, block=block, keep=True) for rec in recordings]
    mags = [np.maximum(np.abs(x.residual) - x.slack, 0.0) for x in runs]
    return margin * np.quantile(np.concatenate(mags), quantile, axis=0)
