"""The recording as a rollout reads it, block by block whatever its length: per segment, consecutive raw
samples with their start velocity, the speed that decides rest, and the recorded joint torques (drive
gains applied, advanced by the fit's delay), cut into windows of a given length that do not overlap.

The blocks are those of the fit's own pipeline (identify.observation.block_rows: margins from the filter's
impulse response, segments filtered one by one, no decimation), so the filtered velocity of a long log
equals the whole-signal one; a window may span blocks (:class:`WindowCutter` carries the samples over).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterator

import numpy as np

import rx90sym

from identify.io.blocks import DEFAULT_BLOCK, block_source
from identify.observation.matrix import shifted_torques
from identify.observation.processing import Processing
from identify.observation.block_rows import plan_windows, windows_in_order
from identify.observation.scan import scan
from identify.signal.filtering import derivatives

__all__ = ["RolloutSource", "Samples", "WindowCutter"]


@dataclass(frozen=True, eq=False)
class Samples:
    """Consecutive raw samples of one segment: ``segment`` its number, ``rate`` [Hz]; t (S,) [s]; q (S, n)
    recorded positions [rad, model angles]; dq (S, n) start velocities [rad/s]; speed (S, n) the speeds
    that decide rest [rad/s] (recorded q̇ when the log has it, else ``dq``: the fit's rest rule); tau
    (S, n) joint torques [N m] (gains applied, τ(t + delay)); measured (S,) False where bridged; index:
    a window's number among the recording's windows of its length (:class:`WindowCutter`; -1: a block)."""

    segment: int
    rate: float
    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    speed: np.ndarray
    tau: np.ndarray
    measured: np.ndarray
    index: int = -1


class RolloutSource:
    """A recording (or recording file) read for a rollout: scanned once on construction (its segments,
    their rates), then :meth:`pieces` reads it again block by block. cutoff [Hz]: the fit's; delay [s]:
    torques advanced by it (identify.observation.matrix.shifted_torques); velocity: "filtered" or
    "recorded" (identify.rollout.defaults.START_VELOCITIES); gains, convention: how a file is read."""

    def __init__(self, robot: rx90sym.Robot, recording: Any, cutoff: float, delay: float = 0.0,
                 velocity: str = "filtered", gains: Any = None, convention: str | None = None,
                 block: int = DEFAULT_BLOCK) -> None:
        if velocity not in ("filtered", "recorded"):
            raise ValueError(f"start velocity must be 'filtered' or 'recorded', got {velocity!r}")
        self.robot, self.cutoff, self.delay, self.velocity = robot, float(cutoff), float(delay), velocity
        self.src = block_source(recording, robot, convention, gains)
        processing = Processing(cutoff=self.cutoff, decimate_to=None, min_velocity=None, rest="none", delay=self.delay,
                                spring=False)
        self.scan = scan(self.src, int(block), None)
        self.plans, self.notes = plan_windows(self.scan, processing, int(block))

    @property
    def source(self) -> str:
        return self.src.source

    def spans_s(self) -> list[float]:
        """Per segment used, the time [s] its filtered samples span (the filter's edges trimmed)."""
        return [(p.length - 2 * p.edge - 1) / p.rate for p in self.plans]

    def pieces(self) -> Iterator[Samples]:
        """The segments' filtered samples, block by block in order (each block's core)."""
        numbers = {id(p): k for k, p in enumerate(self.plans)}
        for plan, window, rec, _ in windows_in_order([self.src], [self.plans]):
            r0 = window.raw[0]
            d0, d1 = window.span
            kept = slice(d0 - r0, d1 - r0)
            d = derivatives(rec.t, rec.q, cutoff=self.cutoff, kept=kept)
            recorded = None if rec.dq is None else np.asarray(rec.dq, dtype=float)[kept]
            if self.velocity == "recorded" and recorded is None:
                raise ValueError(f"{self.source}: no recorded velocities (columns dq1..dq{self.robot.n}) to start the "
                                 f"rollout from; start from the filtered derivative")
            dq = recorded if self.velocity == "recorded" else d.dq
            yield Samples(numbers[id(plan)], plan.rate, np.asarray(rec.t, dtype=float)[kept],
                          np.asarray(rec.q, dtype=float)[kept], dq, d.dq if recorded is None else recorded,
                          shifted_torques(rec, self.delay)[kept], rec.measured_mask[kept])


class WindowCutter:
    """Windows of ``length`` [s] (round(length x rate) samples) from consecutive :class:`Samples`: from
    each segment's first filtered sample, one after the other (a window ends on the next one's first
    sample; none overlaps another), never across two segments; a segment's tail shorter than a window
    is left out."""

    _FIELDS = ("t", "q", "dq", "speed", "tau", "measured")

    def __init__(self, length: float) -> None:
        self.length = float(length)
        self.count = 0
        self._segment: int | None = None
        self._held: dict[str, np.ndarray] = {}

    def samples(self, rate: float) -> int:
        """Samples per window at ``rate`` [Hz] (at least one)."""
        return max(1, int(round(self.length * rate)))

    def feed(self, piece: Samples) -> list[Samples]:
        """The windows that ``piece`` completes (each ``samples`` + 1 samples, numbered by ``index``)."""
        if piece.segment != self._segment:
            self._segment, self._held = piece.segment, {}
        held = {k: np.concatenate([self._held[k], getattr(piece, k)]) if self._held else getattr(piece, k)
                for k in self._FIELDS}
        size = self.samples(piece.rate)
        out, start = [], 0
        while start + size < held["t"].size:
            cut = slice(start, start + size + 1)
            out.append(Samples(piece.segment, piece.rate, *(held[k][cut] for k in self._FIELDS), index=self.count))
            self.count += 1
            start += size
        self._held = {k: v[start:] for k, v in held.items()}
        return out
