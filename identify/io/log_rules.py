"""The rules of a controller log applied to its rows block by block: one implementation for every
input form and every length (:func:`identify.read_log`, :func:`identify.io.log_blocks.convert_log`,
:func:`identify.read_bag`, :func:`identify.io.joint_files.read_joint_files`).

Stale rows are dropped (each block's first row compared with the previous block's last), the rows
checked with the log checks of :mod:`identify.io.logs` (each block after the previous block's last
kept row, so steps, jumps and gaps across blocks are checked too), gaps bridged or split into
segments (:mod:`identify.io.gaps`; a segment shorter than ``MIN_SEGMENT_ROWS`` rows dropped unless it
is the log's only one), each segment put on its own grid when resampling (:class:`_Resampler`), and
currents turned into torques by the drive gains. :func:`log_parts` yields the parts in order, each with
its segment number; :func:`collected` joins them into one recording, a converter writes them. Torque
signs (identify.io.torque_signs) are applied to each part before the drive gains. A time column of the
log's own that counts samples (identify.io.units.sample_clock_refusal) is refused on the first block.

The median time step of the checks (irregular steps, gaps, a gap's ``periods``) is each block's: a
log of one block (every log read whole) is checked on its own median; a longer one by blocks, the
same steps unless the clock drifts by a third of a period between blocks. The report's step figures
are the whole log's (:func:`identify.io.steps.step_figures` on every step).
"""
from __future__ import annotations

import warnings
from typing import Any, Iterator

import numpy as np

import rx90sym
from rx90sym.recording import Recording, RecordingError

from identify.io.columns import ColumnMap
from identify.io.gains import DriveGains, apply_gains
from identify.io.gaps import (DEFAULT_MAX_GAP, MIN_SEGMENT_ROWS, LogGaps, all_segments_short, find_gaps, sample_periods,
                              stale_rows)
from identify.io.log_block_report import BlockReport
from identify.io.logs import (LISTED_ROWS, STILL, check_increasing, check_positions, check_velocities, gains_label,
                              irregular_refusal, log_drive, refuse_splits)
from identify.io.recordings import RecordingWarning
from identify.io.resampling import check_rate, concatenate, interpolate
from identify.io.torque_signs import with_torque_signs
from identify.io.units import check_units, sample_clock_refusal
from identify.io.unlogged import ColumnRange, constant_channels, constant_message

__all__ = ["retimed_rate", "SPLINE_MARGIN", "collected", "log_parts", "log_report", "rows_to_recording"]

#: Samples beyond a resampled block's end: the not-a-knot spline's dependence on far samples decays
#: by ≈ 0.27 per sample, so 40 samples change an interpolated value by < 1e-20 of the signal.
SPLINE_MARGIN = 40


class _Resampler:
    """The rule of :func:`identify.resample` (grid ``t0 + k/rate``, splines) on a stream of blocks of one
    segment (a new segment takes a new resampler: its grid starts at its first sample).

    Rows are buffered until SPLINE_MARGIN samples lie beyond the grid points emitted, so each
    emitted point sees the samples around it as the whole-log spline does.
    """

    def __init__(self, rate: float) -> None:
        self.rate, self.k, self.t0 = float(rate), 0, None
        self.buffer: Recording | None = None

    def feed(self, rec: Recording | None, last: bool) -> Recording | None:
        """The grid points ``rec`` completes (``last``: the segment ends with it; ``rec`` None: flush)."""
        buf = rec if self.buffer is None else (self.buffer if rec is None else _joined(self.buffer, rec))
        if buf is None or (buf.t.size < 2 and not last):  # a segment's first row alone: wait for the next
            self.buffer = buf
            return None
        if self.t0 is None:
            self.t0 = float(buf.t[0])
        limit = float(buf.t[-1]) if last else float(buf.t[max(0, buf.t.size - 1 - SPLINE_MARGIN)])
        count = int(np.floor((limit - self.t0) * self.rate * (1.0 + 1e-12))) + 1
        grid = self.t0 + np.arange(self.k, count) / self.rate
        if last and grid.size:
            grid[-1] = min(grid[-1], limit)  # never beyond the last sample through rounding
        self.k = max(self.k, count)
        self.buffer = None
        if not last:  # keep what the next points need: SPLINE_MARGIN samples before them
            start = max(0, int(np.searchsorted(buf.t, limit)) - 2 * SPLINE_MARGIN)
            self.buffer = buf.select(slice(start, None))
        return interpolate(buf, grid) if grid.size else None


def _joined(a: Recording, b: Recording) -> Recording:
    def cat(x: np.ndarray | None, y: np.ndarray | None) -> np.ndarray | None:
        return None if x is None else np.concatenate([x, y])

    return Recording(t=np.concatenate([a.t, b.t]), q=np.concatenate([a.q, b.q]), tau=cat(a.tau, b.tau),
                     dq=cat(a.dq, b.dq), source=a.source, robot=a.robot, current=cat(a.current, b.current),
                     aux={k: np.concatenate([v, b.aux[k]]) for k, v in a.aux.items()})



class _LogRules:
    """The rules of :func:`identify.io.logs.rows_to_recording` on consecutive blocks of rows: stale rows
    (each block's first row compared with the previous block's last), checks, gaps and segments (each
    block after the previous block's last kept row), the grid of each segment. Yields the parts to
    write, each with its segment number."""

    def __init__(self, cmap: ColumnMap, robot: rx90sym.Robot, conv: str, source: str, resample: float | None,
                 max_gap: float, segments: bool, report: BlockReport, window: bool = True,
                 stale: bool = True, period: float | None = None) -> None:
        self.cmap, self.robot, self.conv, self.source = cmap, robot, conv, source
        self.resample, self.max_gap, self.segments, self.report = resample, max_gap, segments, report
        self.window, self.stale = window, stale
        # A clock that counts samples (its period given) is re-timed from the positions and recorded velocities.
        self.period = period if period is not None and cmap.qd else None
        self.shift = 0  # the periods the re-timed clock is ahead of the counted one
        self.used = [c for c, name in enumerate(cmap.names) if name != "_"]
        self.last_raw: np.ndarray | None = None
        self.last_kept: tuple[np.ndarray, list[int]] | None = None
        self.segment, self.out = 0, -1  # the segment found, and its number in the output
        self.keeping, self.resampler = False, None  # the segment is long enough to keep; its grid
        self.held: list[Recording] = []  # its first rows, until it is
        self.held_rows, self.held_lines = 0, None
        self.t0: float | None = None  # the log's clock at its first sample [s]
        self.clock_checked = False  # a time column counting samples is looked for once (first rows)

    def block(self, values: np.ndarray, numbers: list[int], last: bool) -> Iterator[tuple[Recording, int]]:
        report = self.report
        report.rows += values.shape[0]
        both = values if self.last_raw is None else np.vstack([self.last_raw, values])
        stale = (stale_rows(both, self.cmap.t, self.used)[both.shape[0] - values.shape[0]:] if self.stale
                 else np.zeros(values.shape[0], dtype=bool))
        self.last_raw = values[-1:]
        if self.period is not None:
            values, stale = self._retimed(both, values, stale)
        report.stale += int(stale.sum())
        report.stale_lines += [numbers[k] for k in np.flatnonzero(stale)[:max(0, LISTED_ROWS - len(report.stale_lines))]]
        values, numbers = values[~stale], [n for n, s in zip(numbers, stale) if not s]
        new = values.shape[0]
        if new:  # 0 s at the first sample, as identify.io.logs.rows_to_recording
            if self.t0 is None:
                self.t0 = report.t0_s = float(values[0, self.cmap.t])
            values = values.copy()
            values[:, self.cmap.t] -= self.t0
            if self.last_kept is not None:
                values, numbers = np.vstack([self.last_kept[0], values]), self.last_kept[1] + numbers
            yield from self._kept(values, numbers, new)
        if last:
            yield from self._end(final=True)

    def _retimed(self, both: np.ndarray, values: np.ndarray, stale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The block's rows on the clock of the motion (identify.io.gaps.sample_periods): a row logged again
        within one cycle is stale (dropped), the rows after cycles the logger lost are that many periods
        later (a gap, bridged)."""
        q, qd = both[:, list(self.cmap.q)], both[:, list(self.cmap.qd)]
        k = sample_periods(q, qd, self.period)
        k = k if both.shape[0] > values.shape[0] else np.r_[1, k]
        shifts = self.shift + np.cumsum(k - 1)
        self.shift = int(shifts[-1]) if shifts.size else self.shift
        self.report.retimed_lost += int(np.sum(np.maximum(k - 1, 0)))
        values = values.copy()
        values[:, self.cmap.t] += shifts * self.period
        return values, stale | (k == 0)

    def _kept(self, values: np.ndarray, numbers: list[int], new: int) -> Iterator[tuple[Recording, int]]:
        t = values[:, self.cmap.t]
        if t.size >= 2:
            check_increasing(t, numbers, self.source, self.window)
        found = (find_gaps(t, numbers, self.max_gap) if t.size >= 2
                 else LogGaps((), np.zeros(t.size, np.int64), self.max_gap))
        if not self.segments:
            refuse_splits(found, self.source, self.window)
        if self.stale and not self.clock_checked and t.size >= 3:  # the log's own clock (not a period's)
            self.clock_checked = True
            refusal = sample_clock_refusal(t, values[:, list(self.cmap.q)],
                                           values[:, list(self.cmap.qd)] if self.cmap.qd else None, self.robot,
                                           f"the time column (column {self.cmap.t + 1}, t)")
            if refusal:
                raise RecordingError(f"{self.source}: {refusal}")
        rec = _checked(values, numbers, self.cmap, self.robot, self.conv, self.source, self.window)
        self.report.span(rec.q)
        if self.resample is None and t.size >= 2:
            refusal = irregular_refusal(t, numbers, self.source, found)
            if refusal:
                raise RecordingError(refusal)
        self.report.add(t, numbers, found)
        self.last_kept = (values[-1:], numbers[-1:])
        segment = found.segment[t.size - new:] + self.segment  # the carried row is in self.segment
        rec = rec.select(slice(t.size - new, None))
        lines = np.asarray(numbers[t.size - new:])
        for number in np.unique(segment):
            if number != self.segment:
                yield from self._end(final=False)
                self.segment = int(number)
            yield from self._add(rec.select(segment == number), lines[segment == number])

    def _add(self, part: Recording, lines: np.ndarray) -> Iterator[tuple[Recording, int]]:
        """A part of the current segment: held until the segment has MIN_SEGMENT_ROWS rows (a shorter
        one is dropped, as by the whole-log reader), then resampled and written."""
        self.held.append(part)
        self.held_rows += part.n_samples
        self.held_lines = (self.held_lines[0] if self.held_lines else int(lines[0]), int(lines[-1]))
        if not self.keeping and self.held_rows >= MIN_SEGMENT_ROWS:
            self._keep()
        if self.keeping:
            yield from self._emit()

    def _keep(self) -> None:
        self.keeping = True
        self.out += 1  # the segment's number in the output: a dropped one leaves no hole
        self.resampler = _Resampler(self.resample) if self.resample else None

    def _emit(self) -> Iterator[tuple[Recording, int]]:
        parts, self.held = self.held, []
        for part in parts:
            part = self.resampler.feed(part, False) if self.resampler is not None else part
            if part is not None:
                yield part, self.out

    def _end(self, final: bool) -> Iterator[tuple[Recording, int]]:
        """The current segment ends: its last grid points, or it is dropped when too short (kept when it
        is the log's only segment; every segment too short is an error)."""
        if not self.keeping and self.held:
            if final and self.out < 0 and not self.report.dropped:  # the only segment: kept whatever its length
                self._keep()
                yield from self._emit()
            else:
                self.report.dropped.append((*self.held_lines, self.held_rows))
                if final and self.out < 0:
                    raise all_segments_short(self.source, self.max_gap, self.report.dropped[0][:2])
        if self.keeping and self.resampler is not None:
            part = self.resampler.feed(None, True)
            if part is not None:
                yield part, self.out
        self.keeping, self.resampler, self.held, self.held_rows, self.held_lines = False, None, [], 0, None


def _checked(values: np.ndarray, numbers: list[int], cmap: ColumnMap, robot: rx90sym.Robot, conv: str,
             source: str, window: bool = True) -> Recording:
    """One block through the log checks (units, positions, recorded velocities), as a recording in
    model angles."""
    t = values[:, cmap.t]
    q_file = values[:, list(cmap.q)]
    q = np.asarray(robot.to_model(q_file), dtype=float) if conv == "controller" else q_file
    dq = values[:, list(cmap.qd)] if cmap.qd else None
    # Degrees and swapped q/qd groups named as such, before they read as corrupt rows.
    check_units(t, q_file, dq, robot, source, numbers, to_model=conv == "controller", ranges=False)
    check_positions(q, t, numbers, cmap, robot, source, window)
    if t.size >= 3:
        check_velocities(dq, q, t, np.ptp(q, axis=0), numbers, cmap, source)

    def take(cols: tuple[int, ...]) -> np.ndarray | None:
        return values[:, list(cols)] if cols else None

    return Recording(t=t, q=q, tau=take(cmap.tau), dq=dq, source=source, robot=robot.name, current=take(cmap.i),
                     aux={name: values[:, col] for name, col in cmap.aux})


def retimed_rate(resample: float | None, period: float | None, cmap: ColumnMap) -> float | None:
    """The rate a log is resampled at: ``resample`` [Hz], or with a clock that counts samples of ``period``
    [s] and recorded velocities (re-timed: :func:`log_parts`), the period's own grid (its lost cycles
    bridged)."""
    return resample if resample is not None or period is None or not cmap.qd else 1.0 / period


def log_parts(blocks: Iterator[tuple[np.ndarray, list[int]]], cmap: ColumnMap, robot: rx90sym.Robot, conv: str,
              source: str, report: BlockReport, resample: float | None = None, max_gap: float = DEFAULT_MAX_GAP,
              segments: bool = True, drive: DriveGains | None = None, window: bool = True,
              stale: bool = True, signs: tuple[float, ...] | None = None,
              period: float | None = None) -> Iterator[tuple[Recording, int]]:
    """(part, segment number) of the log whose parsed rows ``blocks`` yields ((rows, columns) as ``cmap``
    names them, their line numbers), in order, by the module's rules; ``report`` gathers what
    :func:`log_report` returns. ``window``: the input form can select a window of lines (its refusals
    advise one; False for a bag); ``stale``: drop rows equal to the previous one (False when the clock
    is a sampling period: every row is a sample; True: the clock is the log's, checked for a sample
    counter); ``signs``: torque signs per joint (identify.io.torque_signs), applied before ``drive``;
    ``period`` [s]: the clock counts samples of this period (the time column made from it): with recorded
    velocities, the rows are re-timed from the positions (cycles logged twice dropped, cycles lost bridged:
    identify.io.gaps.sample_periods)."""
    if not (np.isfinite(max_gap) and max_gap > 0):
        raise ValueError(f"max_gap must be a positive time in s, got {max_gap!r}")
    if resample is not None:
        check_rate(resample)
    stream = _LogRules(cmap, robot, conv, source, resample, max_gap, segments, report, window, stale, period)
    logged = ColumnRange()  # the torque (or current) columns' values: one value on every row is a channel not logged
    pending = next(blocks, None)
    if pending is None:
        raise RecordingError(f"{source}: no data rows")
    while pending is not None:
        values, numbers = pending
        pending = next(blocks, None)
        for rec, segment in stream.block(values, numbers, pending is None):
            logged.add(rec.tau if rec.tau is not None else rec.current)
            rec = with_torque_signs(rec, signs)
            if drive is not None:
                rec = apply_gains(rec, drive, robot)
            report.samples += rec.n_samples
            report.bridged += int(np.sum(~rec.measured_mask))
            yield rec, segment
    if report.rows - report.stale < 2:
        raise RecordingError(f"{source}: line {report.first_line}: a log needs at least 2 rows")
    _warn_constant(source, logged.value(), cmap)
    span = report.position_span()
    if np.all(span < STILL):
        warnings.warn(f"{source}: no joint moves in lines {report.first_line}..{report.last_line} (largest position "
                      f"span {span.max():g} rad): a recording at rest identifies gravity and offsets at most",
                      RecordingWarning, stacklevel=3)


def _warn_constant(source: str, span: np.ndarray | None, cmap: ColumnMap) -> None:
    """A warning naming the torque (or current) columns that hold one value on every row (identify.io.unlogged)."""
    if span is None:
        return
    joints = constant_channels(span[0], span[1])
    if joints:
        what, cols = ("torque", cmap.tau) if cmap.tau else ("current", cmap.i)
        warnings.warn(constant_message(source, joints, [float(span[0, j]) for j in joints], what,
                                       [f"{cmap.names[cols[j]]} in column {cols[j] + 1}" for j in joints]),
                      RecordingWarning, stacklevel=4)


def log_report(report: BlockReport, max_gap: float, resample: float | None, drive: DriveGains | None,
               conv: str, signs: tuple[float, ...] | None = None) -> dict[str, Any]:
    """``meta["log"]`` of a log read by :func:`log_parts` (the keys :func:`identify.read_log` documents)."""
    return {**report.result(max_gap), "resampled_hz": float(resample) if resample else None,
            "gains": None if drive is None else gains_label(drive), "convention": conv,
            "position_span_rad": report.position_span().tolist(),
            "torque_signs": None if signs is None else [float(x) for x in signs]}


def collected(parts: Iterator[tuple[Recording, int]], resampled: bool) -> Recording:
    """The parts of :func:`log_parts` as one recording (``segment`` always, ``measured`` when ``resampled``)."""
    done = list(parts)
    return concatenate([r for r, _ in done], done[0][0].source, [s for _, s in done], measured=resampled)


def rows_to_recording(source: str, values: np.ndarray, numbers: Any, cmap: ColumnMap, robot: rx90sym.Robot,
                      convention: str, gains: DriveGains | str | None = None, max_gap: float = DEFAULT_MAX_GAP,
                      segments: bool = True, resample: float | None = None, window: bool = True,
                      stale: bool = True, signs: tuple[float, ...] | None = None) -> Recording:
    """The rows of a log held in memory (``values`` (N, columns) as ``cmap`` names them, ``numbers``
    their line or message numbers) as a recording, by the module's rules (one block)."""
    drive = log_drive(cmap, gains, robot)
    report = BlockReport()
    rec = collected(log_parts(iter([(np.asarray(values, dtype=float), list(numbers))]), cmap, robot, convention,
                              source, report, resample, max_gap, segments, drive, window, stale, signs),
                    resample is not None)
    return _with_report(rec, log_report(report, max_gap, resample, drive, convention, signs))


def _with_report(rec: Recording, log: dict[str, Any]) -> Recording:
    from dataclasses import replace

    return replace(rec, meta={**rec.meta, "log": log})
