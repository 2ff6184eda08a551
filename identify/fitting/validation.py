"""Torque prediction and cross-validation on a motion not used for fitting (section III-B).

The prediction uses the filtering of the fit (cut-off, decimation: pass the values the fit used)
and, given a rest threshold, takes the Coulomb term as 0 where its joint (or motor) rests: at rest
the static friction lies anywhere in [−FS, FS] and the sign of a noisy speed says nothing. The
errors are reported on all samples and on the samples where each joint moves.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

import rx90sym

from identify.observation.matrix import automatic_cutoff, filtered_motions, presliding_base
from identify.observation.processing import RestPolicy, has_policy, predicted_rest
from identify.estimation.results import IdentificationResult, json_number
from identify.io.blocks import block_source
from identify.observation.matrix import column_regressor
from identify.observation.stream import DEFAULT_BLOCK, StreamSettings, piece, plan_windows, scan_all, windows_in_order

__all__ = ["Validation", "predict", "validate"]


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
    moving_fraction: (n,) share of samples where joint j moves; measured, predicted: (S, n)
    torques (spring added) at the decimated samples; t: (S,) their true time [s]; moving: (S, n).
    cutoff [Hz], rate [Hz]: the filtering used.
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

    def table(self) -> str:
        head = ("joint  rms error [N m]  relative error [%]  rms moving [N m]  relative moving [%]"
                "  moving [%]")
        n = len(self.rms_error)
        rel_m = self.relative_error_pct_moving if self.relative_error_pct_moving is not None else self.relative_error_pct
        rms_m = self.rms_error_moving if self.rms_error_moving is not None else self.rms_error
        frac = self.moving_fraction if self.moving_fraction is not None else np.ones(n)
        rows = [f"{j + 1:5d}  {self.rms_error[j]:15.3f}  {self.relative_error_pct[j]:18.2f}  "
                f"{rms_m[j]:16.3f}  {rel_m[j]:19.2f}  {100 * frac[j]:10.1f}" for j in range(n)]
        thr = ("no rest threshold" if self.moving_threshold is None
               else f"moving: |q̇j| ≥ {self.moving_threshold:g} rad/s")
        return "\n".join([f"Validation on {self.source} (cut-off {self.cutoff:.4g} Hz, rate {self.rate:.6g} Hz, "
                          f"{thr})", head, *rows])

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
                "cutoff_hz": json_number(self.cutoff), "rate_hz": json_number(self.rate)}


def base_vector(result: IdentificationResult, base: Any, robot: rx90sym.Robot) -> np.ndarray:
    """β over ``base.names`` from a result (parameters of the base set missing from it count as 0)."""
    unknown = [nm for nm in result.names if nm not in base.names]
    if unknown:
        raise ValueError(f"result has parameters {unknown} that are not base parameters of "
                         f"{robot.name!r}")
    values = dict(zip(result.names, result.values))
    return np.array([values.get(nm, 0.0) for nm in base.names])


def predict(robot: rx90sym.Robot, result: IdentificationResult, recording: Any, base: Any = None,
            cutoff: float | None = None, decimate_to: float | None = 50.0, spring: bool = True,
            min_velocity: float | None = None, delay: float = 0.0, rest: RestPolicy = "zero-coulomb") -> Validation:
    """Predicted vs measured torques of ``recording`` with the parameters of ``result``.

    cutoff [Hz], decimate_to [Hz]: give those of the fit (None: chosen on this recording);
    min_velocity [rad/s]: rest threshold (Coulomb term 0 at rest, errors also while moving);
    delay [s]: torque lag compensated as in the fit; rest: the fit's rest policy, one or one per joint
    (every sample is predicted: "drop" takes Coulomb 0 at rest; "presliding" the presliding state
    times FPj; the others as in the fit).
    """
    base = presliding_base(robot, base, rest if has_policy(rest, "presliding") and min_velocity is not None else None)
    beta = base_vector(result, base, robot)
    cutoff = cutoff if cutoff is not None else automatic_cutoff([recording], decimate_to)
    motions, _, _ = filtered_motions(robot, [recording], cutoff, decimate_to, spring, base.regressor_batch,
                                     base.names, min_velocity,
                                     predicted_rest(rest), delay)
    # Samples bridged over lost packets are no measurements: they are not scored.
    rows = [m.measured if m.measured is not None else slice(None) for m in motions]
    Y = np.concatenate([m.Y[r] for m, r in zip(motions, rows)])
    predicted = np.concatenate([(m.Phi @ beta)[r] for m, r in zip(motions, rows)])
    moving = np.concatenate([m.moving[r] for m, r in zip(motions, rows)])
    err = Y - predicted
    every = np.ones_like(moving)
    return Validation(
        relative_error_pct=_relative(err, Y, every), rms_error=_rms(err, every),
        measured=Y, predicted=predicted, t=np.concatenate([m.t[r] for m, r in zip(motions, rows)]),
        source=recording.source,
        relative_error_pct_moving=_relative(err, Y, moving), rms_error_moving=_rms(err, moving),
        moving_fraction=moving.mean(axis=0), moving_threshold=min_velocity, moving=moving,
        cutoff=motions[0].cutoff, rate=motions[0].rate)


def validate(robot: rx90sym.Robot, result: IdentificationResult, recording: Any, **options: Any) -> Validation:
    """Cross-validation: torque error per joint on a recording not used in the fit (see :func:`predict`)."""
    return predict(robot, result, recording, **options)


def predict_streamed(robot: rx90sym.Robot, result: IdentificationResult, recording: Any, base: Any = None,
                     cutoff: float | None = None, decimate_to: float | None = 50.0, spring: bool = True,
                     min_velocity: float | None = None, delay: float = 0.0, block: int = DEFAULT_BLOCK,
                     convention: str | None = None, gains: Any = None, rest: RestPolicy = "zero-coulomb") -> Validation:
    """:func:`identify.predict` on a recording of any length: predicted and measured torques block by block
    (only the decimated torques are held, n columns at the decimated rate)."""
    base = presliding_base(robot, base, rest if min_velocity else None)
    beta = base_vector(result, base, robot)
    src = block_source(recording, robot, convention, gains)
    # As identify.predict: every sample predicted (a dropped joint's rest with Coulomb 0).
    settings = StreamSettings(cutoff, decimate_to or None, min_velocity or None, predicted_rest(rest), float(delay),
                              spring, int(block))
    scans, fc = scan_all([src], settings)
    plans, _ = plan_windows(scans[0], fc, settings)
    names, regressor = column_regressor(robot, base)
    parts = []
    for plan, window, rec, _ in windows_in_order([src], [plans]):
        m = piece(robot, rec, window, plan, fc, settings, regressor, names, 0).motion
        rows = m.measured if m.measured is not None else slice(None)  # as identify.predict: measured samples
        parts.append((m.Y[rows], (m.Phi @ beta)[rows], m.t[rows], m.moving[rows]))
    Y, pred, t, mov = (np.concatenate(a) for a in zip(*parts))
    err = Y - pred
    every = np.ones_like(mov)
    return Validation(
        relative_error_pct=_relative(err, Y, every), rms_error=_rms(err, every), measured=Y, predicted=pred, t=t,
        source=src.source, relative_error_pct_moving=_relative(err, Y, mov), rms_error_moving=_rms(err, mov),
        moving_fraction=mov.mean(axis=0), moving_threshold=settings.min_velocity, moving=mov, cutoff=fc,
        rate=plans[0].rate)
