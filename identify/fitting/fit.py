"""One identification, from recordings to a saved fit file (paper sections II-B and III).

:func:`fit` chains the steps block by block for every log length (:mod:`identify.fitting.streamed`:
the processing chosen on the torques, the torque-delay estimate, the observation rows of one
:class:`~identify.observation.processing.Processing`, eqs. 6-8, folded into per-joint factors; the
friction columns; (weighted) least squares, eqs. 9-15; optionally the physically consistent fit;
the plain baseline and the recorded-torque checks) and returns a :class:`Fit` that predicts and
validates with its own processing, carries its bootstrap σ, and saves itself
(:mod:`identify.fitting.record`).
"""
from __future__ import annotations

from types import SimpleNamespace
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

import rx90sym
from rx90sym.threads import one_blas_thread

from identify.estimation.bootstrap import bootstrap_std
from identify.estimation.honest_covariance import HONEST_SEED, honest_covariance, needs_honest_covariance
from identify.estimation.results import METHODS, IdentificationResult
from identify.fitting.file import FitModel
from identify.io.gains import DriveGains
from identify.observation.matrix import Observation
from identify.observation.friction_model import FrictionBase
from identify.observation.offsets import OffsetBase, offset_joints
from rx90sym.base_parameters import BaseParameters
from identify.observation.processing import Processing, friction_label, has_policy, has_smooth_friction
from identify.fitting.record import BOOTSTRAP_BLOCK_S, BOOTSTRAP_DRAWS, Bootstrap, Fit
from identify.fitting.rank_flags import rank_flags

if TYPE_CHECKING:
    from identify.fitting.streamed import ProcessingChoice

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
        bootstrap_seed: int | None = 0, **consistent_options: Any) -> Fit:
    """Identify the base parameters of ``robot`` from ``recordings`` (recordings, or recording files).

    One pipeline for every log length: the recordings are read, filtered and fitted block by block
    (``block`` raw samples at a time, default 60,000: memory bounded by the block whatever the logs'
    length, docs/long-logs.md); a log within one block is one block, and the estimates do not depend on
    the block (to 1e-8 relative). client: a ``dask.distributed.Client`` running the blocks.

    processing: the signal processing (None: the defaults, those of ``rx90 identify``): without a
    cut-off it is chosen by blocked cross-validation against the raw torques (cut-off, decimation,
    rest policy per joint, torque offsets), the friction form per joint too where it is left open;
    method: "ols", "wls" (paper: each joint's rows weighted by 1/σ of its own residual) or
    "consistent" (WLS data, physically consistent standard parameters through cvxpy; extra
    keyword arguments go to identify.estimation.consistent_fit.consistent_fit, e.g.
    physical_prior (default "default": the robot's nominal parameters, as rx90 identify; a JSON
    parameter file; None: no prior; or a PhysicalPrior: the unseen directions from nominal parameters,
    within a covariance of the base parameters calibrated by the segment bootstrap) or
    consistent_least_squares' prior, prior_weight, total_mass, mass_bounds, com_boxes, solver);
    base: the columns (default: the symbolic base parameters, plus the torque offsets the
    cross-validated processing chooses; columns given are fitted as they are; a BaseWithSpring
    identifies the spring too, with processing.spring False). Recorded in the fit file for :func:`load_fit`:
    gains (applied to current recordings), convention (of the files; None: each file's header),
    spring_source ("default", "none" or a table file; None: from the robot).
    bootstrap_seed: seed of the segment bootstrap whose σ the fit carries beside eq. 13's, computed
    while the blocks stream by (as ``rx90 identify --bootstrap-seed``; None: none).
    observation: an already built observation matrix, solved as it is (the recordings are not read: no
    delay estimate, no baseline, no cross-validation).
    The fit keeps its decimated rows (``Fit.observation``) when they are few (identify.observation.row_store);
    its flags hold the recorded-torque checks (identify.fitting.torque_checks: torque scale, gravity at
    rest; errors that rx90 identify stops on) and a rank that depends on the threshold.
    Threads: the BLAS runs on one thread inside the call, as in ``rx90 identify`` (the least squares
    are tall and thin: a second thread spins more than it computes, the more so on a busy or
    many-core machine); the caller's count is back after the call, also when it raises. An
    environment variable naming the count (OPENBLAS_NUM_THREADS, OMP_NUM_THREADS, ...) or the
    caller's ``rx90sym.blas_threads(n)`` keeps the caller's count instead (:mod:`rx90sym.threads`).
    """
    if method not in METHODS:
        raise ValueError(f"fit: method must be one of {METHODS}, got {method!r}")
    if method == "consistent" and isinstance(consistent_options.get("physical_prior", "default"), str):
        from identify.estimation.consistency.prior import nominal_prior

        # The default prior is rx90 identify's: the robot's nominal parameters (None: said, arbitrary split).
        consistent_options["physical_prior"] = nominal_prior(robot, None if consistent_options.get(
            "physical_prior", "default") == "default" else consistent_options["physical_prior"])
    p = processing if processing is not None else Processing()
    _refuse_for_consistent(p, method)
    if method != "consistent" and consistent_options:
        raise ValueError(f"fit: options {sorted(consistent_options)} are for method 'consistent'")
    if observation is not None:
        return _fit_observation(robot, recordings, observation, p, method, base, gains, convention, spring_source,
                                bootstrap_seed, consistent_options)
    done = _fit_blocks(robot, recordings, p, method, base=base, gains=gains, convention=convention,
                       spring_source=spring_source, block=block, client=client, bootstrap_seed=bootstrap_seed,
                       **consistent_options)
    return done.with_flags([*rank_flags(done.base), *done.flags])  # a rank that depends on the threshold


def _fit_observation(robot: rx90sym.Robot, recordings: Sequence[Any], obs: Observation, p: Processing, method: str,
                     base: Any, gains: DriveGains | None, convention: str | None, spring_source: str | None,
                     bootstrap_seed: int | None, consistent_options: dict[str, Any]) -> Fit:
    """The fit of a given observation matrix (eqs. 9-15, optionally the consistent fit)."""
    from identify.observation.spring_fit import BaseWithSpring, spring_summary

    base = base if base is not None else rx90sym.base_parameters(robot)
    options = p.observation_options()
    result = _solve(robot, obs, base, method, consistent_options)
    model = FitModel.of(robot, convention=convention, gains=gains.to_dict() if gains is not None else None,
                        rest=options["rest"], min_velocity=options["min_velocity"],
                        spring=spring_source or _spring_label(robot, base), cutoff_hz=obs.cutoffs[0],
                        decimate_to_hz=options["decimate_to"], rate_hz=obs.rate,
                        delay_s=0.0 if p.delay == "auto" else float(p.delay), offset_joints=_offset_record(base))
    recordings = list(recordings) if isinstance(recordings, (list, tuple)) else [recordings]
    visited = [r for r in recordings if hasattr(r, "q")]
    spring = spring_summary(robot, base if isinstance(base, BaseWithSpring) else None, result, visited)[0]
    done = Fit(robot, result, p, model, base, obs, None, None, spring, flags=tuple(rank_flags(base)))
    return done if bootstrap_seed is None else done.bootstrapped(bootstrap_seed)


def _refuse_for_consistent(p: Processing, method: str) -> None:
    """The consistent method's standard parameters are what a URDF/MJCF holds: Coulomb (FS) and viscous (FV)
    friction; a smooth form or the presliding rest policy is refused (on either path)."""
    if method == "consistent" and (has_smooth_friction(p.friction) or has_policy(p.rest, "presliding")):
        what = " and ".join(([f"friction form {friction_label(p.friction)!r}"] if has_smooth_friction(p.friction) else [])
                            + (["rest policy 'presliding'"] if has_policy(p.rest, "presliding") else []))
        raise ValueError(f"fit: the consistent method fits bodies with Coulomb + viscous friction (what a URDF or "
                         f"MJCF holds), not {what}: use friction 'coulomb' and a rest policy other than "
                         f"'presliding', or method 'wls'")


def _offset_record(base: Any) -> tuple[int, ...] | None:
    """The joints (1-based) given a torque offset by the cross-validated choice (None: none)."""
    inner = base.base if isinstance(base, FrictionBase) else base
    return tuple(j + 1 for j in inner.joints) if isinstance(inner, OffsetBase) else None


def _honest_covariance(obs: Observation, result: IdentificationResult) -> np.ndarray:
    """Eq. 13's covariance inflated by the segment bootstrap (identify.estimation.honest_covariance): the
    budget of the prior fit is measured in it."""
    std = bootstrap_std(obs.W, obs.Y, obs.joint, obs.samples, result.weights, obs.rate, seed=HONEST_SEED)
    return honest_covariance(result, std)


def _solve(robot: rx90sym.Robot, obs: Observation, base: Any, method: str,
           consistent_options: dict[str, Any]) -> IdentificationResult:
    from identify.estimation.least_squares import weighted_least_squares

    result = weighted_least_squares(obs.W, obs.Y, obs.joint, obs.names, weighted=method != "ols")
    if method != "consistent":
        return result
    from identify.estimation.consistent_fit import consistent_fit

    if needs_honest_covariance(method, consistent_options):
        consistent_options = {**consistent_options, "covariance": _honest_covariance(obs, result)}
    return consistent_fit(robot, result, base, **consistent_options)


def _fit_blocks(robot: rx90sym.Robot, recordings: Sequence[Any], processing: Any = None, method: str = "wls", *,
                  base: Any = None, gains: Any = None, convention: str | None = None, spring_source: str | None = None,
                  block: int | None = None, client: Any = None, bootstrap_seed: int | None = 0,
                  **consistent_options: Any) -> Fit:
    """:func:`identify.fit` of recordings, block by block: its bootstrap computed on the way."""
    from identify.fitting.streamed import DEFAULT_BLOCK, BootstrapSpec, fit_streamed  # the block path's modules
    from identify.observation.spring_fit import BaseWithSpring, spring_summary
    from identify.io.blocks import block_source, check_block
    from identify.fitting.baseline_blocks import streamed_baseline
    from identify.fitting.torque_checks import streamed_torque_flags

    from identify.fitting.streamed_friction import FrictionHook

    p = processing if processing is not None else Processing()
    _refuse_for_consistent(p, method)
    smooth = has_smooth_friction(p.friction_form)
    block = DEFAULT_BLOCK if block is None else check_block(block)
    columns_given = base is not None
    # The form given, or chosen per joint by the cross-validation where left open (as in memory: not for the
    # consistent method, whose URDF holds Coulomb + viscous).
    choose = p.friction is None and p.cross_validates and method != "consistent"
    presliding = p.min_velocity is not None and has_policy(p.rest, "presliding")   # its travels searched too
    hook = FrictionHook(p.friction_form, choose) if smooth or choose or presliding else None
    base = base if base is not None else rx90sym.base_parameters(robot)
    recordings = list(recordings) if isinstance(recordings, (list, tuple)) else [recordings]
    spec = BootstrapSpec(BOOTSTRAP_BLOCK_S, BOOTSTRAP_DRAWS, bootstrap_seed) if bootstrap_seed is not None else None
    eligible = (offset_joints(robot, base) if method != "consistent" and not columns_given
                and isinstance(base, BaseParameters) else ())  # as the whole-signal fit's torque offsets
    sf = fit_streamed(robot, recordings, method, base, p.cutoff, p.decimate_to, p.min_velocity, p.rest, p.delay,
                      p.spring, p.estimate_delay, block, client, spec, convention, gains, p.cross_validates,
                      offsets=eligible, friction=hook, **consistent_options)
    base = sf.columns  # with the offsets and the friction columns chosen
    rest = sf.settings.rest  # the policy given, or chosen by the cross-validation
    model = FitModel.of(robot, convention=convention, gains=gains.to_dict() if gains is not None else None,
                        rest=rest, min_velocity=p.min_velocity, spring=spring_source or _spring_label(robot, base),
                        cutoff_hz=sf.cutoff, decimate_to_hz=sf.settings.decimate_to, rate_hz=sf.rate,
                        delay_s=sf.delay, friction=sf.friction, offset_joints=_offset_record(base))
    angles = [SimpleNamespace(q=sf.q_range)]  # what the spring summary reads: the range visited
    spring = spring_summary(robot, base if isinstance(base, BaseWithSpring) else None, sf.result, angles)[0]
    boot = Bootstrap(sf.bootstrap_std, sf.bootstrap_block / sf.rate, spec.draws, spec.seed) if spec else None
    found = sf.delay_estimate
    # The baseline and the recorded-torque checks: a pass each over the logs, block by block, as on whole ones.
    sources = [block_source(r, robot, convention, gains) for r in recordings]
    return Fit(robot, sf.result, p, model, base, sf.observation, found, found.delay if found is not None else None, spring,
               boot, block=block, streamed=sf, recordings=sf.recordings,
               choice=_choice_record(sf.choice, getattr(hook, "choice", None)),
               flags=tuple(streamed_torque_flags(robot, sources, sf.scans, block)),
               baseline=streamed_baseline(robot, sources, sf.scans, p.spring, block, client))


def _choice_record(choice: ProcessingChoice | None, friction: Any) -> dict | None:
    """The fit file's ``processing_choice`` of a block-by-block fit, as the in-memory fit's: the friction
    form's choice (a FrictionChoice, None when the form was given) after the processing's."""
    if choice is None:
        return None
    record = choice.to_dict()
    if friction is None:
        return record
    return dict(record, friction=friction.to_dict(), table=record["table"] + "\n" + friction.table())
