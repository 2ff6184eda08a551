"""A recording: joint positions and joint-side torques sampled in time (Khalil angles, SI).

Lives in rx90sym so that the simulated robot (rx90sym.twin) produces the same object that
identify reads from files.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

_MEMORY = "<memory>"


class RecordingError(ValueError):
    """A recording (file or arrays) is malformed; the message names file, column and row."""


# --------------------------------------------------------------------------------------------
# The recording
# --------------------------------------------------------------------------------------------


def frozen_array(x: Any) -> np.ndarray:
    """Read-only float64 copy of ``x`` (a Recording must not change under its owner's feet)."""
    a = np.array(x, dtype=float, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Recording:
    """One recorded motion in model conventions.

    Attributes:
        t: (N,) time, s.
        q: (N, n) joint positions, rad, Khalil angles.
        tau: (N, n) joint torques, N·m, joint side (spring not added), or None for a recording
            of motor currents that has not been through drive gains yet.
        dq: (N, n) joint velocities, rad/s, or None when not recorded.
        source: file name the data came from, or ``"<memory>"``.
        robot: name of the robot the data belong to.
        meta: provenance (e.g. the simulated robot's true parameters and noise profile).
        current: (N, n) motor currents, A, one column per motor, or None. Joint torques follow
            from drive gains (``tau = Rt·diag(k)·current``); until then ``tau`` is None.
        aux: auxiliary columns kept from a log (``x:NAME`` in a column map, e.g. a target
            current), name -> (N,) array; never used as torque.
        measured: (N,) bool, False for a sample bridged over a lost packet (interpolated, kept
            so that the filters run through, never a measurement), or None: all measured.
        segment: (N,) int, the segment of each sample (0, 1, ...; non-decreasing): a log split at
            gaps too long to bridge; each segment is filtered and differentiated on its own
            (:meth:`pieces`). None: one segment.

    Only shapes are checked here; the data checks (finite values, regular time, radians, ...)
    are done by the readers and :func:`recording_from_arrays`.
    """

    t: np.ndarray
    q: np.ndarray
    tau: np.ndarray | None
    dq: np.ndarray | None = None
    source: str = _MEMORY
    robot: str = ""
    meta: dict = field(default_factory=dict, repr=False)
    current: np.ndarray | None = None
    aux: dict = field(default_factory=dict, repr=False)
    measured: np.ndarray | None = None
    segment: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = frozen_array(self.t)
        q = frozen_array(self.q)
        if t.ndim != 1 or t.size < 1:
            raise RecordingError(f"{self.source}: t must be a non-empty 1-D array, got shape {t.shape}")
        n_samples = t.size
        if q.ndim != 2 or q.shape[0] != n_samples or q.shape[1] < 1:
            raise RecordingError(f"{self.source}: q must have shape ({n_samples}, n), got {q.shape}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "q", q)
        if self.tau is None and self.current is None:
            raise RecordingError(f"{self.source}: a recording needs joint torques (tau) or motor currents")
        for name in ("tau", "dq", "current"):
            value = getattr(self, name)
            if value is None:
                continue
            a = frozen_array(value)
            if a.shape != q.shape:
                raise RecordingError(f"{self.source}: {name} must have shape {q.shape}, got {a.shape}")
            object.__setattr__(self, name, a)
        aux = {}
        for key, value in dict(self.aux).items():
            a = frozen_array(value)
            if a.shape != t.shape:
                raise RecordingError(f"{self.source}: auxiliary column {key} must have shape {t.shape}, got {a.shape}")
            aux[str(key)] = a
        object.__setattr__(self, "aux", aux)
        self._set_layout(n_samples)

    def _set_layout(self, n_samples: int) -> None:
        """Check and freeze ``measured`` and ``segment`` (None when trivial)."""
        if self.measured is not None:
            m = np.array(self.measured, dtype=bool, copy=True)
            if m.shape != (n_samples,):
                raise RecordingError(f"{self.source}: measured must have shape ({n_samples},), got {m.shape}")
            m.setflags(write=False)
            object.__setattr__(self, "measured", None if m.all() else m)
        if self.segment is not None:
            s = np.array(self.segment, copy=True)
            if s.shape != (n_samples,) or not np.all(np.isfinite(s)) or not np.all(s == np.round(s)):
                raise RecordingError(f"{self.source}: segment must be ({n_samples},) integers, got {s.shape}")
            s = s.astype(np.int64)
            if s.size and (s[0] != 0 or np.any(np.diff(s) < 0) or np.any(np.diff(s) > 1)):
                raise RecordingError(f"{self.source}: segment numbers must start at 0 and grow by steps of 1")
            s.setflags(write=False)
            object.__setattr__(self, "segment", None if not s.size or s[-1] == 0 else s)

    @property
    def n_segments(self) -> int:
        """Number of segments (1 for a recording without gaps too long to bridge)."""
        return 1 if self.segment is None else int(self.segment[-1]) + 1

    @property
    def measured_mask(self) -> np.ndarray:
        """(N,) bool: True for a measured sample, False for one bridged over a lost packet."""
        return np.ones(self.t.size, dtype=bool) if self.measured is None else self.measured

    def pieces(self) -> list["Recording"]:
        """One recording per segment (each keeps its ``measured`` mask), in time order."""
        if self.segment is None:
            return [self]
        edges = np.flatnonzero(np.diff(self.segment)) + 1
        bounds = zip(np.r_[0, edges], np.r_[edges, self.t.size])
        return [self.select(slice(int(a), int(b)), f"{self.source}#{k + 1}") for k, (a, b) in enumerate(bounds)]

    @property
    def torques(self) -> np.ndarray:
        """Joint torques (N, n), N·m; a current recording without drive gains is refused.

        Raises:
            RecordingError: the recording holds motor currents only, naming how to give gains.
        """
        if self.tau is None:
            raise RecordingError(
                f"{self.source}: the recording holds motor currents, not joint torques; give drive gains "
                "(--gains K1,...,Kn in N·m/A on the joint side, or --gains GAINS.json from 'rx90 gains')")
        return self.tau

    def select(self, rows: Any, source: str | None = None) -> "Recording":
        """The samples ``rows`` (a slice, indices or a boolean mask) of every per-sample array."""
        def cut(a: np.ndarray | None) -> np.ndarray | None:
            return None if a is None else a[rows]

        segment = None
        if self.segment is not None:  # renumbered from 0, one step per break kept
            kept = self.segment[rows]
            segment = np.r_[0, np.cumsum(np.diff(kept) != 0)] if kept.size else kept
        return Recording(t=self.t[rows], q=self.q[rows], tau=cut(self.tau), dq=cut(self.dq),
                         source=self.source if source is None else source, robot=self.robot,
                         meta=dict(self.meta), current=cut(self.current),
                         aux={k: v[rows] for k, v in self.aux.items()}, measured=cut(self.measured),
                         segment=segment)

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.t.size)

    @property
    def n_joints(self) -> int:
        """Number of joints n."""
        return int(self.q.shape[1])

    @property
    def rate(self) -> float:
        """Sampling rate, Hz: 1 / mean time step inside the segments (nan for a single sample)."""
        if self.t.size < 2:
            return math.nan
        dt = np.diff(self.t)
        if self.segment is not None:
            dt = dt[np.diff(self.segment) == 0]
        return float(dt.size / dt.sum()) if dt.size else math.nan

    @property
    def duration(self) -> float:
        """Time spanned by the samples, s."""
        return float(self.t[-1] - self.t[0])

    def __repr__(self) -> str:
        return (
            f"Recording(robot={self.robot!r}, source={self.source!r}, samples={self.n_samples}, "
            f"joints={self.n_joints}, rate={self.rate:.6g} Hz, dq={'yes' if self.dq is not None else 'no'}, "
            f"{'torques' if self.tau is not None else 'currents'}"
            + (f", {self.n_segments} segments" if self.segment is not None else "")
            + (f", {int(np.sum(~self.measured))} bridged" if self.measured is not None else "") + ")"
        )
