"""Observation matrix of the identification model (eqs. 6-8) from one or many recordings.

Per recording: q filtered and differentiated (eq. 20), the regressor evaluated on every kept
sample, Y = measured torque + spring torque (axis 2, section II-C), then Y and every column of W
decimated by the same zero-phase filter (parallel filtering), and rows grouped per joint (eq. 7).

Rest phases: a joint whose speed is below ``min_velocity`` (rad/s) is at rest; the sign of its
Coulomb term is then the sign of noise. ``rest="drop"`` leaves those rows out of the fit,
``rest="zero-coulomb"`` keeps them with the Coulomb entries set to 0 (see :func:`identify.observation.rest.coulomb_terms`),
``rest="presliding"`` with the presliding state of the position history
(:mod:`identify.observation.rest`), ``rest="none"`` as they are (the sign of the filtered
speed); a tuple gives one policy per joint (the Coulomb entries of joint j's rows follow its policy).
The speed is the recorded one when the recording has it (``Recording.dq``), else the filtered
derivative; it decides the mask only, W keeps the filtered derivatives.

Lost packets: a recording made of segments (``Recording.segment``) is filtered, differentiated
and decimated segment by segment (:meth:`Recording.pieces`), the rows stacked in one W; a sample
bridged over lost packets (``Recording.measured`` False) runs through the filters but gives no
row, nor does a decimated sample whose decimation filter (± the factor) reaches one.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np

import rx90sym

from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.observation.processing import (DEFAULT_MIN_VELOCITY, DEFAULT_REST, REST_POLICIES, Processing, RestPolicy,
                                             drops_rest, rest_label, rest_per_joint)
from identify.observation.rest import presliding_base, rest_rows, without_empty_presliding
from identify.signal.filtering import EDGE_PERIODS, choose_cutoff, decimate, decimation_plan, derivatives

__all__ = ["DECIMATION_PASSBAND", "SPECTRUM_SAMPLES", "automatic_cutoff", "DEFAULT_MIN_VELOCITY", "DEFAULT_REST",
           "REST_POLICIES", "FilteredMotion", "Observation", "filtered_motion", "filtered_motions", "observation_matrix",
           "stack_rows"]

# Rest threshold and policy (measured on the TX40 and the twin: docs/real-data-identification.md):
# defined once, with the other processing defaults, in identify.observation.processing.


@dataclass(frozen=True, eq=False)
class Observation:
    """Y = W x + rho (eq. 6), rows grouped per joint (eq. 7).

    W: (r, c) observation matrix for the parameters ``names``; Y: (r,) torques [N m] with the
    spring added; joint: (r,) joint index (0-based) of each row; samples: (r,) index of each row's
    sample in the concatenated, decimated motion; cutoffs: per recording cut-off [Hz]; rates: per
    recording rate after decimation [Hz]; rate: the first of them; notes: decimation notes;
    min_velocity [rad/s] and rest: the rest policy used (None: no rest mask); t: (n_samples,) time of
    each sample of the concatenated, decimated motion [s] (what ``samples`` indexes).
    """

    W: np.ndarray
    Y: np.ndarray
    joint: np.ndarray
    names: tuple[str, ...]
    samples: np.ndarray
    cutoffs: tuple[float, ...]
    rates: tuple[float, ...]
    rate: float
    sources: tuple[str, ...]
    n_samples: int
    notes: tuple[str, ...] = ()
    min_velocity: float | None = None
    rest: RestPolicy = "drop"
    moving_fraction: np.ndarray | None = None
    t: np.ndarray | None = None

    @property
    def rows(self) -> int:
        return self.W.shape[0]

    def summary(self) -> str:
        """One line per recording: rows, rates, cut-off (what a user checks first)."""
        head = (f"{self.rows} equations, {len(self.names)} parameters, {self.n_samples} samples "
                f"after decimation to {self.rate:g} Hz")
        lines = [head] + [f"  {s}: rate {r:g} Hz, cut-off {c:.3g} Hz"
                          for s, r, c in zip(self.sources, self.rates, self.cutoffs)]
        if self.min_velocity is not None:
            frac = " ".join(f"{100 * f:.0f}%" for f in self.moving_fraction)
            lines.append(f"  rest below {self.min_velocity:g} rad/s ({rest_label(self.rest)}); moving per joint: {frac}")
        return "\n".join(lines + [f"  note: {n}" for n in self.notes if n])


@dataclass(frozen=True, eq=False)
class FilteredMotion:
    """Samples of one recording after derivation and parallel filtering (time on axis 0).

    t: (S,) true time of each kept sample [s]; moving: (S, n) whether each joint moves (all True
    without a threshold); usable: (S, n) the rows a "drop" policy keeps (joint i and every Coulomb driver
    of its row moving; every row of a joint with another policy); factor: decimation factor; kept: slice of the original
    samples before decimation; extra: (K, n) spring torque at the kept samples before decimation
    (what Y adds to the measured torque), for re-building Y from shifted torques.
    """

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    Y: np.ndarray        # measured torque + spring, (S, n)
    Phi: np.ndarray      # regressor, (S, n, c), filtered like Y
    cutoff: float
    rate: float
    source: str
    moving: np.ndarray
    usable: np.ndarray
    factor: int = 1
    kept: slice = field(default_factory=lambda: slice(None))
    extra: np.ndarray | float = 0.0
    note: str = ""
    measured: np.ndarray | None = None
    torque_kept: np.ndarray | None = None  # (n,) False for a joint whose torque is left out (None: all kept)

    def rows(self, drop_rest: bool) -> np.ndarray:
        """(S, n) rows that enter W: measured samples, and with ``drop_rest`` only ``usable`` ones; none of a
        joint whose torque is left out (``torque_kept``)."""
        keep = self.usable if drop_rest else np.ones(self.usable.shape, dtype=bool)
        keep = keep if self.measured is None else keep & self.measured[:, None]
        return keep if self.torque_kept is None else keep & self.torque_kept[None, :]


#: Pass band of the parallel decimation filter, as a fraction of the decimated rate (0.8 of its Nyquist).
DECIMATION_PASSBAND = 0.4


def automatic_cutoff(recordings: Sequence[Any], decimate_to: float | None = None) -> float:
    """The cut-off [Hz] chosen on ``recordings``: the largest :func:`identify.choose_cutoff` over them,
    and, when decimating, at least the pass band of the parallel filter (0.4 × ``decimate_to``):
    Y keeps its content up to there, so W must too (parallel filtering filters both alike)."""
    cuts = []
    pieces = [p for rec in recordings for p in rec.pieces()] if recordings else []
    longest = max((p.n_samples for p in pieces), default=0)
    for rec in pieces:
        if rec.n_samples < min(longest, SPECTRUM_SAMPLES):
            continue  # too short for a spectrum: the longer segments decide
        rate = 1.0 / float(np.median(np.diff(np.asarray(rec.t, dtype=float))))
        floor = max(2.0, DECIMATION_PASSBAND * decimate_to) if decimate_to else 2.0
        cuts.append(choose_cutoff(np.asarray(rec.q, dtype=float), rate, min_cutoff=floor))
    return float(max(cuts))


#: A segment shorter than this many samples does not take part in the automatic cut-off.
SPECTRUM_SAMPLES = 256


def shifted_torques(rec: Any, delay: float) -> np.ndarray:
    """Torques of ``rec`` advanced by ``delay`` seconds: τ(t + delay), linear interpolation
    (torques that lag the positions by ``delay`` are put back in step); ends held."""
    tau = np.asarray(rec.torques, dtype=float)
    if not delay:
        return tau
    t = np.asarray(rec.t, dtype=float)
    return np.column_stack([np.interp(t + delay, t, tau[:, j]) for j in range(tau.shape[1])])


def filtered_motion(robot: rx90sym.Robot, rec: Any, processing: Processing,
                    regressor_batch: Callable[..., np.ndarray] | None = None, names: Sequence[str] | None = None,
                    kept: slice | None = None, rest_span: slice | None = None) -> FilteredMotion:
    """Derivatives, regressor and torques of one recording, decimated together, by ``processing``: q
    filtered at its cut-off (None: :func:`automatic_cutoff` on this recording) and differentiated, the rows
    decimated to its ``decimate_to``, its rest threshold and policy ("drop": rows kept as they are,
    ``usable`` tells which to drop; the others: module docstring), its torque delay compensated
    (:func:`shifted_torques`), its spring torque added to the measured torque.

    regressor_batch: (Q, QD, QDD) -> (S, n, c) giving the columns wanted (default: all the
    standard columns, robot.regressor_batch); selecting before filtering saves the work of
    filtering columns nobody uses. names: the c column names (default: the robot's standard
    parameters), needed to find the Coulomb columns.
    kept: the samples kept after differentiation (default: all but the filter's edges; a block of a
    long recording keeps its core, :mod:`identify.observation.block_rows`); rest_span: the samples, around
    ``kept``, on which the rest runs of the "crossing" policy are measured (default: ``kept``).
    """
    rest, min_velocity, delay = processing.rest, processing.min_velocity, float(processing.delay)
    policies = rest_per_joint(rest, robot.n)
    if rec.q.shape[1] != robot.n:
        raise ValueError(f"{rec.source}: recording has {rec.q.shape[1]} joints, robot "
                         f"{robot.name!r} has {robot.n}")
    if rec.robot and rec.robot != robot.name:
        raise ValueError(f"{rec.source}: recording is of robot {rec.robot!r}, not {robot.name!r}")
    if getattr(rec, "n_segments", 1) > 1:
        raise ValueError(f"{rec.source}: {rec.n_segments} segments: filter each of its pieces() "
                         f"(filtered_motions does)")
    decimate_to = processing.decimate_to
    cutoff = processing.cutoff if processing.cutoff is not None else automatic_cutoff([rec], decimate_to)
    d = derivatives(rec.t, rec.q, cutoff=cutoff, kept=kept)
    tau = shifted_torques(rec, delay)[d.kept]
    extra = robot.spring_torque_batch(d.q)[:, :, 0] if processing.spring else 0.0
    Y = tau + extra
    Phi = (regressor_batch or robot.regressor_batch)(d.q, d.dq, d.ddq)
    n = robot.n
    moving = np.ones(d.dq.shape, dtype=bool)
    usable = moving.copy()
    if min_velocity is not None:
        # Recorded speeds decide the mask only (they are not filtered like q, so W does not use them).
        speed = np.asarray(rec.dq, dtype=float)[d.kept] if getattr(rec, "dq", None) is not None else d.dq
        moving = np.abs(speed) >= min_velocity
        if not (Phi.flags.owndata and Phi.flags.writeable):  # a reused workspace's view: not ours to change
            Phi = np.array(Phi, copy=True)
        context = None
        if rest_span is not None and kept is not None:
            w = derivatives(rec.t, rec.q, cutoff=cutoff, kept=rest_span)
            w_speed = np.asarray(rec.dq, dtype=float)[w.kept] if getattr(rec, "dq", None) is not None else w.dq
            start = d.kept.start - w.kept.start
            context = (w_speed, w.q, slice(start, start + d.dq.shape[0]))
        usable = rest_rows(robot, names, speed, d.q, Phi, min_velocity, policies, d.rate, context)
        dropped = np.array([r == "drop" for r in policies])
        usable[:, dropped] &= moving[:, dropped]
    plan = decimation_plan(d.rate, decimate_to)
    k = plan.factor
    q, dq, ddq, t = d.q, d.dq, d.ddq, d.t
    measured = _measured_rows(getattr(rec, "measured", None), d.kept, k)
    if k > 1:
        # Parallel filtering: the same zero-phase filter on Y and on every column of W.
        Y, Phi = decimate(Y, k), decimate(Phi, k)
        q, dq, ddq, t = q[::k], dq[::k], ddq[::k], t[::k]
        moving, usable = moving[::k], usable[::k]
    assert moving.shape[1] == n
    if not Phi.flags.owndata:  # a view of a reused workspace: the next recording overwrites it
        Phi = Phi.copy()
    return FilteredMotion(t, q, dq, ddq, Y, Phi, d.cutoff, plan.rate, rec.source, moving, usable,
                          k, d.kept, extra, plan.note, measured)


#: A decimated sample gives a row only when at most this share of the samples its decimation
#: filter spans (± the factor) were bridged over lost packets (scattered stale rows pass, a burst
#: of lost packets does not).
BRIDGED_SHARE = 0.25


def _measured_rows(measured: np.ndarray | None, kept: slice, factor: int) -> np.ndarray | None:
    """(S,) measured flags after decimation by ``factor``: the sample itself was measured and at
    most :data:`BRIDGED_SHARE` of the 2·factor + 1 samples around it were bridged."""
    if measured is None:
        return None
    ok = np.asarray(measured, dtype=bool)[kept]
    if factor > 1:
        share = np.convolve((~ok).astype(float), np.ones(2 * factor + 1) / (2 * factor + 1), mode="same")
        ok = (ok & (share <= BRIDGED_SHARE))[::factor]
    return ok


def filtered_motions(robot: rx90sym.Robot, recordings: Sequence[Any], processing: Processing,
                     regressor_batch: Callable[..., np.ndarray] | None = None, names: Sequence[str] | None = None,
                     ) -> tuple[list[FilteredMotion], tuple[str, ...], list[Any]]:
    """:func:`filtered_motion` of every segment of every recording (``processing`` with its cut-off given):
    the motions, notes naming each segment left out because it is too short for the filters' edges, and
    the segments used (one per motion)."""
    cutoff = processing.cutoff
    motions, notes, used = [], [], []
    for rec in recordings:
        for piece in rec.pieces():
            rate = 1.0 / float(np.median(np.diff(piece.t))) if piece.n_samples > 1 else 0.0
            edge = max(2, int(np.ceil(EDGE_PERIODS * rate / cutoff))) if rate else 0
            if rec.n_segments > 1 and piece.n_samples < 2 * edge + 5:
                notes.append(f"{piece.source}: segment of {piece.n_samples} samples left out (shorter than "
                             f"the {2 * edge + 5} the filter's edges need at {cutoff:.3g} Hz)")
                continue
            motions.append(filtered_motion(robot, piece, processing, regressor_batch, names))
            used.append(piece)
    if not motions:
        raise ValueError("no segment is long enough to filter: " + "; ".join(notes))
    return motions, tuple(notes), used


def stack_rows(blocks: Sequence[np.ndarray], Ys: Sequence[np.ndarray], min_velocity: float | None = None,
               dqs: Sequence[np.ndarray] | None = None, masks: Sequence[np.ndarray] | None = None,
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Rows grouped per joint (eqs. 7-8): W = [W_1; ...; W_n], each W_i the joint-i rows of every
    sample of every motion. blocks: per motion (S, n, c); Ys: per motion (S, n).

    masks: per motion (S, n) rows to keep (e.g. ``FilteredMotion.usable``); otherwise
    min_velocity [rad/s] with dqs drops joint i's rows where |qd_i| is below it.
    """
    # One motion is not copied; the rows are gathered straight into W (each large temporary array costs
    # its page faults, as much as the copy itself on a loaded machine).
    Phi = blocks[0] if len(blocks) == 1 else np.concatenate(blocks, axis=0)
    Y = Ys[0] if len(Ys) == 1 else np.concatenate(Ys, axis=0)
    S, n, c = Phi.shape
    keep = np.ones((S, n), dtype=bool)
    if masks is not None:
        keep = np.concatenate(masks, axis=0)
    elif min_velocity is not None:
        keep = np.abs(np.concatenate(dqs, axis=0)) >= min_velocity
    samples = [np.flatnonzero(keep[:, i]) for i in range(n)]
    W = np.empty((sum(idx.size for idx in samples), c), dtype=Phi.dtype)
    start = 0
    for i, idx in enumerate(samples):   # "clip": no bounds to check (flatnonzero's), no buffered copy
        np.take(Phi[:, i, :], idx, axis=0, out=W[start:start + idx.size], mode="clip")
        start += idx.size
    return (W, np.concatenate([Y[idx, i] for i, idx in enumerate(samples)]),
            np.concatenate([np.full(idx.size, i) for i, idx in enumerate(samples)]), np.concatenate(samples))


def column_regressor(robot: rx90sym.Robot, base: Any = None, columns: Sequence[str] | None = None,
                     rest: str | None = None) -> tuple[tuple[str, ...], Callable[..., np.ndarray]]:
    """(names, regressor_batch) of the columns of W: the base parameters of ``robot`` (or ``base``),
    or the standard parameters ``columns``; with ``rest="presliding"`` the base gets the presliding
    magnitudes FPj (:func:`presliding_base`)."""
    # One reused buffer for the full-rate regressor of every recording (no fresh (N, n, c) array each).
    if columns is not None:
        idx = robot.parameter_index(columns)
        workspace = robot.regressor_workspace()

        def regressor(Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray) -> np.ndarray:
            return workspace.evaluate(Q, QD, QDD)[:, :, idx]
        return tuple(columns), regressor
    base = presliding_base(robot, base, rest)
    if hasattr(base, "regressor_workspace"):
        return tuple(base.names), base.regressor_workspace().evaluate
    return tuple(base.names), base.regressor_batch


def observation_matrix(robot: rx90sym.Robot, recordings: Sequence[Any], cutoff: float | None = None,
                       decimate_to: float | None = DEFAULT_DECIMATE_TO, base: Any = None,
                       columns: Sequence[str] | None = None, spring: bool = True,
                       min_velocity: float | None = None, rest: RestPolicy = "drop",
                       delay: float = 0.0) -> Observation:
    """Observation matrix W and torque vector Y (eqs. 6-8) from one or many recordings.

    cutoff [Hz]: Butterworth cut-off for q (None: :func:`automatic_cutoff` on all the recordings,
    used for all, reported); decimate_to [Hz]: rate after parallel filtering (None or 0: no decimation; a rate
    that does not divide the sampling rate decimates to the nearest achievable one, with a note);
    base: BaseParameters giving the columns (default: symbolic base parameters of ``robot``);
    columns: standard parameter names instead of the base parameters (e.g. a payload's);
    spring: add the spring torque to the measured torque (Y2 = Gamma_motor2 + Gamma_s);
    min_velocity [rad/s], rest: rest threshold and policy (see the module docstring);
    delay [s]: torque lag compensated on every recording.
    """
    if isinstance(recordings, (str, bytes)) or not isinstance(recordings, Sequence):
        recordings = [recordings]
    if not recordings:
        raise ValueError("observation_matrix: no recordings given")
    processing = Processing(cutoff=cutoff, decimate_to=decimate_to, min_velocity=min_velocity, rest=rest, delay=delay,
                            spring=spring)
    min_velocity = processing.min_velocity
    names, regressor = column_regressor(robot, base, columns, rest if min_velocity is not None else None)
    if cutoff is None:
        processing = processing.chosen(cutoff=automatic_cutoff(recordings, processing.decimate_to))
    motions, skipped, _ = filtered_motions(robot, recordings, processing, regressor, names)  # one filtering for all
    keep = [m.rows(min_velocity is not None and drops_rest(rest)) for m in motions]
    W, Y, joint, samples = stack_rows([m.Phi for m in motions], [m.Y for m in motions], masks=keep)
    W, names, empty = without_empty_presliding(W, names)
    rates = tuple(m.rate for m in motions)
    if max(rates) > min(rates) * (1 + 1e-3):
        raise ValueError(f"recordings have different rates after decimation: "
                         f"{', '.join(f'{r:g}' for r in rates)} Hz; give decimate_to")
    moving = np.concatenate([m.moving for m in motions])
    return Observation(W, Y, joint, names, samples, tuple(m.cutoff for m in motions), rates,
                       rates[0], tuple(m.source for m in motions), sum(len(m.Y) for m in motions),
                       tuple(m.note for m in motions) + skipped + empty, min_velocity, rest,
                       moving.mean(axis=0) if min_velocity is not None else None,
                       np.concatenate([m.t for m in motions]))

