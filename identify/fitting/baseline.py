"""The plain OLS baseline: the yardstick every validation prints beside the toolkit's figure.

Exactly as the project's issue notes define it (what a user writes in 40 lines):

- q filtered by a 4th-order Butterworth at 10 Hz, zero phase (``scipy.signal.filtfilt``), at the
  recording's own rate, no decimation; q̇ and q̈ by ``numpy.gradient`` of the filtered q;
- the regressor of the standard rigid-body parameters (the toolkit's compiled regressor, equal to
  Pinocchio's ``computeJointTorqueRegressor`` to 1e-9: 10 columns per link in Pinocchio's order)
  plus, per joint, [q̇ⱼ, sign(q̇ⱼ), 1] (viscous, Coulomb, offset);
- ``numpy.linalg.lstsq(W, y, rcond=1e-10)`` on the fitted samples with 0.5 s trimmed at both ends
  of each segment (bridged samples left out);
- errors against the raw measured torques on the predicted samples, 0.5 s trimmed at both ends.

A robot whose description has a spring gets its known spring torque added to the measured torque
(as the toolkit does; none of the real arms has one). Rows are compressed chunk by chunk with a QR
factorisation ([W | y] -> R, same singular values, so lstsq on R with the same rcond solves the same
problem) so that a long log never holds the whole W; a segment is filtered in blocks with margins
(:meth:`BaselineSegment.windows`: the Butterworth's settling, two samples for the two gradients), one
block being the whole segment in memory, so a long log read block by block
(:mod:`identify.fitting.baseline_blocks`) gets the same baseline in bounded memory.

The fit is :mod:`identify.fitting.baseline_factors`' (:func:`~identify.fitting.baseline_factors.fit_baseline`).
Its per-joint factors of [W_j | y_j] (per time block when a blocked
cross-validation's blocks are given) hold everything the second yardstick needs too: the model the
user had (:mod:`identify.fitting.user_model`) is the same factors solved with the rigid-body columns
fixed at the description's values, and the held-out errors of both per time block
(:mod:`identify.fitting.yardsticks`) come from the same factors, without another pass over the data.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable, Iterator, Sequence

import numpy as np
from scipy.signal import butter, filtfilt

import rx90sym
from rx90sym.pinocchio_bridge import PINOCCHIO_ORDER, pinocchio_columns

from identify.estimation.results import json_number
from identify.signal.blocks import Window, lowpass_margin, motion_windows

__all__ = ["BASELINE_CUTOFF_HZ", "BASELINE_ORDER", "BASELINE_TRIM_S", "BASELINE_RCOND", "CHUNK", "LinearYardstick",
           "PlainBaseline", "BaselinePrediction", "BaselineSegment", "baseline_names", "baseline_regressor",
           "memory_windows", "segment_of", "window_signals", "yardstick_predictions"]

#: Cut-off [Hz] and order of the baseline's zero-phase Butterworth on q.
BASELINE_CUTOFF_HZ = 10.0
BASELINE_ORDER = 4
#: Seconds trimmed at both ends of every segment, fitted or predicted.
BASELINE_TRIM_S = 0.5
#: numpy.linalg.lstsq's rcond of the baseline.
BASELINE_RCOND = 1e-10
#: Samples of W evaluated at a time (each chunk compressed by a QR).
CHUNK = 4096


def baseline_names(robot: rx90sym.Robot) -> tuple[str, ...]:
    """The baseline's columns: the 10 rigid-body parameters of each link in Pinocchio's order
    (M, MX, MY, MZ, XX, XY, YY, XZ, YZ, ZZ), then per joint FVj, FSj, OFFj."""
    body = [f"{p}{j + 1}" for j in range(robot.n) for p in PINOCCHIO_ORDER]
    return tuple(body + [f"{p}{j + 1}" for j in range(robot.n) for p in ("FV", "FS", "OFF")])


def baseline_regressor(robot: rx90sym.Robot, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray) -> np.ndarray:
    """(S, n, 13 n) regressor of :func:`baseline_names` at the samples (S, n) [rad, rad/s, rad/s²]."""
    rigid = robot.regressor_batch(q, dq, ddq)[:, :, pinocchio_columns(robot)]
    S, n = np.shape(q)
    extra = np.zeros((S, n, 3 * n))
    for j in range(n):
        extra[:, j, 3 * j] = dq[:, j]
        extra[:, j, 3 * j + 1] = np.sign(dq[:, j])
        extra[:, j, 3 * j + 2] = 1.0
    return np.concatenate([rigid, extra], axis=2)


@dataclass(frozen=True, eq=False)
class BaselineSignals:
    """Samples of one segment through the baseline's filter: t (N,) [s]; q, dq, ddq (N, n) filtered and
    differentiated; tau (N, n) the raw measured torques [N m]; spring (N, n) the known spring torque
    at the filtered q (0 without); kept (N,) the samples fitted or scored (0.5 s from each end of the
    segment, measured)."""

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    tau: np.ndarray
    spring: np.ndarray
    kept: np.ndarray


@dataclass(frozen=True)
class BaselineSegment:
    """One segment as the baseline filters it: step [s] (its median time step), the times [s] of its
    first and last samples, its samples, and its source (for messages)."""

    step: float
    first: float
    last: float
    samples: int
    source: str = "<memory>"
    key: tuple[int, int] | None = None  # (recording index, its first raw sample): RawSpan.bounds' key

    def windows(self, block: int | None = None) -> list[Window]:
        """Blocks of at most ``block`` samples (None: the whole segment, one block), each with the margins
        the zero-phase Butterworth (:func:`identify.signal.blocks.lowpass_margin`) and the two
        ``numpy.gradient`` need: its core then equals the whole segment's to ~1e-12 relative."""
        margin = lowpass_margin(1.0 / self.step, BASELINE_CUTOFF_HZ, BASELINE_ORDER)
        return motion_windows(self.samples, 0, 1, self.samples if block is None else int(block), margin, 0)

    def check(self) -> None:
        if self.samples < 2:
            raise ValueError(f"{self.source}: {self.samples} sample(s): the plain baseline needs a motion")
        if BASELINE_CUTOFF_HZ >= 0.5 / self.step:
            raise ValueError(f"{self.source}: recorded at {1 / self.step:g} Hz: the plain baseline's "
                             f"{BASELINE_CUTOFF_HZ:g} Hz filter needs a rate above {2 * BASELINE_CUTOFF_HZ:g} Hz")


def segment_of(piece: Any) -> BaselineSegment:
    """The :class:`BaselineSegment` of a segment held in memory (a recording without long gaps)."""
    t = np.asarray(piece.t, dtype=float)
    step = float(np.median(np.diff(t))) if t.size > 1 else float("nan")
    return BaselineSegment(step, float(t[0]) if t.size else float("nan"), float(t[-1]) if t.size else float("nan"),
                           int(t.size), str(getattr(piece, "source", "<memory>")))


def window_signals(robot: rx90sym.Robot, segment: BaselineSegment, window: Window, rec: Any,
                   spring: bool = True) -> BaselineSignals:
    """The baseline's derivatives on the core of ``window`` of ``segment``, ``rec`` holding the window's raw
    samples (``window.raw``; the whole segment for the window of a whole segment)."""
    b, a = butter(BASELINE_ORDER, BASELINE_CUTOFF_HZ, fs=1.0 / segment.step)
    q = filtfilt(b, a, np.asarray(rec.q, dtype=float), axis=0)
    dq = np.gradient(q, segment.step, axis=0)
    ddq = np.gradient(dq, segment.step, axis=0)
    core = slice(window.core[0] - window.raw[0], window.core[1] - window.raw[0])
    t, q, dq, ddq = np.asarray(rec.t, dtype=float)[core], q[core], dq[core], ddq[core]
    tol = 1e-9 * segment.step
    kept = (t >= segment.first + BASELINE_TRIM_S - tol) & (t <= segment.last - BASELINE_TRIM_S + tol)
    kept &= np.asarray(rec.measured_mask, dtype=bool)[core]
    extra = robot.spring_torque_batch(q)[:, :, 0] if spring and robot.spring is not None else np.zeros_like(q)
    return BaselineSignals(t, q, dq, ddq, np.asarray(rec.torques, dtype=float)[core], extra, kept)


def memory_windows(recordings: Sequence[Any], block: int | None = None) -> Iterator[tuple]:
    """(segment, window, its raw samples) of every segment of recordings held in memory, blocks of at most
    ``block`` samples (None: each segment whole)."""
    for rec in recordings:
        for piece in rec.pieces():
            segment = segment_of(piece)
            segment.check()
            for w in segment.windows(block):
                yield segment, w, piece if w.raw == (0, segment.samples) else piece.select(slice(*w.raw))


@dataclass(frozen=True, eq=False)
class BaselinePrediction:
    """The baseline's torques of one recording at its own time stamps: t (N,) [s]; predicted (N, n)
    joint torques [N m] (spring not added; nan outside ``scored``); measured (N, n) the raw torques;
    scored (N,) the samples it predicts (0.5 s from each segment's ends, measured)."""

    t: np.ndarray
    predicted: np.ndarray
    measured: np.ndarray
    scored: np.ndarray


def yardstick_predictions(robot: rx90sym.Robot, models: Sequence[Any], windows: Iterable[tuple]
                          ) -> list[BaselinePrediction]:
    """The predictions of ``models`` (each with ``names`` = :func:`baseline_names`, ``values`` and ``spring``, the
    same for all: :class:`PlainBaseline`, :class:`identify.fitting.user_model.UserModel`) on the cores of
    ``windows`` ((segment, window, raw samples), in time order), in one pass: the regressor evaluated once."""
    names, springs = baseline_names(robot), {bool(m.spring) for m in models}
    if any(tuple(m.names) != names for m in models):
        raise ValueError(f"a yardstick was fitted with other columns than robot {robot.name!r}'s")
    if len(springs) > 1:
        raise ValueError("the yardsticks were fitted with and without the spring torque: predict them apart")
    spring = springs.pop() if springs else True
    parts: list[list] = [[] for _ in models]
    for segment, window, rec in windows:
        s = window_signals(robot, segment, window, rec, spring)
        preds = [np.full(s.tau.shape, np.nan) for _ in models]
        rows = np.flatnonzero(s.kept)
        for start in range(0, rows.size, CHUNK):
            idx = rows[start:start + CHUNK]
            Phi = baseline_regressor(robot, s.q[idx], s.dq[idx], s.ddq[idx])
            for pred, m in zip(preds, models):
                pred[idx] = Phi @ m.values - s.spring[idx]
        for part, pred in zip(parts, preds):
            part.append((s.t, pred, s.tau, s.kept))
    return [BaselinePrediction(*(np.concatenate(a) for a in zip(*part))) for part in parts]


@dataclass(frozen=True, eq=False)
class LinearYardstick:
    """What both yardsticks share: a value per :func:`baseline_names` column (``names``), predicted through
    :func:`baseline_regressor` on the baseline's filtered samples (spring subtracted when it was added); the
    fitted samples, the rank of the columns fitted, whether the spring torque was added, per joint
    residual RMS [N m] on the fitted samples."""

    names: tuple[str, ...]
    values: np.ndarray
    samples: int
    rank: int
    spring: bool
    residual_rms: np.ndarray

    def predict(self, robot: rx90sym.Robot, recording: Any, block: int | None = None) -> BaselinePrediction:
        """The prediction of ``recording`` (every segment on its own; filtered in blocks of at most
        ``block`` samples, None: each segment whole)."""
        return self.predict_windows(robot, memory_windows([recording], block))

    def predict_windows(self, robot: rx90sym.Robot, windows: Iterable[tuple]) -> BaselinePrediction:
        """The prediction on the cores of ``windows`` ((segment, window, raw samples), in time order:
        :func:`memory_windows`, or :func:`identify.fitting.baseline_blocks.source_windows` for a long log)."""
        return yardstick_predictions(robot, [self], windows)[0]

    def fitted_json(self) -> dict[str, Any]:
        """The shared fields as the fit file holds them (non-finite numbers null)."""
        return {"names": list(self.names), "values": [json_number(v) for v in self.values], "samples": self.samples,
                "rank": self.rank, "spring": self.spring, "residual_rms": [json_number(v) for v in self.residual_rms]}

    @staticmethod
    def fitted_fields(d: dict[str, Any]) -> tuple:
        """The shared fields from :meth:`fitted_json`'s record, in order."""
        values = np.array([np.nan if v is None else v for v in d["values"]], dtype=float)
        rms = np.array([np.nan if v is None else v for v in d.get("residual_rms", [])], dtype=float)
        return tuple(d["names"]), values, int(d["samples"]), int(d["rank"]), bool(d["spring"]), rms


@dataclass(frozen=True, eq=False)
class PlainBaseline(LinearYardstick):
    """The plain OLS baseline fitted (the fields of :class:`LinearYardstick`; rank: of W)."""

    def to_json(self) -> dict[str, Any]:
        return {"definition": "plain OLS: q by a 4th-order zero-phase Butterworth at 10 Hz, numpy.gradient, "
                              "rigid-body regressor + [dq_j, sign(dq_j), 1] per joint, lstsq(rcond=1e-10), "
                              "0.5 s trimmed at both ends",
                "cutoff_hz": BASELINE_CUTOFF_HZ, "order": BASELINE_ORDER, "trim_s": BASELINE_TRIM_S,
                "rcond": BASELINE_RCOND, **self.fitted_json()}

    @classmethod
    def from_json(cls, d: dict[str, Any] | None) -> "PlainBaseline | None":
        return cls(*cls.fitted_fields(d)) if d else None
