"""Drive gains identified with a payload of known mass (paper section IV turned around).

Joint torques are ``tau = Rt diag(k) (i - i0)`` (:mod:`identify.io.gains`). With currents alone the
scale of the gains is lost: k and every dynamic parameter can be multiplied together. A payload
whose mass Mc is weighed fixes that scale (Gautier and Briot, global identification of joint drive
gains and dynamic parameters of robots):

- ``same-motion`` (eq. 28 turned around): one trajectory run empty and loaded,
  ``Rt diag(k) (i_loaded - i_empty) = W_c chi_c`` with Mc known and the other nine payload
  parameters unknown; the robot's own dynamics, friction and current offsets cancel;
- ``global`` (eq. 29 with currents): empty and loaded runs of any motions; k, the robot's base
  parameters (with per-joint offsets by default) and the nine payload parameters solved together,
  the known-mass column on the right-hand side.

Uncertainty: the least-squares sigma of each gain (eqs. 12-15) and the weighing error of the mass:
every estimate scales with the mass, so ``sigma_k,rel^2 = sigma_LS,rel^2 + (sigma_M / M)^2``; the
mass part is the same for all joints (fully correlated: a mass 1 % heavy makes every gain 1 %
higher). A gain whose relative sigma exceeds ``flag_pct`` is flagged (e.g. joint 1 of an arm whose
first axis is vertical feels no gravity from the payload, only its inertia); ``fix`` sets a gain
from a datasheet instead.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

import rx90sym
from rx90sym.parameters import PAYLOAD_NAMES
from rx90sym.recording import Recording, RecordingError
from rx90sym.threads import one_blas_thread

from identify.gains.defaults import DEFAULT_METHOD, FLAG_PCT, GAIN_METHODS
from identify.signal.filtering import choose_cutoff
from identify.io.gains import DriveGains, apply_gains
from identify.estimation.bootstrap import bootstrap_std
from identify.estimation.least_squares import triangular_cond, weighted_least_squares
from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.observation.matrix import FilteredMotion, column_regressor, filtered_motion, stack_rows
from identify.signal.pairing import POSITION_TOLERANCE, PairedRuns, pair_runs
from identify.estimation.results import IdentificationResult, json_number
from identify.fitting.plausibility import PlausibilityError, gain_flags, raise_errors
from identify.gains.methods import swapped_runs_error

__all__ = ["DriveGainsResult", "drive_gains", "GAIN_METHODS", "DEFAULT_METHOD", "FLAG_PCT"]

# Instrumental-variable iterations (IDIM-IV, see _fit): at most this many, until no unknown moves
# by more than IV_TOLERANCE of its sigma (the twin's weak motor 6 needs ~8; the others 2).
IV_ITERATIONS = 30
IV_TOLERANCE = 1e-3
_OTHER_PAYLOAD = PAYLOAD_NAMES[:-1]  # XXc .. MZc; Mc is known


@dataclass(frozen=True, eq=False)
class DriveGainsResult:
    """Identified drive gains.

    gains: the :class:`DriveGains` (std includes the weighing error; its JSON is the file format);
    rel_std_pct: (n,) total relative sigma, % (nan where fixed): the larger of eq. 13's
    (rel_std_ls_pct) and the segment bootstrap's (rel_std_boot_pct), with the weighing error; flagged / fixed: joint numbers (1-based); method; mass, mass_std: kg; flag_pct: %;
    payload: the nine other payload parameters (SI); fit: the least-squares result of all unknowns;
    robot: base parameters of the robot (``global``), else None; pairs: the paired runs
    (``same-motion``).
    """

    gains: DriveGains
    rel_std_pct: np.ndarray
    rel_std_ls_pct: np.ndarray
    flagged: tuple[int, ...]
    fixed: tuple[int, ...]
    method: str
    mass: float
    mass_std: float
    flag_pct: float
    payload: dict
    fit: IdentificationResult = field(repr=False)
    robot: IdentificationResult | None = field(default=None, repr=False)
    pairs: tuple[PairedRuns, ...] = field(default=(), repr=False)
    rel_std_boot_pct: np.ndarray | None = None

    def to_dict(self) -> dict:
        """The drive-gain JSON (identify.io.gains), read back by :func:`identify.io.gains.read_gains`."""
        return self.gains.to_dict()

    def table(self) -> str:
        """One line per gain: value, sigma, relative sigma (total and LS part), flag."""
        unit = "N·m/A, " + ("motor side" if self.gains.side == "motor" else "joint side")
        lines = [f"Drive gains ({self.method}, Mc = {self.mass:g} ± {self.mass_std:g} kg; {unit})",
                 f"{'motor':>5s} {'gain':>10s} {'σ':>9s} {'σr %':>7s} {'σr eq.13 %':>10s} {'σr boot %':>9s}  note"]
        boot = self.rel_std_boot_pct if self.rel_std_boot_pct is not None else np.full(len(self.gains.gains), np.nan)
        for j, (k, s, r, rl, rb) in enumerate(zip(self.gains.gains, self.gains.std, self.rel_std_pct,
                                                    self.rel_std_ls_pct, boot), start=1):
            note = ("fixed" if j in self.fixed else
                    f"flagged (σr > {self.flag_pct:g} %)" if j in self.flagged else "")
            lines.append(f"{j:5d} {k:10.5g} {s:9.3g} {r:7.3g} {rl:10.3g} {rb:9.3g}  {note}")
        if self.mass_std > 0:
            lines.append(f"the weighing error ({100 * self.mass_std / self.mass:.3g} %) is common to all "
                         "gains (fully correlated)")
        for p in self.pairs:
            lines.append(p.summary())
        return "\n".join(lines)


def _unit_currents(rec: Recording, robot: rx90sym.Robot) -> Recording:
    """The recording with tau = its currents (unit joint-side gains): filtered like torques."""
    if rec.current is None:
        raise RecordingError(f"{rec.source}: drive gains are identified from motor currents; "
                             "the recording holds none")
    return apply_gains(rec, DriveGains(np.ones(robot.n), side="joint", source="unit gains"), robot)


def _current_motions(robot: rx90sym.Robot, recs: Sequence[Recording], columns: Sequence[int], cutoff: float | None,
             decimate_to: float | None, spring: bool) -> list[FilteredMotion]:
    """Filtered currents (Y) and [W columns, spring torque] (Phi), one parallel filter for all."""
    _, standard = column_regressor(robot, columns=[robot.parameter_names[i] for i in columns])

    def regressor(Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray) -> np.ndarray:
        W = standard(Q, QD, QDD)
        s = robot.spring_torque_batch(Q)[:, :, :1] if spring else np.zeros((len(Q), robot.n, 1))
        return np.concatenate([W, s], axis=2)

    return [filtered_motion(robot, _unit_currents(r, robot), cutoff, decimate_to, False, regressor)
            for r in recs]


def _current_columns(Y: np.ndarray, Rt: np.ndarray) -> np.ndarray:
    """(S, n, n_motors): column m of joint j is Rt[j, m] i_m, so that tau = this @ k."""
    return Y[:, None, :] * Rt[None, :, :]


def _check_inputs(robot: rx90sym.Robot, empty: Sequence[Recording], loaded: Sequence[Recording],
                  mass: float, mass_std: float, method: str, fix: Mapping[int, float]) -> None:
    if method not in GAIN_METHODS:
        raise ValueError(f"drive_gains: method must be one of {GAIN_METHODS}, got {method!r}")
    if not empty or not loaded:
        raise ValueError("drive_gains: needs at least one empty and one loaded recording with currents")
    if not (np.isfinite(mass) and mass > 0):
        raise ValueError(f"drive_gains: the payload mass must be > 0 kg, got {mass:g}")
    if not (np.isfinite(mass_std) and mass_std >= 0):
        raise ValueError(f"drive_gains: mass_std must be >= 0 kg, got {mass_std:g}")
    for j, v in fix.items():
        if not (1 <= j <= robot.n):
            raise ValueError(f"drive_gains: fixed gain of joint {j}; robot {robot.name!r} has joints 1..{robot.n}")
        if not np.isfinite(v) or v == 0:
            raise ValueError(f"drive_gains: fixed gain of joint {j} must be finite and non-zero, got {v:g}")
    if len(fix) >= robot.n:
        raise ValueError("drive_gains: every gain is fixed; nothing to identify")
    if method == "same-motion" and len(empty) != len(loaded):
        raise ValueError(f"same-motion pairs each loaded run with the same motion run empty: got "
                         f"{len(empty)} empty and {len(loaded)} loaded recordings (--method global takes any "
                         f"number of each)")


@one_blas_thread()
def drive_gains(robot: rx90sym.Robot, empty: Sequence[Recording], loaded: Sequence[Recording], mass: float,
                method: str = DEFAULT_METHOD, fix: Mapping[int, float] | None = None, mass_std: float = 0.0,
                side: str | None = None, offsets: bool = True, flag_pct: float = FLAG_PCT,
                position_tol: float = POSITION_TOLERANCE, base: rx90sym.BaseParameters | None = None,
                cutoff: float | None = None, decimate_to: float | None = DEFAULT_DECIMATE_TO,
                min_velocity: float | None = None, spring: bool = True,
                iterations: int = IV_ITERATIONS, bootstrap_seed: int = 0, _swap_check: bool = True) -> DriveGainsResult:
    """Identify the drive gains from current recordings and a payload of known mass.

    Args:
        robot: the robot (its transmission ``Rt`` maps motor to joint torques).
        empty, loaded: current recordings without / with the payload (``same-motion``: run i of
            each is the same trajectory, paired in time by :func:`identify.signal.pairing.pair_runs`).
        mass: the payload's weighed mass, kg.
        method: ``"same-motion"`` (eq. 28) or ``"global"`` (eq. 29).
        fix: joint number (1-based) -> gain [N·m/A] known from a datasheet.
        mass_std: standard deviation of the weighing, kg.
        side: ``"motor"`` (tau = Rt diag(k) i) or ``"joint"`` (tau = diag(k) i); default: motor
            for a robot with a coupled wrist, joint otherwise.
        offsets: ``global`` only: identify per-joint current offsets (reported as
            ``current_offsets``, A); same-motion needs none (they cancel).
        flag_pct: flag a gain whose relative sigma exceeds this, %.
        position_tol: same-motion: largest position gap between paired runs, rad.
        base: base parameters of ``robot`` (``global``; computed when None).
        cutoff, decimate_to, min_velocity, spring: filtering as in :func:`identify.fit`.
        iterations: at most this many instrumental-variable iterations (0: least squares, biased
            toward zero gains by the current noise).
        bootstrap_seed: seed of the segment bootstrap (identify.estimation.bootstrap) whose sigma,
            when larger than eq. 13's, is the gain's (coloured residuals, window-to-window spread).

    BLAS on one thread inside the call, the caller's count back after it (rx90sym.threads).

    Raises:
        ValueError: bad arguments, recordings without currents, runs that do not pair.
        PlausibilityError: most gains negative: ``runs_swapped`` when the runs swapped give mostly
            positive gains (the payload is in the runs given as empty), or a gain of the wrong
            sign with a sigma larger than itself (not identified: never returned).
        IdentificationError: the system is rank deficient (names the unexcited unknowns).
    """
    empty, loaded = list(empty), list(loaded)
    fix = {int(j): float(v) for j, v in (fix or {}).items()}
    _check_inputs(robot, empty, loaded, mass, mass_std, method, fix)
    side = side or ("motor" if robot.coupling is not None else "joint")
    if side not in ("motor", "joint"):
        raise ValueError(f"drive_gains: side must be 'motor' or 'joint', got {side!r}")
    Rt = np.asarray(robot.Rt, dtype=float) if side == "motor" else np.eye(robot.n)
    gain_names = tuple(f"K{j}" for j in range(1, robot.n + 1))
    free = [j for j in range(robot.n) if j + 1 not in fix]
    k_fixed = np.array([fix.get(j + 1, 0.0) for j in range(robot.n)])
    if int(iterations) != iterations or iterations < 0:
        raise ValueError(f"drive_gains: iterations must be an integer >= 0, got {iterations!r}")
    opts = dict(robot=robot, Rt=Rt, mass=mass, free=free, k_fixed=k_fixed, cutoff=cutoff,
                decimate_to=decimate_to, min_velocity=min_velocity, spring=spring, iterations=int(iterations),
                rate=decimate_to or empty[0].rate, seed=bootstrap_seed)
    if method == "same-motion":
        (fit, boot), pairs, robot_fit, i0 = _same_motion(empty, loaded, position_tol, **opts)
    else:
        (fit, boot), robot_fit, i0 = _global(empty, loaded, offsets, base, **opts)
        pairs = ()
    k = k_fixed.copy()
    std_ls, std_boot = np.full(robot.n, np.nan), np.full(robot.n, np.nan)
    for j in free:
        i = fit.names.index(gain_names[j])
        k[j], std_ls[j], std_boot[j] = fit.values[i], fit.std[i], boot[i]
    rel_ls, rel_boot = 100 * std_ls / np.abs(k), 100 * std_boot / np.abs(k)
    # The larger of eq. 13's and the bootstrap's sigma; every estimate scales with the mass.
    rel = np.hypot(np.fmax(rel_ls, rel_boot), 100 * mass_std / mass)
    try:
        raise_errors(gain_flags(k, np.abs(k) * rel / 100, tuple(sorted(fix))))
    except PlausibilityError as exc:  # mostly negative: runs swapped? (confirmed by fitting them swapped)
        if not _swap_check or not any(f.code == "gains_negative" for f in exc.flags):
            raise
        raise swapped_runs_error(exc, lambda: drive_gains(
            robot, loaded, empty, mass, method, fix, mass_std, side, offsets, flag_pct, position_tol, base, cutoff,
            decimate_to, min_velocity, spring, iterations, bootstrap_seed, _swap_check=False),
            [r.source for r in empty], [r.source for r in loaded], robot_fit) from None
    flagged = tuple(j + 1 for j in free if not rel[j] <= flag_pct)
    gains = DriveGains(k, side=side, current_offsets=_current_offsets(i0, k, Rt),
                       std=np.abs(k) * rel / 100, robot=robot.name, source=f"drive_gains:{method}",
                       extra={"method": method, "mass": float(mass), "mass_std": float(mass_std),
                              "rel_std_pct": [json_number(r) for r in rel],
                              "rel_std_ls_pct": [json_number(r) for r in rel_ls],
                              "rel_std_bootstrap_pct": [json_number(r) for r in rel_boot],
                              "flagged": list(flagged), "fixed": sorted(fix), "flag_pct": float(flag_pct)})
    payload = {n: float(fit.values[fit.names.index(n)]) for n in _OTHER_PAYLOAD}
    return DriveGainsResult(gains, rel, rel_ls, flagged, tuple(sorted(fix)), method, float(mass),
                            float(mass_std), float(flag_pct), payload, fit, robot_fit, tuple(pairs), rel_boot)


def _current_offsets(torque_offsets: np.ndarray | None, k: np.ndarray, Rt: np.ndarray) -> np.ndarray | None:
    """i0 with Rt diag(k) i0 = the identified torque offsets (the model's OFFj)."""
    if torque_offsets is None:
        return None
    return np.linalg.solve(Rt @ np.diag(k), torque_offsets)


@dataclass(frozen=True, eq=False)
class _Motion:
    """One motion in the form G(I) k - X theta = Kn (per sample, joint on axis 1).

    I: (S, n) filtered currents (same-motion: loaded minus empty); X: (S, n, c) the other
    unknowns' columns; Kn: (S, n) the known-mass column times Mc minus the spring torque; dq: (S, n).
    """

    I: np.ndarray
    X: np.ndarray
    Kn: np.ndarray
    dq: np.ndarray


def _system(motions: Sequence[_Motion], currents: Sequence[np.ndarray], Rt: np.ndarray, free: list[int],
            k_fixed: np.ndarray, min_velocity: float | None):
    """Rows (grouped per joint) of [G(currents)_free, -X] and of the right-hand side."""
    blocks = [np.concatenate([_current_columns(c, Rt)[:, :, free], -m.X], axis=2) for m, c in zip(motions, currents)]
    Ys = [m.Kn - _current_columns(m.I, Rt) @ k_fixed for m in motions]
    return stack_rows(blocks, Ys, min_velocity, [m.dq for m in motions])


def _fit(motions: Sequence[_Motion], names: Sequence[str], Rt: np.ndarray, free: list[int],
         k_fixed: np.ndarray, min_velocity: float | None, method: str, iterations: int, rate: float,
         seed: int) -> tuple[IdentificationResult, np.ndarray]:
    """WLS, then instrumental variables with the model's predicted currents (IDIM-IV).

    The currents are regressors here, so their noise biases plain LS toward zero gains (errors in
    variables: 5-8 % on the twin's realistic runs); the currents predicted by the current estimate,
    i = (Rt diag(k))^-1 (X theta + Kn), are free of that noise and serve as instruments. Iterated
    until no unknown moves by more than IV_TOLERANCE of its sigma (at most ``iterations`` times).
    Each joint's rows are weighted by 1/sigma of its residual (the usual per-joint block fit,
    eqs. 12-13, fails: a joint whose rows carry no known-mass term has a homogeneous block).
    Returns the fit and the segment-bootstrap sigma of its unknowns (same instruments; rate: the
    rows' sample rate, Hz; seed: the bootstrap's).
    """
    W, Y, joint, samples = _system(motions, [m.I for m in motions], Rt, free, k_fixed, min_velocity)
    ols = weighted_least_squares(W, Y, joint, names, weighted=False)  # rank check names the unknowns
    x = ols.values
    n_f = len(free)
    nj = int(joint.max()) + 1
    Z = W  # the instruments; W itself (plain LS) before the first iteration
    cov, sigma_rho, sigma = _iv_covariance(W, Z, Y, x, joint, nj)
    for _ in range(iterations):
        k = k_fixed.copy()
        k[free] = x[:n_f]
        if np.any(k == 0):
            raise ValueError("drive gains: a gain came out as 0; the runs do not excite it")
        gain = Rt @ np.diag(k)
        predicted = [np.linalg.solve(gain, (np.einsum("snc,c->sn", m.X, x[n_f:]) + m.Kn).T).T for m in motions]
        Z, _, _, _ = _system(motions, predicted, Rt, free, k_fixed, min_velocity)
        w = 1.0 / sigma[joint]
        Aw, Zw = W * w[:, None], Z * w[:, None]
        x_new = np.linalg.solve(Zw.T @ Aw, Zw.T @ (Y * w))
        cov, sigma_rho, sigma = _iv_covariance(W, Z, Y, x_new, joint, nj)
        step = np.max(np.abs(x_new - x) / np.sqrt(np.diag(cov)))
        x = x_new
        if step < IV_TOLERANCE:
            break
    std = np.sqrt(np.diag(cov))                                                   # eq. 14
    res = Y - W @ x
    rms = np.array([np.sqrt(np.mean(res[joint == j] ** 2)) for j in range(nj)])
    boot = bootstrap_std(W, Y, joint, samples, 1.0 / sigma, rate, seed, instruments=Z)
    cond = triangular_cond(np.linalg.qr(W / sigma[joint][:, None], mode="r"))
    return IdentificationResult(tuple(names), x, std, 100 * std / np.abs(x), sigma_rho,
                                cond, ols.cond_unweighted, rms, 1.0 / sigma,
                                len(Y), f"drive-gains-{method}-iv", cov), boot


def _iv_covariance(W: np.ndarray, Z: np.ndarray, Y: np.ndarray, x: np.ndarray, joint: np.ndarray,
                   nj: int) -> tuple[np.ndarray, float, np.ndarray]:
    """(covariance, sigma_rho, per-joint sigma) of the estimate x with instruments Z."""
    sigma = _joint_sigma(Y - W @ x, joint, nj, W.shape[1])
    w = 1.0 / sigma[joint]
    Aw, Zw, r = W * w[:, None], Z * w[:, None], (Y - W @ x) * w
    sigma_rho = float(np.sqrt(r @ r / (len(r) - len(x))))                       # eq. 12
    ZAinv = np.linalg.inv(Zw.T @ Aw)
    return sigma_rho**2 * ZAinv @ (Zw.T @ Zw) @ ZAinv.T, sigma_rho, sigma       # eq. 13, IV form


def _joint_sigma(r: np.ndarray, joint: np.ndarray, nj: int, c: int) -> np.ndarray:
    dof = 1.0 - c / len(r)
    sigma = np.array([np.sqrt(np.mean(r[joint == j] ** 2) / dof) for j in range(nj)])
    if np.any(sigma <= 0):
        raise ValueError(f"joint {int(np.argmin(sigma)) + 1}: the gain fit leaves no residual; cannot weight it")
    return sigma


def _same_motion(empty, loaded, position_tol, *, robot, Rt, mass, free, k_fixed, cutoff, decimate_to,
                 min_velocity, spring, iterations, rate, seed):
    pairs = [pair_runs(e, l, position_tol, instead="--method global") for e, l in zip(empty, loaded)]
    # One cut-off for both runs of a pair, so that the same samples are kept and compared.
    cutoff = cutoff or max(choose_cutoff(np.asarray(p.loaded.q), p.loaded.rate) for p in pairs)
    cols = list(rx90sym.payload_regressor_columns(robot))
    m_l = _current_motions(robot, [p.loaded for p in pairs], cols, cutoff, decimate_to, spring)
    m_e = _current_motions(robot, [p.empty for p in pairs], cols, cutoff, decimate_to, spring)
    # eq. 28 turned around: Rt diag(k) (i_l - i_e) - Wc' chi' = Wc_M Mc - (S_l - S_e).
    motions = [_Motion(a.Y - b.Y, a.Phi[:, :, :9], a.Phi[:, :, 9] * mass - (a.Phi[:, :, 10] - b.Phi[:, :, 10]), a.dq)
               for a, b in zip(m_l, m_e)]
    names = tuple(f"K{j + 1}" for j in free) + _OTHER_PAYLOAD
    return _fit(motions, names, Rt, free, k_fixed, min_velocity, "same-motion", iterations, rate, seed), pairs, None, None


def _global(empty, loaded, offsets, base, *, robot, Rt, mass, free, k_fixed, cutoff, decimate_to,
            min_velocity, spring, iterations, rate, seed):
    if offsets and not robot.offsets:
        robot = robot.with_options(offsets=True)
        if base is not None and "OFF1" not in base.names:
            base = None  # the base parameters of the robot without offsets
    base = base if base is not None else rx90sym.base_parameters(robot)
    nb = base.nb
    cols = list(base.independent) + list(rx90sym.payload_regressor_columns(robot))
    motions = (_current_motions(robot, empty, cols, cutoff, decimate_to, spring)
               + _current_motions(robot, loaded, cols, cutoff, decimate_to, spring))
    system = []
    for i, m in enumerate(motions):
        Wc = m.Phi[:, :, nb:nb + 10] if i >= len(empty) else np.zeros_like(m.Phi[:, :, nb:nb + 10])
        # eq. 29 with currents: Rt diag(k) i - Wb beta - Wc' chi' = Wc_M Mc - S.
        system.append(_Motion(m.Y, np.concatenate([m.Phi[:, :, :nb], Wc[:, :, :9]], axis=2),
                              Wc[:, :, 9] * mass - m.Phi[:, :, nb + 10], m.dq))
    names = tuple(f"K{j + 1}" for j in free) + tuple(base.names) + _OTHER_PAYLOAD
    fit, boot = _fit(system, names, Rt, free, k_fixed, min_velocity, "global", iterations, rate, seed)
    idx = [fit.names.index(n) for n in base.names]
    cov = fit.covariance[np.ix_(idx, idx)] if fit.covariance is not None else None
    robot_fit = IdentificationResult(tuple(base.names), fit.values[idx], fit.std[idx], fit.rel_std_pct[idx],
                                     fit.sigma_rho, fit.cond, fit.cond_unweighted, fit.residual_rms,
                                     fit.weights, fit.rows, "drive-gains-global", cov)
    torque_offsets = None
    if robot.offsets:
        off = [f"OFF{j}" for j in range(1, robot.n + 1)]
        # tau_model = W beta includes +OFFj; with raw currents G k = tau + Rt diag(k) i0.
        torque_offsets = np.array([robot_fit[n] if n in robot_fit.names else 0.0 for n in off])
    return (fit, boot), robot_fit, torque_offsets
