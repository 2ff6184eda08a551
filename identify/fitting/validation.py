"""Torque prediction and cross-validation on a motion not used for fitting (section III-B).

The prediction uses the filtering of the fit (cut-off, decimation: pass the values the fit used)
and is scored against the raw measured torques at the recording's own time stamps
(:mod:`identify.fitting.raw_scoring`; beside the two yardsticks on the same samples when given: the
plain OLS baseline, :mod:`identify.fitting.baseline`, and the model the user had,
:mod:`identify.fitting.user_model`); given a rest threshold, it takes the Coulomb term as 0 where its joint (or motor) rests: at rest
the static friction lies anywhere in [−FS, FS] and the sign of a noisy speed says nothing. The
errors are reported on all samples and on the samples where each joint moves.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

import rx90sym
from rx90sym.threads import one_blas_thread

from identify.estimation.results import IdentificationResult, json_number
from identify.fitting.baseline_blocks import baseline_at, log_predictions
from identify.fitting.filtered_errors import FilteredSums, filtered_rms
from identify.fitting.raw_scoring import SCORE_TRIM_S, RawScores
from identify.io.blocks import DEFAULT_BLOCK, block_source, check_block
from identify.observation.block_rows import piece, plan_windows, windows_in_order
from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.observation.matrix import column_regressor
from identify.observation.offsets import offset_base, result_offsets
from identify.observation.processing import Processing, RestPolicy, has_policy, predicted_rest
from identify.observation.rest import presliding_base
from identify.observation.scan import scan_all
from identify.signal.interpolate import onto

__all__ = ["PREDICTION_OVERSAMPLING", "YARDSTICK_NAMES", "Validation", "predict", "prediction_rate", "validate"]

#: A fit predicts at this many times its cut-off (or at the recording's own rate, when lower): its
#: prediction, band-limited at the cut-off, is then interpolated onto the raw time stamps within about 1 %
#: (linear interpolation of a sine sampled 20 times a period: (pi/20)^2/2). At the fit's decimated rate
#: (50 Hz for a 20 Hz cut-off) the interpolation cut the steps of a trapezoidal motion: Panda twin joints
#: 2 and 4 while moving 1.24x and 1.32x the plain baseline, 0.84x and 0.94x at the recording's rate.
PREDICTION_OVERSAMPLING = 20.0
#: The yardsticks' names in tables and verdicts: the plain OLS baseline, the model the user had.
YARDSTICK_NAMES = ("plain OLS", "user model")


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
    baseline_predicted: (S, n) its prediction. user_rms_error, user_rms_error_moving, user_predicted: the same
    of the second yardstick, the model the user had (identify.fitting.user_model; None: not computed,
    ``user_model_note`` says why). rms_error_filtered, rms_error_filtered_moving: (n,) [N m]
    against the torques filtered and decimated like the fit's rows (what FIGAROH and
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
    user_rms_error: np.ndarray | None = None
    user_rms_error_moving: np.ndarray | None = None
    user_predicted: np.ndarray | None = None
    user_model_note: str = ""  # why there is no model the user had ("" when there is, or no yardstick at all)
    t0_s: float = 0.0  # the log's own clock at the recording's first sample (t counts from it) [s]
    rollout: Any = None  # the model rolled out in MuJoCo (identify.rollout.result.Rollout), None: not asked
    not_predicted: tuple[int, ...] = ()  # joints (1-based) whose torque the fit left out: NaN, not scored

    def without_joints(self, joints: Sequence[int]) -> "Validation":
        """This validation with joints (1-based) not predicted: their predicted torques and every figure NaN
        (a fit that left a joint's torque out fitted none of the columns only its rows see: a prediction
        of that joint would lack them)."""
        cols = [j - 1 for j in joints]

        def cut(a: np.ndarray | None) -> np.ndarray | None:
            if a is None:
                return None
            out = np.array(a, dtype=float)
            out[..., cols] = np.nan
            return out

        names = ("relative_error_pct", "rms_error", "predicted", "relative_error_pct_moving", "rms_error_moving",
                 "baseline_rms_error", "baseline_rms_error_moving", "baseline_predicted", "user_rms_error",
                 "user_rms_error_moving", "user_predicted", "rms_error_filtered", "rms_error_filtered_moving")
        return replace(self, **{k: cut(getattr(self, k)) for k in names},
                       not_predicted=tuple(sorted(set(self.not_predicted) | set(joints))))

    @property
    def beats_baseline(self) -> np.ndarray | None:
        """(n,) per joint: the toolkit's RMS on all samples scored at most the plain baseline's."""
        return None if self.baseline_rms_error is None else self.rms_error <= self.baseline_rms_error

    def yardsticks(self, moving: bool = False) -> dict[str, np.ndarray]:
        """The yardsticks' RMS [N m] per joint by name (:data:`YARDSTICK_NAMES`; those computed), on all
        samples scored or while the joint moves."""
        rms = ((self.baseline_rms_error_moving, self.user_rms_error_moving) if moving
               else (self.baseline_rms_error, self.user_rms_error))
        return {name: v for name, v in zip(YARDSTICK_NAMES, rms) if v is not None}

    def yardstick_ratio(self, moving: bool = False) -> tuple[np.ndarray, list[str | None]] | None:
        """(ratio (n,) of the toolkit's RMS to the better yardstick's, the better one's name per joint), on all
        samples or while moving; None without yardsticks (nan and None where a joint never moves)."""
        sticks = self.yardsticks(moving)
        if not sticks:
            return None
        names = list(sticks)
        table = np.vstack([sticks[k] for k in names])
        best = np.argmin(np.where(np.isnan(table), np.inf, table), axis=0)
        own = self.rms_error_moving if moving and self.rms_error_moving is not None else self.rms_error
        better = table[best, np.arange(table.shape[1])]
        with np.errstate(divide="ignore", invalid="ignore"):
            return own / better, [names[k] if np.isfinite(v) else None for k, v in zip(best, better)]

    @property
    def beats_both(self) -> np.ndarray | None:
        """(n,) per joint: the toolkit's RMS on all samples scored at most every yardstick's (None: none)."""
        done = self.yardstick_ratio()
        return None if done is None else done[0] <= 1.0

    def table(self) -> str:
        head = ("joint  rms error [N m]  relative error [%]  rms moving [N m]  relative moving [%]"
                "  moving [%]")
        n = len(self.rms_error)
        rel_m = self.relative_error_pct_moving if self.relative_error_pct_moving is not None else self.relative_error_pct
        rms_m = self.rms_error_moving if self.rms_error_moving is not None else self.rms_error
        frac = self.moving_fraction if self.moving_fraction is not None else np.ones(n)
        extra = []  # (header, values) of the yardsticks' columns
        for name in self.yardsticks():
            extra += [(f"{name} rms [N m]", self.yardsticks()[name]),
                      (f"{name} moving [N m]", self.yardsticks(True)[name])]
        head += "".join(f"  {h}" for h, _ in extra)
        rows = [f"{j + 1:5d}  not predicted: its torque was left out of the fit (constant: a channel not logged)"
                if j + 1 in self.not_predicted else
                f"{j + 1:5d}  {self.rms_error[j]:15.3f}  {self.relative_error_pct[j]:18.2f}  "
                f"{rms_m[j]:16.3f}  {rel_m[j]:19.2f}  {100 * frac[j]:10.1f}"
                + "".join(f"  {v[j]:{len(h)}.3f}" for h, v in extra)
                for j in range(n)]
        thr = ("no rest threshold" if self.moving_threshold is None
               else f"moving: |q̇j| ≥ {self.moving_threshold:g} rad/s")
        lines = [f"Validation on {self.source} against the raw measured torques ({self.t.size} samples; cut-off "
                 f"{self.cutoff:.4g} Hz, rate {self.rate:.6g} Hz, {thr})", head, *rows]
        return "\n".join(lines + self.verdict() + ([self.rollout.table()] if self.rollout is not None else []))

    def verdict(self) -> list[str]:
        """"beats both yardsticks on joints ..." on all samples scored and while moving (per joint, RMS), with
        the better yardstick and the ratio where it does not; the model the user had's absence said."""
        out = []
        both = len(self.yardsticks()) == 2
        ratios = [self.yardstick_ratio(m) for m in (False, True)]
        for label, done in (("all samples", ratios[0]), ("while moving", ratios[1])):
            if done is None:
                continue
            ratio, better = done
            what = ("both yardsticks (the plain OLS, 10 Hz, and the model the user had; same samples)" if both
                    else "the plain baseline (OLS, 10 Hz, same samples)") if not out else "both" if both else "it"
            won = ", ".join(str(j + 1) for j in np.flatnonzero(ratio <= 1.0)) or "none"
            lost = ", ".join(f"{j + 1} ({better[j]} {ratio[j]:.3f}x)" for j in np.flatnonzero(ratio > 1.0))
            still = ", ".join(str(j + 1) for j in np.flatnonzero(np.isnan(ratio)) if j + 1 not in self.not_predicted)
            out.append(f"beats {what} on joints {won} ({label})" + (f"; not on joints {lost}" if lost else "")
                       + (f"; joints {still} never move" if still else "")
                       + (f"; joints {', '.join(map(str, self.not_predicted))} not predicted" if self.not_predicted
                          else ""))
        if ratios[0] is not None:  # the figure the verdict is on, every joint: RMS / the better yardstick's
            cell = lambda v: "-" if not np.isfinite(v) else f"{v:.2f}"  # noqa: E731 (a joint never moving: -)
            out.append("RMS / the better yardstick's, per joint (all samples / while moving): " + "  ".join(
                f"j{j + 1} {cell(a)}/{cell(m)}" for j, (a, m) in enumerate(zip(ratios[0][0], ratios[1][0]))))
        if self.user_model_note and self.yardsticks():
            out.append(f"the model the user had: not computed ({self.user_model_note})")
        return out

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
                "user_model_rms_error": listed(self.user_rms_error),
                "user_model_rms_error_moving": listed(self.user_rms_error_moving),
                "user_model_note": self.user_model_note or None,
                **self._yardstick_dict(),
                "rms_error_filtered": listed(self.rms_error_filtered),
                "rms_error_filtered_moving": listed(self.rms_error_filtered_moving),
                "not_predicted": list(self.not_predicted),
                **({"rollout": self.rollout.to_dict()} if self.rollout is not None else {})}

    def _yardstick_dict(self) -> dict[str, Any]:
        """The JSON's comparison with the yardsticks: per joint the ratio to the better one and its name, and
        whether the toolkit beats both, on all samples and while moving (null without yardsticks)."""
        out: dict[str, Any] = {}
        for suffix, moving in (("", False), ("_moving", True)):
            done = self.yardstick_ratio(moving)
            ratio, better = done if done is not None else (None, None)
            out.update({f"yardstick_ratio{suffix}": None if ratio is None else [json_number(v) for v in ratio],
                        f"better_yardstick{suffix}": better,
                        f"beats_both{suffix}": None if ratio is None else [bool(v <= 1.0) for v in ratio]})
        return out


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
            convention: str | None = None, gains: Any = None, user_model: Any = None,
            user_model_note: str = "", rollout: Any = None) -> Validation:
    """Predicted vs measured torques of ``recording`` (a recording, or a recording file) with the parameters
    of ``result``, block by block whatever its length.

    cutoff [Hz], decimate_to [Hz]: give those of the fit (None: chosen on this recording; decimate_to
    "prediction": :func:`prediction_rate` of the cut-off, what :meth:`identify.Fit.predict` does);
    min_velocity [rad/s]: rest threshold (Coulomb term 0 at rest, errors also while moving);
    delay [s]: torque lag compensated as in the fit; rest: the fit's rest policy, one or one per joint
    (every sample is predicted: "drop" takes Coulomb 0 at rest; "presliding" the presliding state
    times FPj; the others as in the fit); baseline: the fit's plain OLS baseline
    (identify.fitting.baseline.PlainBaseline), user_model: the model the user had
    (identify.fitting.user_model.UserModel), both predicted in one pass block by block and scored on the
    same raw samples (None: none; user_model_note: why there is none, shown beside the figures). Scored against the raw measured torques at the recording's own time stamps;
    the filtered figures (``rms_error_filtered``) on rows decimated to ``filtered_at`` [Hz] (None: not
    decimated; "prediction": the prediction's rate; :meth:`identify.Fit.predict` gives the fit's own).
    block: raw samples read, filtered and predicted at a time (memory: a block, the decimated
    prediction and the samples scored); convention, gains: how a recording file is read.
    rollout: window lengths [s] ("0.25,0.5" or numbers): the bodies of ``result`` (a consistent fit's
    ``standard``) rolled out in MuJoCo with this processing (identify.rollout.run.roll_out; the
    validation's ``rollout``); None: not.
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
    processing = Processing(cutoff=cutoff, decimate_to=None if at_prediction else decimate_to,
                            min_velocity=min_velocity, rest=predicted_rest(rest), delay=float(delay), spring=spring)
    scans, processing = scan_all([src], processing, block)
    fc = processing.cutoff
    if at_prediction:  # at 20 x the cut-off (or the recording's own rate), not at the fit's decimated rate
        processing = processing.chosen(decimate_to=prediction_rate(fc, scans[0].rate))
    filtered = (processing if filtered_at == "prediction"
                else processing.chosen(decimate_to=filtered_at))  # the fit's own rows
    plans, _ = plan_windows(scans[0], processing, block)
    names, regressor = column_regressor(robot, base)
    sticks = [m for m in (baseline, user_model) if m is not None]
    # The yardsticks' own pass over the log, block by block (their own filter and margins).
    preds = log_predictions(robot, sticks, src, scans[0], block) if sticks else []
    sums = FilteredSums(beta, robot.n) if filtered.decimate_to == processing.decimate_to else None
    length = {g.start: g.samples for g in scans[0].segments}
    groups: dict[int, list] = {}
    for plan, window, rec, _ in windows_in_order([src], [plans]):
        m = piece(robot, rec, window, plan, processing, regressor, names).motion
        if sums is not None:
            sums.add(m)
        pred = m.Phi @ beta
        if spring and robot.spring is not None:
            pred = pred - robot.spring_torque_batch(m.q)[:, :, 0]
        # The raw samples this core owns: from its first prediction to the next core's (scored on raw torques).
        t_pred, t = m.t + processing.delay, np.asarray(rec.t, dtype=float)
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
        at = [baseline_at(bp, t) for bp in preds]  # only where the yardsticks predict too
        for scored, _ in at:
            inside &= scored
        t, tau = t[inside], tau[inside]
        nearest = np.clip(np.searchsorted(tp, t - 0.5 * (tp[1] - tp[0] if tp.size > 1 else 0.0)), 0, tp.size - 1)
        parts.append((t, tau, onto(t, tp, pr), mv[nearest], *(b[inside] for _, b in at)))
    if not any(p[0].size for p in parts):
        raise ValueError(f"{src.source}: no recorded sample lies inside the prediction"
                         + (" and 0.5 s from the segments' ends (the yardsticks' trim)" if preds else ""))
    t, Y, pred, mov, *yard = (np.concatenate([p[k] for p in parts]) for k in range(4 + len(preds)))
    base_pred = yard.pop(0) if baseline is not None else None
    user_pred = yard.pop(0) if user_model is not None else None
    # The filtered figures on the fit's rows: from this pass when they are the prediction's, else a pass of their own.
    errors = (sums.result() if sums is not None else
              filtered_rms(robot, src, scans[0], filtered, block, regressor, names, beta))
    val = replace(scored_validation(RawScores(t, Y, pred, mov, base_pred, user_pred), src.source,
                                    processing.min_velocity, fc, plans[0].rate), **errors, t0_s=log_clock(recording, src),
                  user_model_note=user_model_note if user_model is None else "")
    if rollout is None:
        return val
    from identify.rollout.model import result_parameters
    from identify.rollout.run import roll_out

    model, params = result_parameters(robot, result)
    return replace(val, rollout=roll_out(model, params, src, rollout, cutoff=fc, delay=delay,
                                         min_velocity=min_velocity, block=block))


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
    b_all = b_mov = u_all = u_mov = None
    if raw.baseline is not None:
        b_err = Y - raw.baseline
        b_all, b_mov = _rms(b_err, every), _rms(b_err, moving)
    if raw.user is not None:
        u_err = Y - raw.user
        u_all, u_mov = _rms(u_err, every), _rms(u_err, moving)
    return Validation(
        relative_error_pct=_relative(err, Y, every), rms_error=_rms(err, every),
        measured=Y, predicted=predicted, t=raw.t, source=source,
        relative_error_pct_moving=_relative(err, Y, moving), rms_error_moving=_rms(err, moving),
        moving_fraction=moving.mean(axis=0), moving_threshold=min_velocity, moving=moving,
        cutoff=cutoff, rate=rate, baseline_rms_error=b_all, baseline_rms_error_moving=b_mov,
        baseline_predicted=raw.baseline, user_rms_error=u_all, user_rms_error_moving=u_mov, user_predicted=raw.user)


@one_blas_thread()
def validate(robot: rx90sym.Robot, result: IdentificationResult, recording: Any, **options: Any) -> Validation:
    """Cross-validation: torque error per joint on a recording not used in the fit (see :func:`predict`)."""
    return predict(robot, result, recording, **options)
