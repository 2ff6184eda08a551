"""What :func:`identify.read_log` reports in ``meta["log"]``, gathered block by block by the block
converter (:mod:`identify.io.log_blocks`)."""
from __future__ import annotations

from typing import Any

import numpy as np

from identify.io.recordings import TIME_RTOL
from identify.io.gaps import SPLITS_LISTED, Gap, LogGaps
from identify.io.steps import StepCounts, log_steps, step_figures

__all__ = ["BlockReport", "GAPS_KEPT"]

#: Gaps listed one by one in the report of a log converted in blocks (the counts cover them all).
GAPS_KEPT = 10_000


class BlockReport:
    """What :func:`identify.read_log` reports in ``meta["log"]``, gathered block by block."""

    def __init__(self) -> None:
        self.first_line = self.last_line = None
        self.rows = self.samples = self.stale = self.bridged = 0
        self.retimed_lost = 0  # cycles a counted clock lost, found from the positions (identify.io.gaps.sample_periods)
        self.stale_lines: list[int] = []
        self.steps = StepCounts()  # every step of the log: the figures of the whole-log reader
        self.gap, self.gap_lines = -1.0, [0, 0]
        self.gaps: list[Gap] = []  # the first GAPS_KEPT, the rest counted: memory bounded
        self.gap_count, self.bridged_gaps, self.lost_periods = 0, 0, 0.0
        self.splits: list[Gap] = []  # the first SPLITS_LISTED gaps that split the log, the rest counted
        self.split_count = 0
        self.segments = 1
        self.dropped: list[tuple[int, int, int]] = []  # segments too short to filter: lines, rows
        self.t0_s = 0.0  # the log's clock at its first sample [s] (the recording starts at 0 s)
        self.q_min: np.ndarray | None = None  # the smallest and largest position of each joint [rad]
        self.q_max: np.ndarray | None = None

    def span(self, q: np.ndarray) -> None:
        """A block's positions (model angles) into the range of each joint."""
        if q.shape[0]:
            lo, hi = q.min(axis=0), q.max(axis=0)
            self.q_min = lo if self.q_min is None else np.minimum(self.q_min, lo)
            self.q_max = hi if self.q_max is None else np.maximum(self.q_max, hi)

    def position_span(self) -> np.ndarray:
        """(n,) largest minus smallest position of each joint over the rows checked [rad]."""
        return np.zeros(0) if self.q_min is None else self.q_max - self.q_min

    def add(self, t: np.ndarray, numbers: list[int], found: LogGaps) -> None:
        """A block's kept rows (after the previous block's last kept row, when there is one) and its gaps."""
        dt = np.diff(t)
        if self.first_line is None:
            self.first_line = numbers[0]
        self.last_line = numbers[-1]
        self.gaps += found.gaps[:max(0, GAPS_KEPT - len(self.gaps))]
        self.gap_count += len(found.gaps)
        self.bridged_gaps += len(found.bridged)
        self.lost_periods += float(sum(g.periods - 1.0 for g in found.bridged))
        self.splits += found.splits[:max(0, SPLITS_LISTED - len(self.splits))]
        self.split_count += len(found.splits)
        self.segments += int(found.segment[-1])
        if dt.size:
            self.steps.add(log_steps(dt))
            k = int(np.argmax(dt))
            if dt[k] > self.gap:
                self.gap, self.gap_lines = float(dt[k]), [numbers[k], numbers[k + 1]]

    def result(self, max_gap: float) -> dict[str, Any]:
        gaps = {**LogGaps(tuple(self.gaps), np.array([self.segments - 1 - len(self.dropped)]), max_gap,
                          tuple(self.dropped)).summary(),
                "bridged_gaps": self.bridged_gaps, "bridged_lost_periods": self.lost_periods,
                "gaps_total": self.gap_count, "splits": [g.to_dict() for g in self.splits],
                "splits_total": self.split_count}
        return {"lines": [self.first_line, self.last_line], "rows": self.rows, "stale_rows": self.stale,
                "stale_lines": self.stale_lines, **step_figures(self.steps, TIME_RTOL), "largest_gap_s": self.gap,
                "largest_gap_lines": self.gap_lines, "gaps": gaps, "bridged_samples": self.bridged,
                "samples": self.samples, "t0_s": self.t0_s, "lost_cycles": self.retimed_lost}
