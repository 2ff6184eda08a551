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
from typing import Any, Mapping, Sequence

import numpy as np

import rx90sym
from rx90sym.parameters import PAYLOAD_NAMES
from rx90sym.recording import RecordingError
from rx90sym.threads import one_blas_thread

from identify.estimation.bootstrap import BLOCK_S, DRAWS, SegmentBootstrap
from identify.estimation.results import IdentificationResult, json_number
from identify.fitting.plausibility import PlausibilityError, gain_flags, raise_errors
from identify.fitting.run_blocks import RunBlock, RunColumns, Runs, open_runs, run_blocks, run_sources
from identify.gains.defaults import DEFAULT_METHOD, FLAG_PCT, GAIN_METHODS
from identify.gains.iv_fit import IV_ITERATIONS, GainRows, GainSums, iv_fit
from identify.gains.methods import swapped_runs_error
from identify.io.blocks import DEFAULT_BLOCK, check_block
from identify.io.gains import DriveGains
from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.observation.processing import Processing, drops_rest
from identify.signal.pairing import POSITION_TOLERANCE, PairedRuns

__all__ = ["DriveGainsResult", "drive_gains", "GAIN_METHODS", "DEFAULT_METHOD", "FLAG_PCT"]

_OTHER_PAYLOAD = PAYLOAD_NAMES[:-1]  # XXc .. MZc; Mc is known
#: The source of the unit joint-side gains that read the runs' currents as "torques" (filtered like torques).
_UNIT = "unit gains"


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


def _check_inputs(robot: rx90sym.Robot, empty: Sequence[Any], loaded: Sequence[Any],
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
def drive_gains(robot: rx90sym.Robot, empty: Sequence[Any], loaded: Sequence[Any], mass: float,
                method: str = DEFAULT_METHOD, fix: Mapping[int, float] | None = None, mass_std: float = 0.0,
                side: str | None = None, offsets: bool = True, flag_pct: float = FLAG_PCT,
                position_tol: float = POSITION_TOLERANCE, base: rx90sym.BaseParameters | None = None,
                cutoff: float | None = None, decimate_to: float | None = DEFAULT_DECIMATE_TO,
                min_velocity: float | None = None, spring: bool = True,
                iterations: int = IV_ITERATIONS, bootstrap_seed: int | None = 0, *, rest: str | tuple = "drop",
                delay: float = 0.0, convention: str | None = None, block: int | None = None, client: Any = None,
                _swap_check: bool = True) -> DriveGainsResult:
    """Identify the drive gains from current recordings and a payload of known mass, block by block.

    Args:
        robot: the robot (its transmission ``Rt`` maps motor to joint torques).
        empty, loaded: runs with motor currents without / with the payload: recordings, or recording
            files read ``block`` raw samples at a time (memory bounded by the block whatever their length;
            ``convention``: their angles). ``same-motion``: run i of each is the same trajectory, paired
            segment by segment (:func:`identify.signal.pairing.pair_runs`; runs of different segment
            counts refused).
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
        cutoff, decimate_to, min_velocity, rest, delay, spring: the processing, as in :func:`identify.fit`
            (cut-off None: chosen on the runs, identify.fitting.run_blocks).
        iterations: at most this many instrumental-variable iterations (0: least squares, biased
            toward zero gains by the current noise).
        bootstrap_seed: seed of the segment bootstrap (identify.estimation.bootstrap) whose sigma,
            when larger than eq. 13's, is the gain's (coloured residuals, window-to-window spread;
            None: none).
        client: a ``dask.distributed.Client`` running the blocks.

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
    # The currents read as torques through unit joint-side gains: filtered like torques, no spring added.
    unit = DriveGains(np.ones(robot.n), side="joint", source=_UNIT)
    empty, loaded = (run_sources(robot, runs, what, convention, unit) for runs, what in ((empty, "empty"),
                                                                                      (loaded, "loaded")))
    for src in empty + loaded:
        if not src.holds_current:
            raise RecordingError(f"{src.source}: drive gains are identified from motor currents; the recording "
                                 f"holds none")
    # Y is the currents alone: the spring torque is a column of its own (on the right-hand side, Kn).
    processing = Processing(cutoff=cutoff, decimate_to=decimate_to, min_velocity=min_velocity, rest=rest,
                            delay=float(delay), spring=False)
    block = check_block(block) if block is not None else DEFAULT_BLOCK
    opts = dict(robot=robot, Rt=Rt, mass=mass, free=free, k_fixed=k_fixed, iterations=int(iterations),
                seed=bootstrap_seed, client=client, spring=spring)
    if method == "same-motion":
        (fit, boot), pairs, robot_fit, i0 = _same_motion(empty, loaded, position_tol, processing, block, **opts)
    else:
        (fit, boot), robot_fit, i0 = _global(empty, loaded, offsets, base, processing, block, **opts)
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
            decimate_to, min_velocity, spring, iterations, bootstrap_seed, rest=rest, delay=delay, block=block,
            client=client, _swap_check=False),
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


def _same_motion_rows(mass: float, drop: bool):
    """eq. 28 turned around: Rt diag(k) (i_l − i_e) − Wc' χ' = Wc_M Mc − (S_l − S_e), on a pair's block."""
    def rows(b: RunBlock) -> GainRows:
        m, e = b.motion, b.empty
        return GainRows(m.Y - e.Y, m.Phi[:, :, :9], m.Phi[:, :, 9] * mass - (m.Phi[:, :, 10] - e.Phi[:, :, 0]),
                        m.rows(drop) & e.rows(False), b.first)
    return rows


def _global_rows(nb: int, mass: float, drop: bool):
    """eq. 29 with currents: Rt diag(k) i − Wb β − Wc' χ' = Wc_M Mc − S (an empty run's Wc is 0)."""
    def rows(b: RunBlock) -> GainRows:
        m = b.motion
        Wc = m.Phi[:, :, nb:nb + 10] if b.loaded else np.zeros(m.Phi.shape[:2] + (10,))
        return GainRows(m.Y, np.concatenate([m.Phi[:, :, :nb], Wc[:, :, :9]], axis=2),
                        Wc[:, :, 9] * mass - m.Phi[:, :, -1], m.rows(drop), b.first)
    return rows


def _fit(robot: rx90sym.Robot, runs: Runs, columns: dict, rows: Any, names: tuple[str, ...], Rt: np.ndarray,
         free: list[int], k_fixed: np.ndarray, cx: int, method: str, iterations: int, seed: int | None,
         client: Any) -> tuple[IdentificationResult, np.ndarray]:
    """The IV fit on the sums of one pass (identify.gains.iv_fit), then a second pass for the segment
    bootstrap with the final instruments: (fit, bootstrap σ of its unknowns)."""
    sums = GainSums(Rt, free, k_fixed, cx)
    for block in run_blocks(robot, runs, columns, rows, client):
        sums.add(block)
    fit, instruments = iv_fit(sums, names, method, iterations)
    if seed is None:
        return fit, np.full(len(names), np.nan)
    boot = SegmentBootstrap(runs.samples, max(1, int(round(BLOCK_S * runs.rate))), robot.n, len(names), DRAWS, seed)
    for block in run_blocks(robot, runs, columns, rows, client):
        for j in range(robot.n):
            idx, A, y, Z = sums.bootstrap_rows(block, instruments, j)
            boot.add(j, block.first + idx, A, y, Z)
    return fit, boot.std(fit.weights)


def _same_motion(empty, loaded, position_tol, processing, block, *, robot, Rt, mass, free, k_fixed, iterations, seed,
                 client, spring):
    runs = open_runs(robot, empty, loaded, processing, block, paired=True, position_tol=position_tol,
                     instead="--method global")
    columns = {"loaded": RunColumns(robot, spring=spring), "empty": RunColumns(robot, payload=False, spring=spring)}
    names = tuple(f"K{j + 1}" for j in free) + _OTHER_PAYLOAD
    drop = processing.min_velocity is not None and drops_rest(processing.rest)
    fit = _fit(robot, runs, columns, _same_motion_rows(mass, drop), names, Rt, free, k_fixed, 9, "same-motion",
               iterations, seed, client)
    return fit, runs.pairs, None, None


def _global(empty, loaded, offsets, base, processing, block, *, robot, Rt, mass, free, k_fixed, iterations, seed,
            client, spring):
    if offsets and not robot.offsets:
        robot = robot.with_options(offsets=True)
        if base is not None and "OFF1" not in base.names:
            base = None  # the base parameters of the robot without offsets
    base = base if base is not None else rx90sym.base_parameters(robot)
    nb = base.nb
    runs = open_runs(robot, empty, loaded, processing, block)
    columns = {"loaded": RunColumns(robot, base, spring=spring), "empty": RunColumns(robot, base, False, spring)}
    names = tuple(f"K{j + 1}" for j in free) + tuple(base.names) + _OTHER_PAYLOAD
    drop = processing.min_velocity is not None and drops_rest(processing.rest)
    fit, boot = _fit(robot, runs, columns, _global_rows(nb, mass, drop), names, Rt, free, k_fixed, nb + 9, "global",
                     iterations, seed, client)
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
