"""``rx90 identify``: base parameters from recordings (WLS, OLS) and the identified model weighed between
the robot's description and the data, validation, report.

The options make one :class:`identify.Processing` (its defaults are the library's), the library's
:func:`identify.fit` does the work and ``--json`` writes its fit file (:meth:`identify.Fit.save`):
one filtering for fit and validation, reused by ``rx90 predict`` through :func:`identify.load_fit`.
"""
from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING, Any

from identify.io.defaults import DEFAULT_BLOCK
from identify.estimation.defaults import DEFAULT_DIVERGENCE, DIVERGENCES
from identify.observation.defaults import (DEFAULT_DECIMATE_TO, DEFAULT_DELAY, DEFAULT_MIN_VELOCITY, DEFAULT_REST,
                                           FRICTION_FORMS, REST_POLICIES)

from ..flags import given_gain_flags, settle, with_hint
from ..common import (UsageError, check_output, convention_option, progress, robot_option, robot_with_spring,
                      spring_options)

from .identify_runs import block_option, fit_recordings, rollout_option

if TYPE_CHECKING:  # the model and the method are imported when the command runs, not for its --help
    import rx90sym
    from identify.fitting.fit_result import Fit
    from identify.observation.processing import Processing


def _auto_or_number(option: str, text: str, what: str, ok: Any, bound: str) -> str | float:
    """An option taking 'auto' or a number ``what``, refused with ``bound`` when not ``ok(value)``."""
    if text == "auto":
        return text
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{option} takes 'auto' or {what}, got {text!r}") from None
    if not ok(value):
        raise argparse.ArgumentTypeError(f"{option} must be {bound}, got {text!r}")
    return value


def _prior_weight(text: str) -> str | float:
    return _auto_or_number("--prior-weight", text, "a number >= 0 ('inf' allowed)", lambda v: v >= 0,
                           ">= 0 ('inf' allowed)")


def _delay(text: str) -> str | float:
    return _auto_or_number("--delay", text, "a number of seconds", lambda v: math.isfinite(v) and abs(v) <= 1.0,
                           "a finite number of seconds within ±1")


def add_recording_options(sp: argparse.ArgumentParser) -> None:
    """--convention and --gains: how the files are read (shared with ``predict``)."""
    convention_option(sp)
    sp.add_argument("--gains", help="drive gains for current recordings: K1,...,Kn [N m/A, joint side] "
                                    "or the JSON of rx90 gains")


def register(sub: Any) -> None:
    sp = sub.add_parser("identify", help="identify the base parameters from recordings",
                        description="identify the base parameters from recordings")
    sp.set_defaults(func=run)
    sp.add_argument("recordings", nargs="+", help="recording CSV files")
    robot_option(sp, None, "the robot the recordings' '# robot:' line names")
    add_recording_options(sp)
    spring_options(sp)
    sp.add_argument("--offsets", action="store_true", help="add per-joint torque offsets OFF1..OFFn")
    sp.add_argument("--coulomb-sign", choices=("paper", "motor"),
                    help="Coulomb form of the coupled wrist for this run (default: the robot file's)")
    sp.add_argument("--asymmetric-coulomb", metavar="JOINTS",
                    help="FS+ / FS- instead of FS on these joints: 'all', 'none' or e.g. 1,2,3 "
                         "(default: the robot file's [friction]); not with --offsets (collinear)")
    sp.add_argument("--method", choices=("ols", "wls", "consistent"), default="wls",
                    help="the estimates printed and saved as the fit's result: the paper's weighted (wls, default) "
                         "or ordinary (ols) least squares with eq. 13's sigma, or the identified model itself "
                         "(consistent). Every fit also carries the identified model (physically consistent bodies "
                         "weighed between the prior and the data), which predicts, exports and monitors")
    sp.add_argument("--prior", metavar="description|none|FILE",
                    help="the identified model's prior: 'description' (the default: the robot's URDF inertials or "
                         "robot-file [nominal] bodies; a link whose inertials are not physical gets its nearest "
                         "physical body), 'none' (the data alone), or FILE (a JSON parameter file)")
    sp.add_argument("--prior-weight", type=_prior_weight, default="auto", metavar="auto|VALUE",
                    help="the prior's weight λ >= 0 ('inf': the prior's bodies with the drives fitted; 0: the data "
                         "alone); 'auto' (default): chosen by blocked cross-validation against the raw torques")
    sp.add_argument("--divergence", choices=DIVERGENCES, default=DEFAULT_DIVERGENCE,
                    help=f"how the model's bodies are weighed against the prior's (default {DEFAULT_DIVERGENCE}: "
                         f"per-link scaled Gaussian; entropic: the log-det divergence of the pseudo-inertias)")
    sp.add_argument("--essential", action="store_true", help="also compute the essential parameters")
    sp.add_argument("--cutoff", type=float, help="Butterworth cut-off for q [Hz] (default: chosen on the torques "
                                                 "by cross-validation; a given cut-off turns it off)")
    sp.add_argument("--cross-validate", action=argparse.BooleanOptionalAction, default=None,
                    help="choose the cut-off, the decimation and (without --rest) the rest policy per joint on "
                         "the torques by blocked cross-validation (a small grid around the position knee, capped "
                         "by the rows processed, never the clock; the candidate table is printed and saved). Default: on without --cutoff; "
                         "--no-cross-validate: the position-spectrum cut-off and --decimate-to")
    sp.add_argument("--decimate-to", type=float, default=DEFAULT_DECIMATE_TO,
                    help=f"rate after parallel filtering [Hz] (default {DEFAULT_DECIMATE_TO:g}; 0: no decimation)")
    sp.add_argument("--no-decimate", action="store_true", help="no decimation (same as --decimate-to 0)")
    sp.add_argument("--min-velocity", type=float, default=DEFAULT_MIN_VELOCITY,
                    help=f"rest threshold: a joint slower than this is at rest [rad/s] "
                         f"(default {DEFAULT_MIN_VELOCITY:g}; 0: no rest handling)")
    sp.add_argument("--rest", type=_rest_option, default=None,
                    help=f"rest samples: drop their rows, keep them with Coulomb = 0, with the presliding "
                         f"state of the position history, or as they are ({', '.join(REST_POLICIES)}); one, "
                         f"or one per joint separated by commas (default: chosen per joint by the "
                         f"cross-validation, else {DEFAULT_REST})")
    sp.add_argument("--friction", type=_friction_option, default=None,
                    help=f"friction while moving: Coulomb sign(q̇), smooth tanh(q̇/vs) or Stribeck "
                         f"({', '.join(FRICTION_FORMS)}), the velocity scale vs per joint found by separable least "
                         f"squares; one, or one per joint separated by commas (default: coulomb or tanh chosen per "
                         f"joint by the cross-validation, coulomb unless clearly beaten on that joint; without "
                         f"cross-validation coulomb)")
    sp.add_argument("--delay", type=_delay, default=DEFAULT_DELAY,
                    help=f"torque lag behind the positions: 'auto' (estimated) or seconds (default {DEFAULT_DELAY:g}; "
                         f"the estimate is always reported)")
    sp.add_argument("--block", type=block_option, default=DEFAULT_BLOCK,
                    help=f"samples read, filtered and fitted at a time, at least 1000: memory bounded by the block "
                         f"whatever the logs' length, the estimates the same to 1e-8 whatever the block "
                         f"(default {DEFAULT_BLOCK})")
    sp.add_argument("--scheduler", metavar="ADDR|local",
                    help="fit the blocks on Dask: a scheduler address (tcp://host:8786) or 'local' "
                         "(a local cluster, one worker per core)")
    sp.add_argument("--bootstrap-seed", type=int, default=0, help="seed of the segment bootstrap (default 0)")
    sp.add_argument("--validate", help="recording used for cross-validation only")
    rollout_option(sp, "the --validate recording (the fit's identified model, as rx90 export --mjcf writes it)")
    sp.add_argument("--json", help="results as JSON")
    sp.add_argument("--report", help="self-contained HTML report")
    sp.add_argument("--urdf-out", help="the URDF with the identified model's inertials and joint dynamics, and "
                                       "FILE.actuation.json (as rx90 export --urdf)")


def _robot(args: argparse.Namespace) -> tuple[rx90sym.Robot, Any]:
    import rx90sym

    robot, spring_model = robot_with_spring(args, args.recordings)
    if args.coulomb_sign is not None:
        if robot.coupling is None:
            raise UsageError(f"--coulomb-sign: robot {robot.name!r} has no coupled joints")
        robot = robot.with_options(coupling=rx90sym.Coupling(robot.coupling.joints, args.coulomb_sign))
    if args.asymmetric_coulomb is not None:
        robot = with_asymmetric_coulomb(robot, args.asymmetric_coulomb)
    return robot, spring_model


def with_asymmetric_coulomb(robot: rx90sym.Robot, spec: str) -> rx90sym.Robot:
    """The robot with FS+ / FS- on the joints of ``spec`` ('all', 'none' or '1,2,...')."""
    text = spec.strip().lower()
    if text == "all":
        joints = tuple(range(robot.n))
    elif text == "none":
        joints = ()
    else:
        try:
            joints = tuple(int(c) - 1 for c in text.split(","))
        except ValueError:
            raise UsageError(f"--asymmetric-coulomb: expected 'all', 'none' or joint numbers like 1,2,3, "
                             f"got {spec!r}") from None
    try:
        return robot.with_options(asymmetric_coulomb=joints)
    except ValueError as exc:
        raise UsageError(f"--asymmetric-coulomb: {exc}") from None


def _check(args: argparse.Namespace) -> None:
    if args.essential and args.method == "consistent":
        raise UsageError("conflicting options: --essential works on the ols/wls estimate, "
                         "not with --method consistent")
    if args.no_decimate and args.decimate_to not in (DEFAULT_DECIMATE_TO, 0.0):
        raise UsageError("conflicting options: --no-decimate and --decimate-to "
                         f"{args.decimate_to:g}")
    if args.cross_validate and args.cutoff is not None:
        raise UsageError(f"conflicting options: --cutoff {args.cutoff:g} and --cross-validate (which chooses "
                         "the cut-off): give one of them")
    if args.min_velocity < 0:
        raise UsageError(f"--min-velocity must be >= 0 rad/s, got {args.min_velocity:g}")
    if args.min_velocity == 0 and args.rest is not None:
        rest = ",".join(args.rest) if isinstance(args.rest, tuple) else args.rest
        raise UsageError(f"conflicting options: --rest {rest} and --min-velocity 0 (no rest threshold: every row "
                         f"is a moving one, no rest policy applies): give a threshold or drop --rest")
    if args.rollout is not None and args.validate is None:
        raise UsageError("--rollout rolls the model out over the --validate recording: give --validate")
    for out in (args.json, args.report, args.urdf_out):
        check_output(out)


def _per_joint_option(what: str, choices: tuple[str, ...]) -> Any:
    """The parser of an option taking one name of ``choices``, or one per joint separated by commas
    (--rest "none,none,zero-coulomb,...", --friction "tanh,coulomb,...")."""
    def parse(text: str) -> str | tuple[str, ...]:
        parts = tuple(p.strip() for p in text.split(","))
        bad = [p for p in parts if p not in choices]
        if bad:
            raise argparse.ArgumentTypeError(f"unknown {what} {bad[0]!r} (choose from {', '.join(choices)})")
        return parts[0] if len(parts) == 1 else parts

    return parse


_rest_option = _per_joint_option("rest policy", REST_POLICIES)
_friction_option = _per_joint_option("friction form", FRICTION_FORMS)


def processing_of(args: argparse.Namespace, spring: bool) -> Processing:
    """The Processing the options ask for (the library's defaults where they say nothing)."""
    from identify.observation.processing import Processing

    return Processing(cutoff=args.cutoff, decimate_to=None if args.no_decimate else args.decimate_to,
                      min_velocity=args.min_velocity, rest=args.rest, delay=args.delay,
                      estimate_delay=True, spring=spring, cross_validate=args.cross_validate,
                      friction=args.friction)


def run(args: argparse.Namespace) -> int:
    from identify.fitting.torque_checks import CODES as TORQUE_CODES
    from identify.io.gains import read_gains

    from ..spring_output import attach_spring
    from .identify_output import print_choices, print_fit, show_choice, write_report

    _check(args)
    robot, spring_model = _robot(args)
    if isinstance(args.rest, tuple) and len(args.rest) != robot.n:
        raise UsageError(f"--rest: {len(args.rest)} policies given for the {robot.n} joints of {robot.name!r}")
    if isinstance(args.friction, tuple) and len(args.friction) != robot.n:
        raise UsageError(f"--friction: {len(args.friction)} forms given for the {robot.n} joints of {robot.name!r}")
    sb = attach_spring(robot, spring_model, args.validate, args.method)
    gains = read_gains(args.gains, robot) if args.gains else None
    flags = given_gain_flags(gains) if gains is not None else []
    # The identified model's prior (--prior, --prior-weight, --divergence), on whole logs and block by block alike.
    prior = physical_prior(args, robot)
    options = {"physical_prior": prior, "prior_weight": args.prior_weight, "divergence": args.divergence}
    # Every log read, filtered and fitted block by block (a log within one block is one block: docs/long-logs.md).
    val_rec = args.validate
    # The processing choice's table is printed before any refusal that follows it (the fit's own errors carry it).
    try:
        result = fit_recordings(args, robot, processing_of(args, sb is None), sb, gains, **options)
    except Exception as exc:
        show_choice(getattr(exc, "processing_choice", None))
        raise
    # What the fit chose, before any refusal: the processing's and the prior weight's tables.
    print_choices(result)
    # The recorded torques' scale, sign and gravity at rest, and the identified model against the model the user
    # had on held-back blocks, checked by the fit (every log, block by block when long): an error stops the run
    # (exit 2, nothing written), a warning is printed.
    stopping = [f for f in result.flags if f.code in TORQUE_CODES or f.code in MODEL_CODES]
    settle(stopping)
    for f in result.flags:  # the fit's own findings (columns left out or merged, a rank that depends on the
        if f not in stopping:  # threshold): fitted, never silent
            progress(f"{f.severity}: {with_hint(f)}")
    result = result.with_flags([*result.flags, *flags, *_fit_flags(result, args.method)])
    if args.essential:
        result = result.with_essential()
    if val_rec is not None:
        result = result.validated(val_rec, rollout=args.rollout)
        if result.validation.still_message():
            progress(f"warning: {result.validation.still_message()}")
    print_fit(result, [], args.delay == "auto")
    if args.json:
        from identify.monitor.thresholds import with_contact_thresholds

        result, why = with_contact_thresholds(result, args.recordings, val_rec)
        if why:
            progress(f"contact thresholds not stored ({why}): rx90 monitor will need --calibrate")
        result.save(args.json)
    if args.report:
        write_report(args.report, result, args.recordings, args.convention, args.block)
    if args.urdf_out:  # last: a refused (non-physical) link must not cost the fit's JSON and report
        _write_urdf(args, result)
    return 0


#: The identified model's checks against the yardsticks (identify.fitting.plausibility.heldout_flags).
MODEL_CODES = ("model_unexplained", "model_worse_on_joint", "torque_poorly_explained")


def physical_prior(args: argparse.Namespace, robot: rx90sym.Robot) -> Any:
    """The identified model's prior (--prior) as identify.fit takes it, said on stderr; a prior that gives
    no body (a description whose masses are all zero, a file naming no link) is refused."""
    from identify.fitting.fit import model_prior

    if args.prior == "none":
        progress("no prior (--prior none): the identified model is the data's alone; the split of what the data "
                 "cannot see is arbitrary")
        return "none"
    try:
        if args.prior == "description":  # asked for: a description without bodies is refused
            from rx90sym.description_prior import required_description_prior

            required_description_prior(robot)
        prior = model_prior(robot, args.prior or "description", args.divergence)
    except ValueError as exc:
        raise UsageError(f"--prior {args.prior or 'description'}: {exc}".replace("--prior description: --prior "
                                                                                "description: ", "--prior description: ")) from None
    if prior is None:
        if args.prior is not None:
            raise UsageError(f"--prior {args.prior}: no link has a body with a mass above 0")
        progress(f"robot {robot.name!r} has no description bodies: the identified model is the data's alone "
                 f"(give --prior FILE)")
        return "none"
    progress(f"prior: {prior.source} ({len(prior.links)} of {robot.n} links)"
             + "".join(f"\n  note: {n}" for n in prior.notes))
    return prior


def _fit_flags(f: Fit, method: str) -> list:
    """A joint the model explains poorly (a fit without held-back errors) is flagged; non-physical WLS
    estimates are flagged (judged with the larger of eq. 13's and the bootstrap's sigma); the identified
    model is judged against its prior (link masses)."""
    import numpy as np

    from identify.fitting.plausibility import estimate_flags, prior_flags, residual_flags

    obs, res = f.observation, f.result
    if obs is None:  # fitted in blocks: ‖Y_j‖² is the joint system's residual at x = 0
        torque_rms = np.array([np.sqrt(s.rss(np.zeros(s.columns)) / s.rows) if s.rows else np.nan
                               for s in f.least_squares.joint_systems])  # nan: a joint whose torque was left out
    else:
        torque_rms = np.array([np.sqrt(np.mean(obs.Y[obs.joint == j] ** 2)) if np.any(obs.joint == j) else np.inf
                               for j in range(len(res.residual_rms))])
    # Held-back errors against the yardsticks judged the fit already (its flags); without them the residuals.
    judged = f.identified is not None and f.identified.heldout is not None
    flags = [] if judged else settle(residual_flags(res.residual_rms, torque_rms,
                                                    f.robot.limits.tau_max[:torque_rms.size]))
    if method != "consistent":
        flags += settle(estimate_flags(res.names, res.values, np.fmax(res.std, f.bootstrap.of(res.names)), f.flags))
    model = f.identified
    if model is not None and model.prior is not None:
        from rx90sym import nominal_parameters

        flags += settle(prior_flags(model.standard, {k: v for k, v in (nominal_parameters(f.robot) or {}).items()
                                                     if k.startswith("M")}, f.robot.name))
    return flags


def _write_urdf(args: argparse.Namespace, f: Fit) -> None:
    """--urdf-out: a shortcut of rx90 export --urdf (identify.export_urdf)."""
    from rx90sym import UrdfError
    from identify.export.models import export_urdf

    try:
        written = export_urdf(f, args.urdf_out)
    except UrdfError as exc:
        kept = [p for p in (args.json, args.report) if p]
        raise UrdfError(f"{args.urdf_out} not written: {exc}" +
                        (f" (written: {', '.join(kept)})" if kept else "")) from None
    progress("wrote " + ", ".join(str(p) for p in written))
