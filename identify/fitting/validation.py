"""Torque prediction and cross-validation on a motion not used for fitting (section III-B).

The prediction uses the filtering of the fit (cut-off, decimation: pass the values the fit used)
and is scored against the raw measured torques at the recording's own time stamps
(:mod:`identify.fitting.raw_scoring`; beside the plain OLS baseline on the same samples when one is
given, :mod:`identify.fitting.baseline`); given a rest threshold, it takes the Coulomb term as 0 where its joint (or motor) rests: at rest
the static friction lies anywhere in [−FS, FS] and the sign of a noisy speed says nothing. The
errors are reported on all samples and on the samples where each joint moves.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

import rx90sym
from rx90sym.threads import one_blas_thread

from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.observation.matrix import presliding_base
from identify.observation.processing import RestPolicy, has_policy, predicted_rest
from identify.estimation.results import IdentificationResult, json_number
from identify.io.blocks import block_source, check_block
from identify.fitting.baseline_blocks import baseline_at, streamed_baseline_prediction
from identify.fitting.raw_scoring import SCORE_TRIM_S, RawScores
from identify.fitting.streamed_filtered import FilteredSums, streamed_filtered_rms
from identify.signal.interpolate import onto
from identify.observation.matrix import column_regressor
from identify.observation.offsets import offset_base, result_offsets
from identify.observation.stream import DEFAULT_BLOCK, StreamSettings, piece, plan_windows, scan_all, windows_in_order

__all__ = ["PREDICTION_OVERSAMPLING", "Validation", "predict", "prediction_rate", "validate"]

#: A fit predicts at this many times its cut-off (or at the recording's own rate, when lower): its
#: prediction, band-limited at the cut-off, is then interpolated onto the raw time stamps within about 1 %
#: (linear interpolation of a sine sampled 20 times a period: (pi/20)^2/2). At the fit's decimated rate
#: (50 Hz for a 20 Hz cut-off) the interpolation cut the steps of a trapezoidal motion: Panda twin joints
#: 2 and 4 while moving 1.24x and 1.32x the plain baseline, 0.84x and 0.94x at the recording's rate.
PREDICTION_OVERSAMPLING = 20.0


def _rms(err: np.ndarray, mask: np.ndarray) -> np.ndarray:
    return np.array([np.sqrt(np.mean(err[mask[:, j], j] ** 2)) if mask[:, j].any() else np.nan
                     for j in range(err.shape[1])])


def _relative(err: np.ndarray, y: np.ndarray, mask: np.ndarray) -> np.ndarray:
    # No samples, or a torque that is 0 on all of them (joint 1 at rest): no relative error (nan).
    norms = [(np.linalg.norm(err[mask[:, j], j]), np.linalg.norm(y[mask[:, j], j])) for j in range(err.shape[1])]
    return np.array([100 * e / y_ if y_ > 0 else np.nan for e, y_ in norms])


@dataclass(frozen=True, eq=False)
class Validation:
    """Torque prediction on a motion not used for fitting (cross-validation, section III-B).

    relative_error_pct: (n,) 100 ||Y_j - W_j beta|| / ||Y_j|| per joint on all samples; rms_error:
    (n,) N m; the ``_moving`` pair: the same on the samples where joint j moves (|q̇j| ≥
    moving_threshold rad/s; equal to the all-sample figures without a threshold);
    moving_fraction: (n,) share of samples where joint j moves; measured: (S, n) the raw measured
    torques [N m] at the recorded samples scored (inside the prediction, measured; with a baseline,
    0.5 s from each segment's ends too), predicted: (S, n) the prediction interpolated there (spring
    not added); t: (S,) their time [s]; moving: (S, n). cutoff [Hz], rate [Hz]: the filtering used.
    baseline_rms_error, baseline_rms_error_moving: (n,) the plain OLS baseline's RMS [N m] on the same
    samples (None: no baseline); beats_baseline: (n,) rms_error <= baseline_rms_error;
    baseline_predicted: (S, n) its prediction. rms_error_filtered, rms_error_filtered_moving: (n,) [N m]
    the former figures, against the torques filtered and decimated like the fit's rows (what FIGAROH and
    the paper report; they differ between fits of other filters, the raw figures do not).
    """

    relative_error_pct: np.ndarray
    rms_error: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    t: np.ndarray
    source: str
    relative_error_pct_moving: np.ndarray | None = None
    rms_error_moving: np.ndarray | None = None
    moving_fraction: np.ndarray | None = None
    moving_threshold: float | None = None
    moving: np.ndarray | None = None
    cutoff: float = float("nan")
    rate: float = float("nan")
    baseline_rms_error: np.ndarray | None = None
    baseline_rms_error_moving: np.ndarray | None = None
    baseline_predicted: np.ndarray | None = None
    rms_error_filtered: np.ndarray | None = None
    rms_error_filtered_moving: np.ndarray | None = None
    t0_s: float = 0.0  # the log's own clock at the recording's first sample (t counts from it) [s]

    @property
    def beats_baseline(self) -> np.ndarray | None:
        """(n,) per joint: the toolkit's RMS on all samples scored at most the plain baseline's."""
        return None if self.baseline_rms_error is None else self.rms_error <= self.baseline_rms_error

    def table(self) -> str:
        head = ("joint  rms error [N m]  relative error [%]  rms moving [N m]  relative moving [%]"
                "  moving [%]")
        n = len(self.rms_error)
        rel_m = self.relative_error_pct_moving if self.relative_error_pct_moving is not None else self.relative_error_pct
        rms_m = self.rms_error_moving if self.rms_error_moving is not None else self.rms_error
        frac = self.moving_fraction if self.moving_fraction is not None else np.ones(n)
        base = self.baseline_rms_error is not None
        if base:
            head += "  baseline rms [N m]  baseline moving [N m]"
        rows = [f"{j + 1:5d}  {self.rms_error[j]:15.3f}  {self.relative_error_pct[j]:18.2f}  "
                f"{rms_m[j]:16.3f}  {rel_m[j]:19.2f}  {100 * frac[j]:10.1f}"
                + (f"  {self.baseline_rms_error[j]:18.3f}  {self.baseline_rms_error_moving[j]:21.3f}" if base else "")
                for j in range(n)]
        thr = ("no rest threshold" if self.moving_threshold is None
               else f"moving: |q̇j| ≥ {self.moving_threshold:g} rad/s")
        lines = [f"Validation on {self.source} against the raw measured torques ({self.t.size} samples; cut-off "
                 f"{self.cutoff:.4g} Hz, rate {self.rate:.6g} Hz, {thr})", head, *rows]
        return "\n".join(lines + ([self.baseline_verdict()] if base else []))

    def baseline_verdict(self) -> str:
        """"beats the plain baseline on joints ..." (RMS on all samples scored, per joint)."""
        beats = self.beats_baseline
        won = ", ".join(str(j + 1) for j in np.flatnonzero(beats)) or "none"
        lost = ", ".join(f"{j + 1} ({self.rms_error[j] / self.baseline_rms_error[j]:.3f}x)"
                         for j in np.flatnonzero(~beats))
        return (f"beats the plain baseline (OLS, 10 Hz, same samples) on joints {won}"
                + (f"; not on joints {lost}" if lost else ""))

    def still_message(self) -> str | None:
        """What to say when joints never move in the recording (their while-moving errors are
        undefined, nan), or None when every joint moves on some sample."""
        if self.moving_fraction is None or np.all(self.moving_fraction > 0):
            return None
        thr = "" if self.moving_threshold is None else f" (|q̇j| ≥ {self.moving_threshold:g} rad/s on no sample)"
        if np.all(self.moving_fraction == 0):
            return (f"{self.source}: no joint moves{thr}: the errors while moving are undefined (nan) and the "
                    f"all-sample errors judge the model at rest only (gravity, offsets)")
        still = ", ".join(str(j + 1) for j in np.flatnonzero(self.moving_fraction == 0))
        return f"{self.source}: joint(s) {still} never move{thr}: their errors while moving are undefined (nan)"

    def to_dict(self) -> dict[str, Any]:
        def listed(a: np.ndarray | None) -> list | None:
            return None if a is None else [json_number(v) for v in a]

        return {"source": self.source, "relative_error_pct": listed(self.relative_error_pct),
                "rms_error": listed(self.rms_error),
                "relative_error_pct_moving": listed(self.relative_error_pct_moving),
                "rms_error_moving": listed(self.rms_error_moving),
                "moving_fraction": listed(self.moving_fraction),
                "moving_threshold": self.moving_threshold,
                "cutoff_hz": json_number(self.cutoff), "rate_hz": json_number(self.rate),
                "scored_against": "raw measured torques", "samples_scored": int(self.t.size),
                "baseline_rms_error": listed(self.baseline_rms_error),
                "baseline_rms_error_moving": listed(self.baseline_rms_error_moving),
                "beats_baseline": None if self.beats_baseline is None else [bool(v) for v in self.beats_baseline],
                "rms_error_filtered": listed(self.rms_error_filtered),
                "rms_error_filtered_moving": listed(self.rms_error_filtered_moving)}


def prediction_rate(cutoff: float, rate: float) -> float | None:
    """The rate [Hz] a fit of cut-off ``cutoff`` [Hz] predicts a recording of ``rate`` [Hz] at
    (``decimate_to`` of :func:`predict`): PREDICTION_OVERSAMPLING x the cut-off, None (the recording's
    own rate) when that is not at least half the recording's rate."""
    target = PREDICTION_OVERSAMPLING * float(cutoff)
    return None if 2.0 * target > float(rate) else target


def base_vector(result: IdentificationResult, base: Any, robot: rx90sym.Robot) -> np.ndarray:
    """β over ``base.names`` from a result (parameters of the base set missing from it count as 0)."""
    unknown = [nm for nm in result.names if nm not in base.names]
    if unknown:
        raise ValueError(f"result has parameters {unknown} that are not base parameters of "
                         f"{robot.name!r}")
    values = dict(zip(result.names, result.values))
    return np.array([values.get(nm, 0.0) for nm in base.names])


@one_blas_thread()
def predict(robot: rx90sym.Robot, result: IdentificationResult, recording: Any, base: Any = None,
            cutoff: float | None = None, decimate_to: float | None | str = DEFAULT_DECIMATE_TO, spring: bool = True,
            min_velocity: float | None = None, delay: float = 0.0, rest: RestPolicy = "zero-coulomb",
            baseline: Any = None, filtered_at: float | None | str = "prediction", block: int = DEFAULT_BLOCK,
            convention: str | None = None, gains: Any = None) -> Validation:
    """Predicted vs measured torques of ``recording`` (a recording, or a recording file) with the parameters
    of ``result``, block by block whatever its length.

    cutoff [Hz], decimate_to [Hz]: give those of the fit (None: chosen on this recording; decimate_to
    "prediction": :func:`prediction_rate` of the cut-off, what :meth:`identify.Fit.predict` does);
    min_velocity [rad/s]: rest threshold (Coulomb term 0 at rest, errors also while moving);
    delay [s]: torque lag compensated as in the fit; rest: the fit's rest policy, one or one per joint
    (every sample is predicted: "drop" takes Coulomb 0 at rest; "presliding" the presliding state
    times FPj; the others as in the fit); baseline: the fit's plain OLS baseline
    (identify.fitting.baseline.PlainBaseline), predicted block by block and scored on the same raw
    samples (None: none). Scored against the raw measured torques at the recording's own time stamps;
    the filtered figures (``rms_error_filtered``) on rows decimated to ``filtered_at`` [Hz] (None: not
    decimated; "prediction": the prediction's rate; :meth:`identify.Fit.predict` gives the fit's own).
    block: raw samples read, filtered and predicted at a time (memory: a block, the decimated
    prediction and the samples scored); convention, gains: how a recording file is read.
    BLAS on one thread inside the call, the caller's count back after it (rx90sym.threads).
    """
    if base is None:  # the symbolic base, with the torque offsets the fit chose (OFFj in the result)
        base = offset_base(rx90sym.base_parameters(robot), result_offsets(result, robot))
    base = presliding_base(robot, base, rest if has_policy(rest, "presliding") and min_velocity is not None else None)
    beta = base_vector(result, base, robot)
    block = check_block(block)
    src = block_source(recording, robot, convention, gains)
    at_prediction = decimate_to == "prediction"
    # As the fit: every sample predicted (a dropped joint's rest with Coulomb 0).
    settings = StreamSettings(cutoff, None if at_prediction else (decimate_to or None), min_velocity or None,
                              predicted_rest(rest), float(delay), spring, block)
    scans, fc = scan_all([src], settings)
    if at_prediction:  # at 20 x the cut-off (or the recording's own rate), not at the fit's decimated rate
        settings = replace(settings, decimate_to=prediction_rate(fc, scans[0].rate))
    filtered_settings = (settings if filtered_at == "prediction"
                         else replace(settings, decimate_to=filtered_at or None))  # the fit's own rows
    plans, _ = plan_windows(scans[0], fc, settings)
    names, regressor = column_regressor(robot, base)
    bp = None
    if baseline is not None:  # its own pass over the log, block by block (its own filter and margins)
        bp = streamed_baseline_prediction(robot, baseline, src, scans[0], block)
    sums = FilteredSums(beta, robot.n) if filtered_settings == settings else None
    length = {g.start: g.samples for g in scans[0].segments}
    groups: dict[int, list] = {}
    for plan, window, rec, _ in windows_in_order([src], [plans]):
        m = piece(robot, rec, window, plan, fc, settings, regressor, names, 0).motion
        if sums is not None:
            sums.add(m)
        pred = m.Phi @ beta
        if spring and robot.spring is not None:
            pred = pred - robot.spring_torque_batch(m.q)[:, :, 0]
        # The raw samples this core owns: from its first prediction to the next core's (scored on raw torques).
        t_pred, t = m.t + settings.delay, np.asarray(rec.t, dtype=float)
        step = float(np.median(np.diff(t)))
        own = ((t >= t_pred[0] - 1e-6 * step) & (t < t_pred[0] + (m.t.size * m.factor - 1e-6) * step)
               & rec.measured_mask)
        # The segment's first and last times (the windows' raw samples lie on its regular grid).
        ends = (t[0] - window.raw[0] * step, t[-1] + (length[plan.start] - window.raw[1]) * step)
        groups.setdefault(id(plan), []).append((t_pred, pred, m.moving, t[own], np.asarray(rec.torques)[own], ends))
    parts = []
    for group in groups.values():  # one segment: its predictions interpolated onto its raw samples
        first, last = group[0][5][0], group[-1][5][1]
        tp, pr, mv, t, tau = (np.concatenate(a) for a in list(zip(*group))[:5])
        tol = 1e-9 * max(1.0, abs(tp[-1]))
        # SCORE_TRIM_S from the segment's ends (the baseline's trim), inside the prediction.
        inside = (t <= tp[-1] + tol) & (t >= first + SCORE_TRIM_S - tol) & (t <= last - SCORE_TRIM_S + tol)
        b = None
        if bp is not None:  # only where the baseline predicts too
            scored, b = baseline_at(bp, t)
            inside &= scored
            b = b[inside]
        t, tau = t[inside], tau[inside]
        nearest = np.clip(np.searchsorted(tp, t - 0.5 * (tp[1] - tp[0] if tp.size > 1 else 0.0)), 0, tp.size - 1)
        parts.append((t, tau, onto(t, tp, pr), mv[nearest], b))
    if not any(p[0].size for p in parts):
        raise ValueError(f"{src.source}: no recorded sample lies inside the prediction"
                         + (" and 0.5 s from the segments' ends (the plain baseline's trim)" if bp is not None else ""))
    t, Y, pred, mov = (np.concatenate([p[k] for p in parts]) for k in range(4))
    base_pred = None if bp is None else np.concatenate([p[4] for p in parts])
    # The filtered figures on the fit's rows: from this pass when they are the prediction's, else a pass of their own.
    filtered = (sums.result() if sums is not None else
                streamed_filtered_rms(robot, src, scans[0], fc, filtered_settings, regressor, names, beta))
    return replace(scored_validation(RawScores(t, Y, pred, mov, base_pred), src.source, settings.min_velocity, fc,
                                     plans[0].rate), **filtered, t0_s=log_clock(recording, src))


def log_clock(recording: Any, source: Any = None) -> float:
    """The log's own clock [s] at ``recording``'s first sample: its ``meta["log"]``, else the ``t0_s`` field
    of its file (``source``: its :class:`identify.io.blocks.BlockSource`); 0 when it was not read from a log."""
    own = float(((getattr(recording, "meta", None) or {}).get("log") or {}).get("t0_s") or 0.0)
    return own or float((getattr(source, "log", None) or {}).get("t0_s") or 0.0)


def scored_validation(raw: RawScores, source: str, min_velocity: float | None, cutoff: float,
                      rate: float) -> Validation:
    """The :class:`Validation` of raw-torque scores (identify.fitting.raw_scoring.RawScores)."""
    Y, predicted, moving = raw.measured, raw.predicted, raw.moving
    err = Y - predicted
    every = np.ones_like(moving)
    b_all = b_mov = None
    if raw.baseline is not None:
        b_err = Y - raw.baseline
        b_all, b_mov = _rms(b_err, every), _rms(b_err, moving)
    return Validation(
        relative_error_pct=_relative(err, Y, every), rms_error=_rms(err, every),
        measured=Y, predicted=predicted, t=raw.t, source=source,
        relative_error_pct_moving=_relative(err, Y, moving), rms_error_moving=_rms(err, moving),
        moving_fraction=moving.mean(axis=0), moving_threshold=min_velocity, moving=moving,
        cutoff=cutoff, rate=rate, baseline_rms_error=b_all, baseline_rms_error_moving=b_mov,
        baseline_predicted=raw.baseline)


@one_blas_thread()
def validate(robot: rx90sym.Robot, result: IdentificationResult, recording: Any, **options: Any) -> Validation:
    """Cross-validation: torque error per joint on a recording not used in the fit (see :func:`predict`)."""
    return predict(robot, result, recording, **options)
