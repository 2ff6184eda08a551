"""Identification of a payload's 10 inertial parameters (paper section IV, eqs. 21-29).

The payload (XXc ... Mc, frame n about its origin) adds to link n's inertial parameters, so its
observation matrix Wc is the ten columns of link n in the standard regressor (eq. 21).

- method 1 (eqs. 21-22): known robot parameters, chi_c = Wc+ (Y_T - W beta);
- method 2 (eqs. 23-27): re-identify with the load; the payload solves the grouping relations
  Delta beta = K_c chi_c in the least-squares sense (K_c: the columns of link n's inertial
  parameters in the symbolic K, so the relations are derived, not typed in);
- method 3 (eq. 28): same motion empty and loaded, chi_c = Wc+ (Y_T - Y_v);
- method 4 (eq. 29): global system of empty and loaded motions, which may differ.

Each has a constrained variant (payload pseudo-inertia PSD, mass within a scale's tolerance),
and identify.monitor.payload.PayloadMonitor updates method 4 after every new loaded motion (the
paper's conclusion).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import cvxpy as cp
import numpy as np

import rx90sym
from rx90sym.parameters import PAYLOAD_NAMES
from rx90sym.physical import DEFAULT_MARGIN
from rx90sym.rigid_body import RigidBody, physical_problem
from rx90sym.threads import one_blas_thread

from identify.estimation.consistency import ConsistencyError, pseudo_inertia
from identify.estimation.consistency.fit import SOLVE_FACTOR
from identify.estimation.bootstrap import bootstrap_estimates, bootstrap_std
from identify.estimation.least_squares import compress, solve_system, weighted_least_squares
from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.observation.processing import Processing
from identify.payloads.defaults import MASS_TOL
from identify.signal.filtering import choose_cutoff
from identify.observation.matrix import column_regressor, filtered_motion, stack_rows
from identify.signal.pairing import POSITION_TOLERANCE, PairedRuns, pair_runs
from identify.estimation.results import IdentificationResult
from identify.payloads.result import PayloadResult

METHODS = (1, 2, 3, 4)
# A loaded motion must move the wrist: otherwise Wc is (nearly) rank deficient (eq. 22).
MIN_WRIST_MOTION = 0.05  # rad, range of each of joints 4..6 over all loaded motions together


def recording_list(recs: Any) -> list:
    """``recs`` as a list of recordings (None: none; one recording: a list of it)."""
    if recs is None:
        return []
    return list(recs) if isinstance(recs, (list, tuple)) else [recs]


def check_joint_count(robot: rx90sym.Robot, recs: Sequence[Any], what: str) -> None:
    """Refuse a recording (``what``: "empty" or "loaded") with another joint count or of another robot."""
    for rec in recs:
        if rec.q.shape[1] != robot.n:
            raise ValueError(f"{what} recording {rec.source}: {rec.q.shape[1]} joints, robot "
                             f"{robot.name!r} has {robot.n}")
        if rec.robot and rec.robot != robot.name:
            raise ValueError(f"{what} recording {rec.source} is of robot {rec.robot!r}, not {robot.name!r}")


def check_wrist_motion(robot: rx90sym.Robot, loaded: Sequence[Any]) -> None:
    """Refuse loaded motions whose wrist joints all move by less than MIN_WRIST_MOTION rad (eq. 22)."""
    q = np.concatenate([np.asarray(r.q) for r in loaded])
    wrist = list(range(max(0, robot.n - 3), robot.n))
    span = q[:, wrist].max(axis=0) - q[:, wrist].min(axis=0)
    if np.all(span < MIN_WRIST_MOTION):
        raise ValueError(f"loaded motion(s) {[r.source for r in loaded]}: joints "
                         f"{[w + 1 for w in wrist]} move by at most {span.max():.3g} rad; the payload "
                         f"is not excited (need > {MIN_WRIST_MOTION} rad on at least one of them)")


def payload_motions(robot: rx90sym.Robot, recs: Sequence[Any], columns: Sequence[int], options: Mapping[str, Any]):
    """Filtered motions with the standard regressor's ``columns`` (indices) as Phi."""
    _, regressor = column_regressor(robot, columns=[robot.parameter_names[i] for i in columns])
    return [filtered_motion(robot, r, options.get("cutoff"), options.get("decimate_to", DEFAULT_DECIMATE_TO),
                            options.get("spring", True), regressor, delay=options.get("delay", 0.0))
            for r in recs]


def payload_rows(blocks: Sequence[np.ndarray], Y: Sequence[np.ndarray], motions: Sequence[Any],
                 options: Mapping[str, Any]):
    """Rows grouped per joint; a joint's rows near rest are dropped when options has min_velocity."""
    return stack_rows(blocks, Y, options.get("min_velocity"), [m.dq for m in motions])


def _robot_vector(robot: rx90sym.Robot, base: Any, robot_params: Any) -> np.ndarray:
    """Base parameter values from an IdentificationResult, a dict of base or standard names."""
    if robot_params is None:
        raise ValueError("method 1 needs the robot's parameters (robot_params): an identification "
                         "result, or a dict of base or standard parameter values")
    values = robot_params.as_dict() if hasattr(robot_params, "as_dict") else dict(robot_params)
    if set(values) <= set(robot.parameter_names) and not set(values) <= set(base.names):
        return base.K @ robot.parameter_vector(values, strict=False)
    unknown = set(values) - set(base.names)
    if unknown:
        raise ValueError(f"robot_params: {sorted(unknown)[:5]} are not base parameters of {robot.name!r}")
    # Parameters of the base set left out (e.g. an essential set) count as 0.
    return np.array([values.get(n, 0.0) for n in base.names])


# --------------------------------------------------------------------------------------------
# The methods
# --------------------------------------------------------------------------------------------
@one_blas_thread()
def payload(robot: rx90sym.Robot, method: int, empty: Sequence[Any] = (), loaded: Sequence[Any] = (),
            robot_params: Any = None, base: Any = None, a_priori: Mapping[str, float] | str | None = None,
            constrained: bool = False, mass: float | None = None, mass_tol: float = MASS_TOL,
            position_tol: float = POSITION_TOLERANCE, bootstrap_seed: int | None = 0, **options: Any) -> PayloadResult:
    """Identify the payload by method 1, 2, 3 or 4 of section IV.

    empty / loaded: recordings without / with the payload; robot_params: the robot's base (or
    standard) parameters for method 1; a_priori: CAD values (dict or bundled payload name) to
    print beside the estimates; constrained: impose the payload pseudo-inertia PSD and, when
    ``mass`` [kg] is given (weighed), |Mc - mass| <= mass_tol [kg]; position_tol [rad]: method 3
    pairs each empty run with its loaded run in time (identify.signal.pairing: lag, common part) and
    refuses pairs whose positions still differ by more; options: cutoff, decimate_to, spring,
    min_velocity, delay (see identify.observation_matrix; an identification's are
    ``FitModel.filtering()``); bootstrap_seed: seed of the segment bootstrap beside eq. 13's sigma
    (identify.estimation.bootstrap; methods 1, 3 and 4; None: no bootstrap).
    BLAS on one thread inside the call, the caller's count back after it (rx90sym.threads).
    """
    if method not in METHODS:
        raise ValueError(f"payload: method must be 1, 2, 3 or 4, got {method!r}")
    empty, loaded = recording_list(empty), recording_list(loaded)
    if not loaded:
        raise ValueError("payload: no loaded recording given")
    if method in (2, 3, 4) and not empty:
        raise ValueError(f"payload method {method} needs at least one empty (unloaded) recording")
    check_joint_count(robot, empty, "empty")
    check_joint_count(robot, loaded, "loaded")
    check_wrist_motion(robot, loaded)
    if isinstance(a_priori, str):
        a_priori = rx90sym.load_payload(a_priori)
    base = base if base is not None else rx90sym.base_parameters(robot)
    if constrained and method == 2:
        raise ValueError("payload method 2 has no constrained variant here: constrain method 4, "
                         "which solves the same relations on the data")
    if method == 1 and empty:
        raise ValueError("payload method 1 uses the robot's known parameters and no empty recordings; "
                         "give robot_params and leave empty out")
    if method != 1 and robot_params is not None:
        raise ValueError(f"payload method {method} identifies the robot's parameters itself; "
                         "robot_params is for method 1 only")
    pairs: list[PairedRuns] = []
    if method == 3:
        empty, loaded, pairs = _paired(empty, loaded, position_tol)
    solve = {1: _method_1, 2: _method_2, 3: _method_3, 4: _method_4}[method]
    fit, robot_fit, rows = solve(robot, base, empty, loaded, robot_params=robot_params, options=options)
    values, std, rel = payload_estimates(fit)
    boot = None
    if callable(rows) and bootstrap_seed is not None:  # method 2: a difference of two fits
        boot = rows(bootstrap_seed)
    elif rows is not None and bootstrap_seed is not None:
        rate = options.get("decimate_to", DEFAULT_DECIMATE_TO) or loaded[0].rate
        boot = bootstrap_std(*rows, fit.weights, rate, bootstrap_seed)[[fit.names.index(n) for n in PAYLOAD_NAMES]]
    if constrained:
        values = _constrained(fit, mass, mass_tol)
        rel = 100 * std / np.abs(values)
    if robot.urdf is not None:
        values, std, rel = estimates_in_tip_frame(robot, fit, values, std)
    return PayloadResult(method, PAYLOAD_NAMES, values, std, rel, fit, robot_fit,
                         dict(a_priori) if a_priori else None, constrained, tuple(pairs), boot)


def estimates_in_tip_frame(robot: rx90sym.Robot, fit: IdentificationResult, values: np.ndarray, std: np.ndarray
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frame-n estimates in the payload frame of a URDF robot (its tip link)."""
    idx = [fit.names.index(n) for n in PAYLOAD_NAMES]
    cov = fit.covariance[np.ix_(idx, idx)] if fit.covariance is not None else np.diag(std ** 2)
    values, std = rx90sym.urdf.payload_in_tip_frame(robot, values, cov)
    return values, std, 100 * std / np.abs(values)


def payload_estimates(fit: IdentificationResult) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(values, σ, relative σ in %) of the payload parameters (PAYLOAD_NAMES) of ``fit``."""
    idx = [fit.names.index(n) for n in PAYLOAD_NAMES]
    return fit.values[idx], fit.std[idx], fit.rel_std_pct[idx]


def _method_1(robot, base, empty, loaded, robot_params, options, **_):
    beta = _robot_vector(robot, base, robot_params)
    cols = list(base.independent) + list(rx90sym.payload_regressor_columns(robot))
    motions = payload_motions(robot, loaded, cols, options)
    nb = base.nb
    # eq. 22: the robot's known part is moved to the left-hand side.
    Y = [m.Y - m.Phi[:, :, :nb] @ beta for m in motions]
    W, Yr, joint, samples = payload_rows([m.Phi[:, :, nb:] for m in motions], Y, motions, options)
    return weighted_least_squares(W, Yr, joint, PAYLOAD_NAMES), None, (W, Yr, joint, samples)


def _paired(empty, loaded, position_tol):
    """Method 3: each loaded run on the time grid of the same motion run empty (lag, common part)."""
    if len(empty) != len(loaded):
        raise ValueError(f"payload method 3 pairs each loaded motion with the same motion run empty: "
                         f"got {len(empty)} empty and {len(loaded)} loaded recordings")
    pairs = [pair_runs(e, l, position_tol) for e, l in zip(empty, loaded)]
    return [p.empty for p in pairs], [p.loaded for p in pairs], pairs


def _method_3(robot, base, empty, loaded, options, **_):
    cols = list(rx90sym.payload_regressor_columns(robot))
    # One cut-off for both runs of a pair, so that the same samples are kept and compared.
    cutoff = options.get("cutoff") or max(choose_cutoff(np.asarray(r.q), r.rate) for r in loaded)
    same = {**options, "cutoff": cutoff}
    m_l = payload_motions(robot, loaded, cols, same)
    m_e = payload_motions(robot, empty, cols, same)
    # eq. 28: the empty run's torques replace W chi.
    W, Y, joint, samples = payload_rows([m.Phi for m in m_l], [a.Y - b.Y for a, b in zip(m_l, m_e)], m_l, options)
    return weighted_least_squares(W, Y, joint, PAYLOAD_NAMES), None, (W, Y, joint, samples)


def _global_rows(robot, base, empty, loaded, options):
    """Rows of eq. 29: [W_v 0; W_T W_c] and [Y_v; Y_T], grouped per joint."""
    cols = list(base.independent) + list(rx90sym.payload_regressor_columns(robot))
    nb = base.nb
    m_e = payload_motions(robot, empty, cols, options)
    m_l = payload_motions(robot, loaded, cols, options)
    blocks = [np.concatenate([m.Phi[:, :, :nb], np.zeros_like(m.Phi[:, :, nb:])], axis=2) for m in m_e]
    blocks += [m.Phi for m in m_l]
    return payload_rows(blocks, [m.Y for m in m_e + m_l], m_e + m_l, options)


def _method_4(robot, base, empty, loaded, options, **_):
    W, Y, joint, samples = _global_rows(robot, base, empty, loaded, options)
    names = tuple(base.names) + PAYLOAD_NAMES
    fit = weighted_least_squares(W, Y, joint, names)
    return fit, result_subset(fit, base.names), (W, Y, joint, samples)


def result_subset(fit: IdentificationResult, names: Sequence[str]) -> IdentificationResult:
    """The part of ``fit`` on the parameters ``names`` (values, σ, covariance)."""
    idx = [fit.names.index(n) for n in names]
    cov = fit.covariance[np.ix_(idx, idx)] if fit.covariance is not None else None
    return IdentificationResult(tuple(names), fit.values[idx], fit.std[idx], fit.rel_std_pct[idx],
                                fit.sigma_rho, fit.cond, fit.cond_unweighted, fit.residual_rms,
                                fit.weights, fit.rows, fit.method, cov)


def grouping_relations(robot: rx90sym.Robot, base: Any) -> np.ndarray:
    """K_c (nb x 10): how the payload enters the base parameters, Delta beta = K_c chi_c (eqs. 24-27).

    Read off the symbolic K: the payload adds to link n's ten inertial parameters."""
    return base.K[:, list(rx90sym.payload_regressor_columns(robot))]


def _method_2(robot, base, empty, loaded, options, **_):
    from identify.fitting.fit import fit

    kw = {k: options[k] for k in ("cutoff", "decimate_to", "spring", "min_velocity", "delay") if k in options}
    # One processing for both runs (their difference is the payload): not chosen on each run.
    processing = Processing(**{"min_velocity": None, "rest": "drop", "estimate_delay": False, "cross_validate": False,
                               **kw})
    empty_fit, loaded_fit = (fit(robot, runs, processing, base=base, bootstrap_seed=None) for runs in (empty, loaded))
    fit_v, fit_t = empty_fit.result, loaded_fit.result
    delta = fit_t.values - fit_v.values                    # eq. 23
    cov = fit_t.covariance + fit_v.covariance
    Kc = grouping_relations(robot, base)
    rows = np.flatnonzero(np.any(Kc != 0, axis=1))         # only relations that hold the payload
    # Generalised LS on eqs. 24-27: each relation weighted by the precision of its Delta beta,
    # so that, e.g., Mc leans on the well identified MX2R rather than on ZZ1R.
    C = cov[np.ix_(rows, rows)]
    L = np.linalg.cholesky(C)
    A = np.linalg.solve(L, Kc[rows])
    b = np.linalg.solve(L, delta[rows])
    system = compress(A, b)
    sol = solve_system(system, PAYLOAD_NAMES, method="payload-2")
    # The covariance of Delta beta is known (not estimated from this small system): eq. 13 with
    # sigma_rho = 1 for whitened relations.
    Rinv = np.linalg.inv(system.R)
    covc = Rinv @ Rinv.T
    std = np.sqrt(np.diag(covc))
    fit = IdentificationResult(PAYLOAD_NAMES, sol.values, std, 100 * std / np.abs(sol.values),
                               sol.sigma_rho, sol.cond, sol.cond_unweighted, np.zeros(0), np.zeros(0),
                               len(rows), "payload-2", covc)

    def bootstrap(seed: int) -> np.ndarray:
        # Each run's segment bootstrap (independent draws: two experiments), their difference per
        # draw (eq. 23) through the same whitened relations (eqs. 24-27): the spread of the payload.
        draws = [bootstrap_estimates(f.observation.W, f.observation.Y, f.observation.joint, f.observation.samples,
                                     f.result.weights, f.observation.rate, seed + k)
                 for k, f in enumerate((empty_fit, loaded_fit))]
        deltas = (draws[1] - draws[0])[:, rows]
        deltas = deltas[~np.isnan(deltas).any(axis=1)]  # rank-deficient draws
        if deltas.shape[0] < 2:
            return np.full(len(PAYLOAD_NAMES), np.nan)
        chi, *_ = np.linalg.lstsq(A, np.linalg.solve(L, deltas.T), rcond=None)
        return np.nanstd(chi.T, axis=0, ddof=1)

    return fit, fit_t, bootstrap


def _constrained(fit: IdentificationResult, mass: float | None, mass_tol: float) -> np.ndarray:
    """Refit with the payload's pseudo-inertia PSD and the weighed mass (cvxpy, Clarabel)."""
    system = fit.system
    if system is None:
        raise ValueError("constrained payload needs the compressed system of the fit")
    x = cp.Variable(len(fit.names))
    idx = [fit.names.index(n) for n in PAYLOAD_NAMES]
    scale = max(float(np.linalg.norm(system.z)), 1e-12)
    objective = cp.Minimize(cp.sum_squares(system.R @ x - system.z) / scale**2)
    # The consistent fit's margin (rx90sym.physical): asked for ten times, checked below, so that an
    # export (physical_problem, margin 0) never refuses a constrained payload for solver error.
    cons = [pseudo_inertia(x[idx]) >> SOLVE_FACTOR * DEFAULT_MARGIN * np.eye(4)]
    if mass is not None:
        if mass <= 0 or mass_tol < 0:
            raise ValueError(f"constrained payload: mass must be > 0 and mass_tol >= 0, got {mass}, {mass_tol}")
        cons += [cp.abs(x[idx[-1]] - mass) <= mass_tol]
    prob = cp.Problem(objective, cons)
    try:
        prob.solve(solver="CLARABEL")
    except cp.error.SolverError as exc:
        raise ConsistencyError(f"constrained payload: solver failed ({exc})", status="solver_error",
                               solver="CLARABEL") from None
    if prob.status != cp.OPTIMAL:
        raise ConsistencyError(f"constrained payload: solver status {prob.status}", status=str(prob.status),
                               solver="CLARABEL")
    values = np.asarray(x.value)[idx]
    problem = physical_problem(RigidBody.from_vector(values), DEFAULT_MARGIN)
    if problem is not None:
        raise ConsistencyError(f"constrained payload: solution fails the external check ({problem})",
                               status="inaccurate", solver="CLARABEL")
    return values
