"""Plausibility of inputs and results: refuse what cannot be right, flag what is doubtful.

Each check returns :class:`Flag` objects; severity ``"error"`` stops a run (the application exits
2 with the message, nothing written), ``"warning"`` is printed and kept in the JSON and the report.

Errors (the likely cause is named):

- ``gains_negative`` — most drive gains (more than half) are negative: the empty and loaded
  runs are swapped (a payload "removed" gives negative gains; the wrist motor of a coupled wrist,
  which the payload hardly loads, may keep its sign);
- ``payload_mass_negative`` — the payload mass is below 0 by more than 3 sigma: empty and loaded
  swapped (or gains of the wrong sign);
- ``torque_scale`` — the torques are far from the robot's torque limits: every joint's peak below
  :data:`TORQUE_LOW` of its limit (currents turned into torques with gains in A/(N m), not
  N m/A, or torques in kN m) or some joint's peak above :data:`TORQUE_HIGH` times it (mA, N mm);
- ``model_unexplained`` — the identified model predicts the held-back blocks of the fitted data worse
  than the model the user had (the plain OLS where the description has no bodies) over all joints, by
  more than the blocks' spread: no weight of the prior, not even the description itself, explains the
  data (wrong robot, swapped joints, wrong units, sign or gains). A joint whose held-back error is above
  :data:`RESIDUAL_SHARE` of its torque (or, without held-back blocks, whose residual RMS is) is the
  warning ``torque_poorly_explained``, ``model_worse_on_joint`` a joint where the yardstick alone is better
  (on the blocks' mean difference beyond its spread and on the pooled errors both, the figures printed).
  Measured: good fits leave 5-15 % (TX40), 7-24 % (UR10e, 14-harmonic run); the UR10e run with
  q1 and q2 swapped leaves 94 %, 75 % and 59 % on joints 1-3. A joint whose torque RMS is below
  :data:`RESIDUAL_FLOOR` of its torque limit is not judged (its torque may be mostly noise).

- ``static_gravity`` — at rest, a joint's torque is not the gravity of the robot's nominal
  parameters (``[nominal]``) within a factor :data:`GRAVITY_RATIO` (or of the opposite sign).

- ``torque_sign`` (warning, identify.fitting.torque_checks) — a joint's recorded torques have the
  opposite sign of the description's inverse dynamics: the fix (torque signs) is named.

Warnings:

- ``gain_negative`` — a negative gain (half of the gains at most): that motor's current sign may be
  inverted (the gain then makes the right torque: the run goes on);
- ``gain_uncertain`` — a gain whose relative sigma is above the flag threshold;
- ``gain_unidentified`` (error) — a gain of the wrong sign whose sigma is larger than itself is
  never returned: it is not identified; fix it from a datasheet;
- ``estimate_not_physical`` — a plain (ungrouped) base parameter that physics wants >= 0 (a mass,
  a diagonal inertia, a rotor inertia, a friction coefficient) with value + 3 sigma < 0;
- ``consistency_margin_negative`` — no physical standard parameters reproduce the estimate (both advise
  the consistent fit, unless a flag of :data:`SUSPECT_TORQUES` names a sign or gain: fix that first);
- ``payload_inertia_not_physical`` — the payload's pseudo-inertia has a negative eigenvalue;
- ``payload_mass_on_bound`` — the constrained mass sits on its bound (weighed mass ± tolerance,
  within :data:`BOUND_SHARE` of the tolerance): the data pull it outside, the bound set it.
- ``bodies_far_from_prior`` — the identified model with a prior: a link's identified mass outside
  [1/:data:`PRIOR_MASS_RATIO`, :data:`PRIOR_MASS_RATIO`] x its prior mass (wrong robot, gains or
  units; or a description whose mass the data weigh otherwise). Thresholds measured: docs/plausibility.md.

With the constrained payload fit, ``payload_mass_negative`` judges the unconstrained estimate too
(the constraints would hide swapped runs behind a small positive mass).
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

import rx90sym

__all__ = ["Flag", "PlausibilityError", "raise_errors", "gain_flags", "payload_flags", "torque_scale_flags",
           "residual_flags", "estimate_flags", "mass_bound_flags", "margin_flags", "static_gravity_flags", "GravityAtRest",
           "prior_flags", "heldout_flags", "judged_joints", "LIKELY_CAUSES", "REFUSE_RATIO", "PRIOR_MASS_RATIO", "TORQUE_LOW", "TORQUE_HIGH", "RESIDUAL_SHARE", "RESIDUAL_FLOOR",
           "SIGMAS", "CONSISTENT_ACTION", "SUSPECT_TORQUES"]

#: Every joint's torque peak below this fraction of its limit: torques of the wrong scale.
TORQUE_LOW = 0.01
#: Some joint's torque peak above this many times its limit: torques of the wrong scale.
TORQUE_HIGH = 10.0
#: A constrained mass within this fraction of the tolerance from its bound sits on the bound.
BOUND_SHARE = 0.01
#: A joint whose residual RMS exceeds this fraction of its torque RMS is not explained.
RESIDUAL_SHARE = 0.5
#: A joint whose torque RMS is below this fraction of its torque limit is not judged by
#: RESIDUAL_SHARE: its torque may be mostly noise (the UR10 twin's wrist: ~1e-3 of the limits).
RESIDUAL_FLOOR = 0.01
#: Rest for the static check: every joint slower than this, rad/s; at least REST_SAMPLES samples.
REST_SPEED = 0.01
REST_SAMPLES = 25
#: Joints judged by the static check: nominal gravity RMS at least this fraction of the limit.
GRAVITY_SHARE = 0.1
#: Measured / nominal gravity at rest outside [1/GRAVITY_RATIO, GRAVITY_RATIO] is refused.
GRAVITY_RATIO = 3.0
#: An identified link mass outside [1/PRIOR_MASS_RATIO, PRIOR_MASS_RATIO] x its prior mass is flagged.
PRIOR_MASS_RATIO = 3.0
#: A consistent fit with a prior costing more than this many % over WLS is flagged
#: (docs/plausibility.md: good fits measured far below, the UR10e read as a TX40 at 20 %).
#: How many sigma below zero a non-negative quantity may lie before it is flagged.
SIGMAS = 3.0
#: The action of estimate_not_physical and consistency_margin_negative when the torques are not suspect.
CONSISTENT_ACTION = "use the physically consistent fit"
#: Flags that make the recorded torques suspect (a sign, a gain, a unit): estimates no physical body has
#: are then their symptom, and the consistent fit is not advised (identify.fitting.torque_checks).
SUSPECT_TORQUES = ("torque_sign", "torque_scale", "static_gravity", "gains_negative", "gain_negative",
                   "gain_unidentified")
# Plain parameters that physics wants >= 0: masses, diagonal inertias, rotor inertias, viscous
# and (symmetric) Coulomb friction, the coupled motor's friction.
_NONNEGATIVE = re.compile(r"^(M|XX|YY|ZZ|IA|FV|FS|FVM|FSM)\d+$")


@dataclass(frozen=True)
class Flag:
    """One plausibility finding.

    code: stable identifier (module docstring); severity: "error" or "warning"; message: what is
    wrong, with the numbers; action: what to do; joint: 1-based joint or None; parameter: the
    parameter concerned or None.
    """

    code: str
    severity: str
    message: str
    action: str
    joint: int | None = None
    parameter: str | None = None

    def __post_init__(self) -> None:
        if self.severity not in ("error", "warning"):
            raise ValueError(f"Flag severity must be 'error' or 'warning', got {self.severity!r}")

    def to_json(self) -> dict:
        return {"code": self.code, "severity": self.severity, "joint": self.joint, "parameter": self.parameter,
                "message": self.message, "action": self.action}

    @classmethod
    def from_json(cls, d: dict) -> "Flag":
        """The flag of :meth:`to_json` (a fit file's ``flags``)."""
        return cls(str(d["code"]), str(d["severity"]), str(d["message"]), str(d["action"]),
                   None if d.get("joint") is None else int(d["joint"]), d.get("parameter"))

    def line(self) -> str:
        return f"{self.message}: {self.action}"


class PlausibilityError(ValueError):
    """Inputs or results that cannot be right; ``flags`` holds the errors (the first in the message)."""

    def __init__(self, flags: Sequence[Flag]) -> None:
        self.flags = tuple(flags)
        super().__init__("; ".join(f.line() for f in self.flags))


def raise_errors(flags: Sequence[Flag]) -> list[Flag]:
    """Raise PlausibilityError when any flag is an error; return the warnings otherwise."""
    errors = [f for f in flags if f.severity == "error"]
    if errors:
        raise PlausibilityError(errors)
    return list(flags)


def gain_flags(gains: np.ndarray, std: np.ndarray, fixed: Sequence[int] = (), rel_std_pct: np.ndarray | None = None,
               flag_pct: float | None = None) -> list[Flag]:
    """Drive gains [N m/A] and their sigma: all negative, one negative, unidentified, uncertain.

    fixed: 1-based joints set from a datasheet (not judged); rel_std_pct, flag_pct: relative sigma
    and its flag threshold, % (None: no uncertainty flag).
    """
    k, s = np.asarray(gains, dtype=float), np.asarray(std, dtype=float)
    free = [j for j in range(k.size) if j + 1 not in fixed]
    negative = [j for j in free if k[j] < 0]
    if len(negative) > len(free) / 2:
        values = ", ".join(f"{k[j]:.4g}" for j in free)
        return [Flag("gains_negative", "error", f"{len(negative)} of {len(free)} drive gains are negative "
                     f"({values} N m/A)",
                     "were they identified with the empty and loaded recordings swapped? (the payload must be on in the loaded runs)")]
    flags = []
    for j in free:
        if k[j] < 0 and not abs(k[j]) > s[j]:
            flags.append(Flag("gain_unidentified", "error", f"the gain of joint {j + 1} is {k[j]:.4g} ± {s[j]:.3g} "
                              "N m/A: negative and smaller than its sigma, it is not identified", "fix it from a "
                              "datasheet (or record motions that load this joint)", joint=j + 1))
        elif k[j] < 0:
            flags.append(Flag("gain_negative", "warning", f"the gain of joint {j + 1} is negative ({k[j]:.4g} N m/A)",
                              "check the sign of that motor's current (a current sign can be inverted)", joint=j + 1))
        elif rel_std_pct is not None and flag_pct is not None and not rel_std_pct[j] <= flag_pct:
            flags.append(Flag("gain_uncertain", "warning", f"the gain of joint {j + 1} has a relative sigma of "
                              f"{rel_std_pct[j]:.3g} % (above {flag_pct:g} %)", "fix it from a datasheet, or "
                              "record motions where the payload's mass loads this joint", joint=j + 1))
    return flags


def payload_flags(names: Sequence[str], values: np.ndarray, std: np.ndarray) -> list[Flag]:
    """Payload (XXc..Mc, SI): a negative mass (error), a non-physical inertia (warning)."""
    p = dict(zip(names, np.asarray(values, dtype=float)))
    s = dict(zip(names, np.asarray(std, dtype=float)))
    flags = []
    if "Mc" in p and p["Mc"] + SIGMAS * np.nan_to_num(s.get("Mc", 0.0)) < 0:
        flags.append(Flag("payload_mass_negative", "error", f"the payload mass is negative ({p['Mc']:.4g} ± "
                          f"{s['Mc']:.3g} kg)", "are the empty and loaded recordings swapped? (or the drive "
                          "gains of the wrong sign)", parameter="Mc"))
    fields = ("XXc", "XYc", "XZc", "YYc", "YZc", "ZZc", "MXc", "MYc", "MZc", "Mc")
    if all(f in p for f in fields):
        from identify.estimation.consistency.lmi import pseudo_inertia

        smallest = float(np.linalg.eigvalsh(pseudo_inertia([p[f] for f in fields])).min())
        if smallest < 0:
            flags.append(Flag("payload_inertia_not_physical", "warning", f"the payload's pseudo-inertia has a "
                              f"negative eigenvalue ({smallest:.3g} kg m^2): no rigid body has these "
                              "parameters", "use the constrained payload fit"))
    return flags


def mass_bound_flags(estimate: float, mass: float, tol: float) -> list[Flag]:
    """The constrained payload mass ``estimate`` [kg] against its bound ``mass`` ± ``tol`` [kg]:
    a warning when it sits on the bound (the data alone put it outside the weighed range)."""
    if tol <= 0 or abs(estimate - mass) < (1 - BOUND_SHARE) * tol:
        return []
    side = "upper" if estimate > mass else "lower"
    return [Flag("payload_mass_on_bound", "warning", f"the constrained payload mass {estimate:.4g} kg sits on "
                 f"its {side} bound ({mass:g} ± {tol:g} kg): the data alone put it outside", "check the weighed "
                 "mass, the drive gains and the pairing of the runs; compare with the unconstrained fit",
                 parameter="Mc")]


def torque_scale_flags(torques: Sequence[np.ndarray], robot: rx90sym.Robot, what: str = "torques") -> list[Flag]:
    """Joint torques (N m, (N, n) arrays) against the robot's torque limits [limits] torque."""
    limit = np.asarray(robot.limits.tau_max, dtype=float)
    known = np.isfinite(limit) & (limit > 0)
    if not known.any() or not torques:
        return []
    peak = np.max([np.max(np.abs(np.asarray(t, dtype=float)), axis=0) for t in torques], axis=0)
    ratio = peak[known] / limit[known]
    joints = np.flatnonzero(known)
    if np.all(ratio < TORQUE_LOW):
        j = int(joints[np.argmax(ratio)])
        return [Flag("torque_scale", "error", f"the {what} are far below robot {robot.name}'s torque limits (largest "
                     f"peak {peak[j]:.3g} N m on joint {j + 1}, {100 * peak[j] / limit[j]:.2g} % of its "
                     f"{limit[j]:g} N m)", "are the gains in A/(N m) instead of N m/A, or the torques in "
                     "another unit?")]
    if np.any(ratio > TORQUE_HIGH):
        j = int(joints[np.argmax(ratio)])
        return [Flag("torque_scale", "error", f"the {what} are far above robot {robot.name}'s torque limits (joint "
                     f"{j + 1}: peak {peak[j]:.3g} N m, {peak[j] / limit[j]:.3g} x its {limit[j]:g} N m)",
                     "are the gains or the torques in another unit (mA, N mm)?", joint=j + 1)]
    return []


def residual_flags(residual_rms: np.ndarray, torque_rms: np.ndarray, torque_limit: np.ndarray | None = None
                   ) -> list[Flag]:
    """Joints the model explains poorly (a warning): residual RMS > RESIDUAL_SHARE x torque RMS (both N m),
    for a fit without held-back blocks (:func:`heldout_flags` judges the others).

    torque_limit: (n,) the robot's torque limits, N m: a joint whose torque RMS is below
    RESIDUAL_FLOOR of its limit is not judged (its torque may be mostly noise).
    """
    rms = np.asarray(torque_rms, dtype=float)
    share = np.asarray(residual_rms, dtype=float) / rms
    judged = np.ones(share.size, bool) if torque_limit is None else ~(rms < RESIDUAL_FLOOR * np.asarray(torque_limit))
    bad = [j for j in range(share.size) if judged[j] and share[j] > RESIDUAL_SHARE]
    if not bad:
        return []
    text = ", ".join(f"joint {j + 1} {100 * share[j]:.2f} %" for j in bad)
    return [Flag("torque_poorly_explained", "warning", f"the model explains the torques poorly: residual RMS / torque RMS "
                 f"{text} (more than {100 * RESIDUAL_SHARE:g} %)", LIKELY_CAUSES, joint=bad[0] + 1)]


#: A fit is refused when its identified model's held-back error, over the joints, is above this many times
#: the model the user had's (and clearly so): no weight of the prior, the description itself included,
#: explains the data (measured: the UR10e run with q1 and q2 swapped, 1.41x; good twins and real logs at
#: most 1.03x, where the description is exact and the processing alone differs).
REFUSE_RATIO = 1.25
def judged_joints(torque_rms: Sequence[float], torque_limit: Sequence[float]) -> np.ndarray:
    """(n,) the joints whose torque RMS [N m] is at least RESIDUAL_FLOOR of their torque limit [N m] (a
    smaller torque may be mostly noise: its relative error is not judged)."""
    rms = np.asarray(torque_rms, dtype=float)
    return ~(np.nan_to_num(rms, nan=0.0) < RESIDUAL_FLOOR * np.asarray(torque_limit, dtype=float)[:rms.size])


#: What a model worse than the description's, or one that explains little, most often means.
LIKELY_CAUSES = ("check the torque signs (rx90 convert --torque-signs), the drive gains (--gains, rx90 gains), the "
                 "robot (is it the one recorded?), the joint order (swapped columns) and the units (rad, N m); with "
                 "a processing given, its rest policy (--rest crossing keeps the Coulomb term through short slow "
                 "passes, as the model the user had does)")


def heldout_flags(model: Sequence[float], model_blocks: Sequence[Sequence[float]], reference: Sequence[float],
                  reference_blocks: Sequence[Sequence[float]], reference_name: str,
                  judged: Sequence[bool] | None = None) -> list[Flag]:
    """The identified model against a yardstick on the same held-back blocks of the fitted data (relative
    errors [%] per joint, and per block and joint: the cross-validation's scores).

    An error (the fit refused) only when the model is worse than the yardstick — ``reference_name``: the
    model the user had, or the plain OLS where the description has no bodies — over all joints: its mean
    over the joints above :data:`REFUSE_RATIO` times the yardstick's, and higher by more than the blocks'
    spread (the paired difference's mean above one standard error); a warning for each joint where it is
    worse by more than the spread (and on the pooled figures it prints), and for each joint whose held-back error is above RESIDUAL_SHARE of its
    torque; exact figures in every message. ``judged``: the joints whose held-back error is judged against
    their torque (default all; :func:`judged_joints`)."""
    import math

    model, reference = np.asarray(model, float), np.asarray(reference, float)
    mb, rb = np.asarray(model_blocks, float), np.asarray(reference_blocks, float)
    if mb.shape != rb.shape or mb.size == 0:
        return []

    def worse(joint: int | None) -> bool:
        d = (mb - rb) if joint is None else (mb - rb)[:, joint:joint + 1]
        d = np.array([row[np.isfinite(row)].mean() for row in d if np.isfinite(row).any()])
        if d.size < 2:
            return bool(d.size and d[0] > 0)
        return bool(d.mean() - d.std(ddof=1) / math.sqrt(d.size) > 0)

    flags = []
    figures = ", ".join(f"joint {j + 1} {model[j]:.2f} % against {reference[j]:.2f} %" for j in range(model.size)
                        if np.isfinite(model[j]) and np.isfinite(reference[j]))
    if worse(None) and np.nanmean(model) > REFUSE_RATIO * np.nanmean(reference):
        flags.append(Flag("model_unexplained", "error", f"the identified model predicts the held-back blocks worse than "
                          f"{reference_name} ({np.nanmean(model):.2f} % against {np.nanmean(reference):.2f} % over the "
                          f"joints; {figures})", LIKELY_CAUSES))
        return flags
    for j in range(model.size):
        if np.isfinite(model[j]) and np.isfinite(reference[j]) and model[j] > reference[j] and worse(j):
            flags.append(Flag("model_worse_on_joint", "warning", f"joint {j + 1}: the identified model predicts the "
                              f"held-back blocks worse than {reference_name} ({model[j]:.2f} % against "
                              f"{reference[j]:.2f} %)", LIKELY_CAUSES, joint=j + 1))
    judged = np.ones(model.size, bool) if judged is None else np.asarray(judged, bool)
    poor = [j for j in range(model.size) if judged[j] and np.isfinite(model[j]) and model[j] > 100 * RESIDUAL_SHARE]
    if poor:
        flags.append(Flag("torque_poorly_explained", "warning", "the identified model explains the torques poorly: held-back "
                          "error " + ", ".join(f"joint {j + 1} {model[j]:.2f} % ({reference_name} {reference[j]:.2f} %)"
                                               for j in poor)
                          + f" of the torque (more than {100 * RESIDUAL_SHARE:g} %)", LIKELY_CAUSES, joint=poor[0] + 1))
    return flags


def _unphysical_action(torque_flags: Sequence[Flag]) -> str:
    """What to do about estimates no physical body has: the consistent fit (CONSISTENT_ACTION), unless the
    recorded torques are suspect (a flag of SUSPECT_TORQUES among ``torque_flags``): a wrong sign or gain
    makes such estimates, and a physically consistent fit would only hide it."""
    suspect = sorted({f.code for f in torque_flags if f.code in SUSPECT_TORQUES})
    if not suspect:
        return CONSISTENT_ACTION
    return (f"fix the recorded torques first ({', '.join(suspect)}): a wrong torque sign or gain makes such "
            f"estimates, which a physically consistent fit cannot correct")


def estimate_flags(names: Sequence[str], values: np.ndarray, std: np.ndarray,
                   torque_flags: Sequence[Flag] = ()) -> list[Flag]:
    """Plain parameters that physics wants >= 0 with value + SIGMAS sigma < 0 (grouped base
    parameters, e.g. ZZ1R, are sums with signs and are not judged). torque_flags: the fit's other
    flags; with one of SUSPECT_TORQUES the action is to fix the torques, never the consistent fit."""
    flags = []
    action = _unphysical_action(torque_flags)
    for n, v, s in zip(names, np.asarray(values, dtype=float), np.asarray(std, dtype=float)):
        if _NONNEGATIVE.match(n) and v + SIGMAS * np.nan_to_num(s) < 0:
            flags.append(Flag("estimate_not_physical", "warning", f"{n} = {v:.4g} ± {s:.3g} cannot be physical "
                              f"(value + {SIGMAS:g} sigma < 0)", action, parameter=n))
    return flags


def margin_flags(margin: float, torque_flags: Sequence[Flag] = ()) -> list[Flag]:
    """A negative consistency margin (identify.estimation.consistency.consistency_margin); torque_flags as
    for :func:`estimate_flags`."""
    if margin >= 0:
        return []
    return [Flag("consistency_margin_negative", "warning", f"no physical standard parameters reproduce the "
                 f"estimate (consistency margin {margin:.3g})", _unphysical_action(torque_flags))]


class GravityAtRest:
    """Sums over the samples at rest (every joint slower than REST_SPEED) of the torque times the nominal
    gravity torque and of its square, per joint; fed block by block."""

    def __init__(self, robot: rx90sym.Robot, nominal: dict) -> None:
        self.robot = robot
        self.chi = robot.parameter_vector({k: v for k, v in nominal.items() if k in robot.parameter_names
                                           and not k.startswith(("FS", "FV", "OFF"))}, strict=False)
        self.count = 0
        self.tau_g = np.zeros(robot.n)
        self.g_g = np.zeros(robot.n)

    def add(self, q: np.ndarray, tau: np.ndarray, dq: np.ndarray) -> None:
        """Samples (S, n): positions [rad], torques [N m], velocities [rad/s]."""
        rest = np.all(np.abs(dq) < REST_SPEED, axis=1)
        if not rest.any():
            return
        Q = np.asarray(q)[rest]
        Z = np.zeros_like(Q)
        g = self.robot.regressor_batch(Q, Z, Z) @ self.chi
        if self.robot.spring is not None:  # the motor holds gravity minus the spring (Y = tau + spring, eq. 7)
            g = g - self.robot.spring_torque_batch(Q)[:, :, 0]
        self.count += Q.shape[0]
        self.tau_g += np.einsum("sj,sj->j", np.asarray(tau)[rest], g)
        self.g_g += np.einsum("sj,sj->j", g, g)

    def flags(self) -> list[Flag]:
        """static_gravity errors: on each joint whose nominal gravity RMS is at least GRAVITY_SHARE of its
        limit, the least-squares scale of measured on nominal outside [1/GRAVITY_RATIO, GRAVITY_RATIO]."""
        if self.count < REST_SAMPLES:
            return []
        robot = self.robot
        judged = np.sqrt(self.g_g / self.count) >= GRAVITY_SHARE * np.asarray(robot.limits.tau_max, dtype=float)
        flags = []
        for j in np.flatnonzero(judged):
            s = float(self.tau_g[j] / self.g_g[j])
            if not 1 / GRAVITY_RATIO <= s <= GRAVITY_RATIO:
                cause = ("the torque sign (a log counting torques the other way: convert it with torque signs, "
                         "rx90 convert --torque-signs)" if s < 0 else "the robot, the units or the gains")
                flags.append(Flag("static_gravity", "error", f"at rest, joint {j + 1}'s torque is {s:.3g} x the "
                                  f"gravity of robot {robot.name}'s nominal parameters ({self.count} samples at rest; "
                                  f"expected {1 / GRAVITY_RATIO:.2g}..{GRAVITY_RATIO:g})", f"check {cause}",
                                  joint=int(j) + 1))
        return flags


def static_gravity_flags(recordings: Sequence, robot: rx90sym.Robot, nominal: dict | None) -> list[Flag]:
    """Torques at rest against the gravity of the robot's nominal parameters ([nominal] table).

    At rest (every joint slower than REST_SPEED) the torque is gravity (and the spring) plus at
    most the Coulomb friction; on each joint whose nominal gravity RMS is at least GRAVITY_SHARE of
    its torque limit, the least-squares scale s of measured on nominal must lie in
    [1/GRAVITY_RATIO, GRAVITY_RATIO]; s < 0 is a wrong sign. Measured on the UR10e at rest
    (ur-20_01_17-p4.csv, the source's gains): s = 0.875 on joint 3 (the only joint judged).
    No nominal parameters (None): no check.
    """
    if not nominal or not recordings:
        return []
    gravity = GravityAtRest(robot, nominal)
    for rec in recordings:
        if rec.tau is None or len(rec.t) < 3:
            continue
        dq = rec.dq if rec.dq is not None else np.gradient(np.asarray(rec.q), np.asarray(rec.t), axis=0)
        gravity.add(np.asarray(rec.q), np.asarray(rec.tau), dq)
    return gravity.flags()


def prior_flags(standard: Mapping[str, float], prior: Mapping[str, float], robot_name: str = "") -> list[Flag]:
    """The identified model against its prior (the robot's description, SI): a link whose identified mass
    is more than PRIOR_MASS_RATIO away from the prior's.

    standard: the identified standard parameters (name -> value; masses ``M<j>`` in kg);
    prior: the prior's values (same names). Links whose prior mass is not positive are not judged.
    """
    flags = []
    links = sorted((k[1:] for k in prior if re.fullmatch(r"M\d+", k) and prior[k] > 0 and k in standard), key=int)
    for j in links:
        m, m0 = float(standard[f"M{j}"]), float(prior[f"M{j}"])
        ratio = m / m0
        if not 1 / PRIOR_MASS_RATIO <= ratio <= PRIOR_MASS_RATIO:
            flags.append(Flag("bodies_far_from_prior", "warning", f"link {j}'s identified mass {m:.3g} kg is "
                              f"{ratio:.3g} x its prior mass {m0:.3g} kg (expected {1 / PRIOR_MASS_RATIO:.2g}.."
                              f"{PRIOR_MASS_RATIO:g})", "check the robot (is it the one recorded?) and the units; "
                              "or the description's mass is wrong (the data weighed it down)", parameter=f"M{j}"))
    return flags
