"""One identification, from recordings to a saved fit file (paper sections II-B and III).

:func:`fit` chains the steps block by block for every log length (:mod:`identify.fitting.passes`:
the processing chosen on the torques, the torque-delay estimate, the observation rows of one
:class:`~identify.observation.processing.Processing`, eqs. 6-8, folded into per-joint factors; the
friction columns; (weighted) least squares, eqs. 9-15; optionally the physically consistent fit;
the two yardsticks and the recorded-torque checks) and returns a :class:`Fit` that predicts and
validates with its own processing, carries its bootstrap σ, and saves itself
(:mod:`identify.fitting.fit_result`).
"""
from __future__ import annotations

import math
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

import rx90sym
from rx90sym.threads import one_blas_thread

from identify.estimation.consistency.body_prior import DEFAULT_DIVERGENCE, BodyPrior, body_prior
from identify.fitting.consistent_fit import check_prior_weight
from identify.estimation.results import METHODS, IdentificationResult
from identify.fitting.fit_file import FitModel
from identify.io.gains import DriveGains
from identify.observation.matrix import Observation
from identify.friction.columns import inner_columns
from identify.observation.offsets import OffsetBase, offset_joints
from rx90sym.base_parameters import BaseParameters
from identify.observation.processing import Processing, has_policy, has_smooth_friction
from identify.fitting.fit_result import BOOTSTRAP_BLOCK_S, BOOTSTRAP_DRAWS, Bootstrap, Fit
from identify.fitting.rank_flags import column_flags, rank_flags

if TYPE_CHECKING:
    from identify.fitting.passes import Passes
    from identify.fitting.plausibility import Flag
    from identify.selection.candidates import ProcessingChoice

__all__ = ["fit"]


def _spring_label(robot: rx90sym.Robot, base: Any) -> str:
    from identify.observation.spring_fit import BaseWithSpring

    if isinstance(base, BaseWithSpring):
        return "identify-k" if type(base.model).__name__ == "SpringStiffness" else "identify"
    return "none" if robot.spring is None else "default"


@one_blas_thread()
def fit(robot: rx90sym.Robot, recordings: Sequence[Any], processing: Processing | None = None,
        method: str = "wls", *, base: Any = None, gains: DriveGains | None = None,
        convention: str | None = None, spring_source: str | None = None,
        observation: Observation | None = None, block: int | None = None, client: Any = None,
        bootstrap_seed: int | None = 0, physical_prior: Any = "description", prior_weight: float | str = "auto",
        divergence: str = DEFAULT_DIVERGENCE, **bounds: Any) -> Fit:
    """Identify the base parameters of ``robot`` from ``recordings`` (recordings, or recording files),
    and the physically consistent model weighed between the robot's description and the data.

    One pipeline for every log length: the recordings are read, filtered and fitted block by block
    (``block`` raw samples at a time, default 60,000: memory bounded by the block whatever the logs'
    length, docs/long-logs.md); a log within one block is one block, and the estimates do not depend on
    the block (to 1e-8 relative). client: a ``dask.distributed.Client`` running the blocks.

    processing: the signal processing (None: the defaults, those of ``rx90 identify``): without a
    cut-off it is chosen by blocked cross-validation against the raw torques (cut-off, decimation,
    rest policy per joint, torque offsets), the friction form per joint too where it is left open;
    method: "ols" or "wls" (paper: each joint's rows weighted by 1/σ of its own residual): ``Fit.result``
    holds those estimates with eq. 13's σ; "consistent": ``Fit.result`` is the identified model itself.
    Every fit carries the identified model (``Fit.identified``, :mod:`identify.fitting.consistent_fit`):
    physically consistent standard parameters minimising the weighted residual plus λ·D(θ ‖ θ₀), θ₀ the
    prior's bodies: it is what :meth:`Fit.predict`, the exports, the monitor and the payload methods use.
    physical_prior: "description" (the robot's URDF inertials or robot-file [nominal] bodies; a link
    whose inertials are not physical gets no prior), "none" (the data alone), a JSON parameter file, a
    name -> value mapping, or a :class:`~identify.estimation.consistency.body_prior.BodyPrior`;
    prior_weight: λ ≥ 0 (math.inf: the description's bodies, the drives fitted) or "auto": chosen by
    blocked cross-validation against the raw torques; divergence: D, "gaussian" or "entropic"
    (:mod:`identify.estimation.consistency.body_prior`); bounds: ``mass_bounds``, ``total_mass``,
    ``com_boxes`` (kg, m; :func:`identify.estimation.consistency.consistent_least_squares`) and ``solver``.
    base: the columns (default: the symbolic base parameters, plus the torque offsets the
    cross-validated processing chooses; columns given are fitted as they are; a BaseWithSpring
    identifies the spring too, with processing.spring False). Recorded in the fit file for :func:`load_fit`:
    gains (applied to current recordings), convention (of the files; None: each file's header),
    spring_source ("default", "none" or a table file; None: from the robot).
    bootstrap_seed: seed of the segment bootstrap whose σ the fit carries beside eq. 13's, computed
    while the blocks stream by (as ``rx90 identify --bootstrap-seed``; None: none).
    observation: an already built observation matrix, solved as it is (the recordings are not read: no
    delay estimate, no baseline, no cross-validation; the prior weight is then chosen on the
    observation's own filtered torques).
    The fit keeps its decimated rows (``Fit.observation``) when they are few (identify.observation.row_store);
    its flags hold the recorded-torque checks (identify.fitting.torque_checks: torque scale, gravity at
    rest, errors that rx90 identify stops on; the torques' sign against the description's inverse dynamics,
    a warning) and a rank that depends on the threshold.
    The fit never stops on its own rows: columns they cannot separate are left out or merged
    (identify.estimation.dependent_columns; flags column_left_out, columns_merged; ``result.holds``),
    a joint whose torque holds one value on every sample of a recording (not logged) is left out
    (flag torque_not_logged, ``model.torque_left_out``: not predicted), a recording too short for the
    cross-validation's blocks gets the fixed defaults (``choice["skipped"]`` says why), a torque delay
    at the search bound is not applied. An error raised once the processing is chosen carries the
    choice as its attribute ``processing_choice`` (its ``table()``).
    Threads: the BLAS runs on one thread inside the call, as in ``rx90 identify`` (the least squares
    are tall and thin: a second thread spins more than it computes, the more so on a busy or
    many-core machine); the caller's count is back after the call, also when it raises. An
    environment variable naming the count (OPENBLAS_NUM_THREADS, OMP_NUM_THREADS, ...) or the
    caller's ``rx90sym.blas_threads(n)`` keeps the caller's count instead (:mod:`rx90sym.threads`).
    """
    if method not in METHODS:
        raise ValueError(f"fit: method must be one of {METHODS}, got {method!r}")
    unknown = sorted(set(bounds) - {"mass_bounds", "total_mass", "com_boxes", "solver"})
    if unknown:
        raise TypeError(f"fit: unknown options {unknown} (the model's bounds: mass_bounds, total_mass, com_boxes, "
                        f"solver)")
    prior = model_prior(robot, physical_prior, divergence)
    check_prior_weight(prior_weight)
    options = {"prior": prior, "prior_weight": prior_weight, **bounds}
    processing = processing if processing is not None else Processing()
    if observation is not None:
        return _fit_observation(robot, recordings, observation, processing, method, base, gains, convention,
                                spring_source, bootstrap_seed, options)
    done = _fit_blocks(robot, recordings, processing, method, base=base, gains=gains, convention=convention,
                       spring_source=spring_source, block=block, client=client, bootstrap_seed=bootstrap_seed,
                       options=options)
    return done.with_flags([*rank_flags(done.base), *done.flags])  # a rank that depends on the threshold


def model_prior(robot: rx90sym.Robot, physical_prior: Any, divergence: str = DEFAULT_DIVERGENCE) -> BodyPrior | None:
    """The :class:`BodyPrior` of ``physical_prior`` (see :func:`fit`); None for "none", or for
    "description" when the description has no bodies."""
    if isinstance(physical_prior, BodyPrior):
        return physical_prior if physical_prior.divergence == divergence else physical_prior.with_divergence(divergence)
    if physical_prior is None or (isinstance(physical_prior, str) and physical_prior == "none"):
        return None
    from rx90sym.urdf_carried import carried_bodies

    carried = {link: body for link, (body, _) in carried_bodies(robot).items()}
    if isinstance(physical_prior, str) and physical_prior == "description":
        from rx90sym.description_prior import description_prior

        described = description_prior(robot)
        if described is None:
            return None
        return body_prior(described.values, robot.n, described.source, divergence, described.notes, carried)
    values = rx90sym.nominal_parameters(robot, physical_prior)
    label = str(physical_prior) if not isinstance(physical_prior, dict) else "given parameters"
    return body_prior(values, robot.n, label, divergence, carried=carried)


def _fit_observation(robot: rx90sym.Robot, recordings: Sequence[Any], obs: Observation, p: Processing, method: str,
                     base: Any, gains: DriveGains | None, convention: str | None, spring_source: str | None,
                     bootstrap_seed: int | None, options: dict[str, Any]) -> Fit:
    """The fit of a given observation matrix (eqs. 9-15 and the identified model)."""
    from identify.estimation.least_squares import weighted_least_squares
    from identify.selection.prior_weight import observation_folds
    from identify.observation.spring_fit import BaseWithSpring, spring_summary

    base = base if base is not None else rx90sym.base_parameters(robot)
    popts = p.observation_options()
    wls = weighted_least_squares(obs.W, obs.Y, obs.joint, obs.names, weighted=method != "ols")
    identified = _identified(robot, wls, base, observation_folds(obs), options, given=True)
    result = identified if method == "consistent" else wls
    model = FitModel.of(robot, convention=convention, gains=gains.to_dict() if gains is not None else None,
                        rest=popts["rest"], min_velocity=popts["min_velocity"],
                        spring=spring_source or _spring_label(robot, base), cutoff_hz=obs.cutoffs[0],
                        decimate_to_hz=popts["decimate_to"], rate_hz=obs.rate,
                        delay_s=0.0 if p.delay == "auto" else float(p.delay), offset_joints=_offset_record(base))
    recordings = list(recordings) if isinstance(recordings, (list, tuple)) else [recordings]
    visited = [r for r in recordings if hasattr(r, "q")]
    spring = spring_summary(robot, base if isinstance(base, BaseWithSpring) else None, result, visited)[0]
    done = Fit(robot, result, p, model, base, obs, None, None, spring, flags=tuple(rank_flags(base)),
               identified=identified, ls_result=wls if result is not wls else None)
    return done if bootstrap_seed is None else done.bootstrapped(bootstrap_seed)


def _identified(robot: rx90sym.Robot, wls: IdentificationResult, columns: Any, factors: Any,
                options: dict[str, Any], given: bool = False, spread: np.ndarray | None = None,
                moving: np.ndarray | None = None) -> Any:
    """The identified model of the least-squares fit ``wls`` (identify.fitting.consistent_fit), fitted
    on ``factors`` with a torque offset on every joint that may have one (as the description's model:
    the prior's bodies with each joint's friction and offset fitted), unless the columns were ``given``."""
    from identify.fitting.consistent_fit import consistent_fit

    bounds = {k: options[k] for k in ("mass_bounds", "total_mass", "com_boxes") if options.get(k) is not None}
    reference = {f"IA{j + 1}": v for j in range(robot.n) if (v := _description_value(robot, f"IA{j + 1}"))}
    offsets = [] if given else [j for j in offset_joints(robot, rx90sym.base_parameters(robot))
                                if f"OFF{j + 1}" not in columns.names]
    still = () if moving is None else tuple(int(j) for j in np.flatnonzero(np.asarray(moving) == 0))
    return consistent_fit(robot, wls, columns, options["prior"], options["prior_weight"], factors, offsets=offsets,
                          solver=options.get("solver", "CLARABEL"), bounds=bounds or None, reference=reference,
                          spread=spread, still=still, weight_why=options.get("weight_why"))


def _description_value(robot: rx90sym.Robot, name: str) -> float:
    """A standard parameter of the robot's description (0 where it has none)."""
    try:
        values = rx90sym.nominal_parameters(robot)
    except ValueError:
        return 0.0
    return float((values or {}).get(name, 0.0))


def _offset_record(base: Any) -> tuple[int, ...] | None:
    """The joints (1-based) given a torque offset by the cross-validated choice (None: none)."""
    inner = inner_columns(base)
    return tuple(j + 1 for j in inner.joints) if isinstance(inner, OffsetBase) else None


def _fit_blocks(robot: rx90sym.Robot, recordings: Sequence[Any], processing: Processing, method: str = "wls", *,
                base: Any = None, gains: Any = None, convention: str | None = None, spring_source: str | None = None,
                block: int | None = None, client: Any = None, bootstrap_seed: int | None = 0,
                options: dict[str, Any]) -> Fit:
    """:func:`identify.fit` of recordings, block by block: its bootstrap computed on the way."""
    from identify.friction.fitted_columns import FrictionHook
    from identify.fitting.passes import BootstrapSpec, run_passes
    from identify.fitting.yardsticks import log_yardsticks
    from identify.io.blocks import DEFAULT_BLOCK, block_source, check_block
    from identify.observation.spring_fit import BaseWithSpring, spring_summary

    block = DEFAULT_BLOCK if block is None else check_block(block)
    recordings = list(recordings) if isinstance(recordings, (list, tuple)) else [recordings]
    sources = [block_source(r, robot, convention, gains) for r in recordings]
    if gains is not None and sources and not any(s.holds_current for s in sources):
        raise ValueError(f"drive gains given, but no recording holds motor currents "
                         f"({', '.join(s.source for s in sources)}: joint torques): the gains would not be used")
    columns_given = base is not None
    # The form given, or chosen per joint by the cross-validation where left open.
    choose = processing.friction is None and processing.cross_validates
    presliding = processing.min_velocity is not None and has_policy(processing.rest, "presliding")   # its travels searched too
    smooth = has_smooth_friction(processing.friction_form)
    hook = FrictionHook(processing.friction_form, choose) if smooth or choose or presliding else None
    base = base if base is not None else rx90sym.base_parameters(robot)
    spec = BootstrapSpec(BOOTSTRAP_BLOCK_S, BOOTSTRAP_DRAWS, bootstrap_seed) if bootstrap_seed is not None else None
    eligible = (offset_joints(robot, base) if not columns_given
                and isinstance(base, BaseParameters) else ())  # as the whole-signal fit's torque offsets
    passes = run_passes(robot, sources, processing, method, base, block=block, client=client, bootstrap=spec, offsets=eligible,
                        friction=hook)
    base = passes.columns  # with the offsets and the friction columns chosen
    used = passes.processing  # the cut-off, decimation, rest policy per joint and delay given or chosen
    span = _model_span(passes)
    skipped = passes.choice.skipped if passes.choice is not None else None
    if skipped and options["prior_weight"] == "auto":  # too short for the blocks: the description kept (docs)
        options = {**options, "prior_weight": math.inf,
                   "weight_why": "λ inf: not cross-validated, as the processing (the description kept)"}
    identified = _identified(robot, passes.result, base, _model_factors(robot, sources, passes, span, client), options,
                             given=columns_given, spread=passes.bootstrap_std, moving=passes.moving_fraction)
    result = identified if method == "consistent" else passes.result
    model = FitModel.of(robot, convention=convention, gains=gains.to_dict() if gains is not None else None,
                        rest=used.rest, min_velocity=processing.min_velocity, spring=spring_source or _spring_label(robot, base),
                        cutoff_hz=passes.cutoff, decimate_to_hz=used.decimate_to, rate_hz=passes.rate,
                        delay_s=passes.delay, friction=passes.friction, offset_joints=_offset_record(base),
                        torque_left_out=tuple(j + 1 for j in passes.left_out) or None)
    angles = [SimpleNamespace(q=passes.q_range)]  # what the spring summary reads: the range visited
    spring = spring_summary(robot, base if isinstance(base, BaseWithSpring) else None, result, angles)[0]
    boot = (Bootstrap(passes.bootstrap_std, passes.bootstrap_block / passes.rate, spec.draws, spec.seed,
                      tuple(passes.result.names)) if spec else None)
    found = passes.delay_estimate
    # The yardsticks and the recorded-torque checks: a pass each over the logs, block by block, as on whole ones.
    sticks = log_yardsticks(robot, sources, passes.scans, processing.spring, block, client, span)
    return Fit(robot, result, processing, model, base, passes.observation, found,
               found.delay if found is not None and found.found else None, spring,
               boot, block=block, passes=passes, recordings=passes.recordings,
               choice=_choice_record(passes.choice, getattr(hook, "choice", None)),
               flags=(_flags(robot, sources, passes, block, base, bool(processing.spring))
                      + tuple(model_flags(identified, sticks.folds, robot))),
               baseline=sticks.plain, user_model=sticks.user, user_model_note=sticks.user_note,
               identified=identified, ls_result=passes.result if result is not passes.result else None)


def _model_span(passes: Passes) -> Any:
    """The time blocks of the identified model's cross-validation and of the yardsticks' held-out errors:
    the fit's own processing (its cut-off's filter edges, its decimation and delay from each segment's
    ends), :data:`identify.selection.cross_validation.DEFAULT_BLOCKS` of them."""
    from identify.selection.candidates import Candidate
    from identify.selection.cross_validation import DEFAULT_BLOCKS
    from identify.selection.raw_torque_scores import raw_span

    return raw_span(passes.scans, [Candidate(passes.cutoff, passes.processing.decimate_to)], DEFAULT_BLOCKS,
                    passes.delay)


def _model_factors(robot: rx90sym.Robot, sources: Sequence[Any], passes: Passes, span: Any, client: Any) -> Any:
    """The per-(time block, joint) factors of the fit's own columns and processing, at the rate the fit
    predicts at (identify.fitting.validation.prediction_rate: a held-back block is predicted as
    :meth:`Fit.predict` predicts, not interpolated from the decimated rows), and of the raw samples they
    predict: what the identified model is fitted and its prior weight cross-validated on (one pass)."""
    from identify.fitting.validation import prediction_rate
    from identify.selection.processing_choice import column_factors

    rate = min(s.rate for s in passes.scans)
    processing = passes.processing.chosen(decimate_to=prediction_rate(passes.cutoff, rate))
    return column_factors(robot, sources, passes.scans, passes.columns, processing, span, passes.block,
                          passes.left_out, client)


def model_flags(model: Any, folds: Any, robot: rx90sym.Robot) -> list:
    """The identified model's held-back errors against the yardstick's on the same time blocks
    (identify.fitting.plausibility.heldout_flags): the model the user had, or the plain OLS where the
    description has no bodies; none without held-back errors."""
    from identify.fitting.plausibility import heldout_flags, judged_joints

    if model is None or model.heldout is None or folds is None:
        return []
    kind, name = ("user", "the model the user had") if "user" in folds.err2 else ("plain", "the plain OLS")
    _, per_joint, per_block = folds.scores(kind)
    nan = lambda rows: [[float("nan") if v is None else v for v in row] for row in rows]  # noqa: E731 (null in JSON)
    judged = judged_joints(nan([model.heldout["torque_rms"]])[0], robot.limits.tau_max)
    return heldout_flags(nan([model.heldout["per_joint_pct"]])[0], nan(model.heldout["per_block_pct"]), per_joint,
                         per_block, name, judged)


def _flags(robot: rx90sym.Robot, sources: Sequence[Any], passes: Passes, block: int, base: Any,
           spring_added: bool) -> tuple[Flag, ...]:
    """The flags of a fit in blocks: the joints whose torque was left out (constant: not logged), the columns
    left out or merged, the recorded-torque checks and the torques' sign (of the joints fitted)."""
    from identify.fitting.torque_checks import not_logged_flags, log_torque_flags, torque_sign_flags

    left = passes.left_out
    checks = [f for f in (log_torque_flags(robot, sources, passes.scans, block)
                          + torque_sign_flags(robot, passes.result, base, spring_added=spring_added))
              if f.joint is None or f.joint - 1 not in left]
    return (*not_logged_flags(passes.scans, left), *column_flags(passes.reduction, [j + 1 for j in left]), *checks)


def _choice_record(choice: ProcessingChoice | None, friction: Any) -> dict | None:
    """The fit file's ``processing_choice`` of a block-by-block fit, as the in-memory fit's: the friction
    form's choice (a FrictionChoice, None when the form was given) after the processing's."""
    if choice is None:
        return None
    record = choice.to_dict()
    if friction is None:
        return record
    return dict(record, friction=friction.to_dict(), table=record["table"] + "\n" + friction.table())
