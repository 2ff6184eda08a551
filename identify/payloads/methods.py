"""Identification of a payload's 10 inertial parameters (paper section IV, eqs. 21-29).

The payload (XXc ... Mc, frame n about its origin) adds to link n's inertial parameters, so its
observation matrix Wc is the ten columns of link n in the standard regressor (eq. 21).

- method 1 (eqs. 21-22): known robot parameters, chi_c = Wc+ (Y_T - W beta);
- method 2 (eqs. 23-27): re-identify with the load; the payload solves the grouping relations
  Delta beta = K_c chi_c in the least-squares sense (K_c: the columns of link n's inertial
  parameters in the symbolic K, so the relations are derived, not typed in);
- method 3 (eq. 28): same motion empty and loaded, chi_c = Wc+ (Y_T - Y_v);
- method 4 (eq. 29): global system of empty and loaded motions, which may differ.

Every method reads, filters and fits its runs block by block on the rows identify makes (methods
1, 3, 4: identify.payloads.systems; method 2: two identify.fit), any length, any number of segments,
memory bounded by the block. Each has a constrained variant (payload pseudo-inertia PSD, mass within
a scale's tolerance), and identify.monitor.payload.PayloadMonitor updates method 4 after every new
loaded motion (the paper's conclusion).
"""
from __future__ import annotations

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
from identify.estimation.least_squares import compress, solve_system
from identify.fitting.run_blocks import RunColumns, Runs, open_runs
from identify.io.blocks import DEFAULT_BLOCK, check_block
from identify.observation.defaults import DEFAULT_DECIMATE_TO
from identify.observation.processing import Processing
from identify.payloads.defaults import MASS_TOL
from identify.payloads.robot_params import known_robot
from identify.payloads.systems import drop_rest, fold_rows, method_1_rows, method_3_rows, method_4_rows
from identify.signal.pairing import POSITION_TOLERANCE
from identify.estimation.results import IdentificationResult
from identify.payloads.result import PayloadResult

METHODS = (1, 2, 3, 4)
# A loaded motion must move the wrist: otherwise Wc is (nearly) rank deficient (eq. 22).
MIN_WRIST_MOTION = 0.05  # rad, range of each of joints 4..6 over all loaded motions together
#: The processing of the payload methods (keyword arguments of :func:`payload`) and its defaults: the
#: automatic cut-off, decimation to 50 Hz, no rest threshold (rest "drop" once one is given), no delay.
PROCESSING = {"cutoff": None, "decimate_to": DEFAULT_DECIMATE_TO, "min_velocity": None, "rest": "drop", "delay": 0.0,
              "spring": True}


def recording_list(recs: Any) -> list:
    """``recs`` as a list of recordings or files (None: none; one: a list of it)."""
    if recs is None:
        return []
    return list(recs) if isinstance(recs, (list, tuple)) else [recs]


def check_wrist_motion(robot: rx90sym.Robot, q_range: np.ndarray, sources: Sequence[str]) -> None:
    """Refuse loaded motions whose wrist joints all move by less than MIN_WRIST_MOTION rad (eq. 22);
    ``q_range``: (2, n) smallest and largest position of each joint over them [rad]."""
    wrist = list(range(max(0, robot.n - 3), robot.n))
    span = q_range[1, wrist] - q_range[0, wrist]
    if np.all(span < MIN_WRIST_MOTION):
        raise ValueError(f"loaded motion(s) {list(sources)}: joints {[w + 1 for w in wrist]} move by at most "
                         f"{span.max():.3g} rad; the payload is not excited (need > {MIN_WRIST_MOTION} rad on at "
                         f"least one of them)")


def _processing(options: Mapping[str, Any], fit_processing: Mapping[str, Any] | None) -> dict[str, Any]:
    """The processing asked (``options``), defaults :data:`PROCESSING`; with a fit's (method 1), the fit's,
    an option given beside it only when it is the same."""
    unknown = sorted(set(options) - set(PROCESSING))
    if unknown:
        raise ValueError(f"payload: unknown option(s) {unknown}; the processing options are {sorted(PROCESSING)}")
    if fit_processing is None:
        return {**PROCESSING, **options}
    for key, value in options.items():
        own = fit_processing[key]
        same = value == own or (isinstance(value, float) and isinstance(own, float) and np.isclose(value, own,
                                                                                                     rtol=1e-12))
        if not same:
            raise ValueError(f"payload method 1: {key}={value!r} given, but the fit given as robot_params was made with "
                             f"{key}={own!r}: its rows are those of its own processing (give the same, or leave it out)")
    return dict(fit_processing)


def processing_of(options: Mapping[str, Any]) -> Processing:
    """The :class:`~identify.observation.processing.Processing` of the processing ``options`` (defaults
    :data:`PROCESSING`; an unknown option refused)."""
    p = _processing(options, None)
    return Processing(cutoff=p["cutoff"], decimate_to=p["decimate_to"], min_velocity=p["min_velocity"], rest=p["rest"],
                      delay=float(p["delay"]), spring=bool(p["spring"]))


def read_block(block: int | None) -> int:
    """Raw samples read at a time: ``block`` checked, or the default."""
    return check_block(block) if block is not None else DEFAULT_BLOCK


# --------------------------------------------------------------------------------------------
# The methods
# --------------------------------------------------------------------------------------------
@one_blas_thread()
def payload(robot: rx90sym.Robot, method: int, empty: Sequence[Any] = (), loaded: Sequence[Any] = (),
            robot_params: Any = None, base: Any = None, a_priori: Mapping[str, float] | str | None = None,
            constrained: bool = False, mass: float | None = None, mass_tol: float = MASS_TOL,
            position_tol: float = POSITION_TOLERANCE, bootstrap_seed: int | None = 0, *, convention: str | None = None,
            gains: Any = None, block: int | None = None, client: Any = None, **options: Any) -> PayloadResult:
    """Identify the payload by method 1, 2, 3 or 4 of section IV, block by block on logs of any length.

    empty / loaded: runs without / with the payload (recordings, or recording files read block by block:
    ``block`` raw samples at a time, memory bounded by the block; ``convention``, ``gains``: how files
    are read, gains turning currents into torques); robot_params: method 1's known robot, a
    :class:`~identify.Fit` or its file (its columns, torque offsets included, and its processing, gains
    and convention: identify.payloads.robot_params), its result, or a dict of base or standard
    parameter values; a_priori: CAD values (dict or bundled payload name) to print beside the
    estimates; constrained: impose the payload pseudo-inertia PSD and, when ``mass`` [kg] is given
    (weighed), |Mc - mass| <= mass_tol [kg]; position_tol [rad]: method 3 pairs each empty run with its
    loaded run segment by segment (identify.signal.pairing: lag, common part; runs of different
    segment counts refused) and refuses pairs whose positions still differ by more; options: the
    processing, :data:`PROCESSING` (cutoff [Hz], decimate_to [Hz], min_velocity [rad/s], rest, delay
    [s], spring; an identification's are ``Fit.filtering()``); client: a ``dask.distributed.Client``
    running the blocks; bootstrap_seed: seed of the segment bootstrap beside eq. 13's sigma
    (identify.estimation.bootstrap; None: no bootstrap).
    BLAS on one thread inside the call, the caller's count back after it (rx90sym.threads).
    """
    if method not in METHODS:
        raise ValueError(f"payload: method must be 1, 2, 3 or 4, got {method!r}")
    empty, loaded = recording_list(empty), recording_list(loaded)
    if not loaded:
        raise ValueError("payload: no loaded recording given")
    if method in (2, 3, 4) and not empty:
        raise ValueError(f"payload method {method} needs at least one empty (unloaded) recording")
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
    known = known_robot(robot, base, robot_params) if method == 1 else None
    p = _processing(options, known.processing if known is not None else None)
    if known is not None:
        gains = gains if gains is not None else known.gains
        convention = convention if convention is not None else known.convention
    read = dict(convention=convention, gains=gains, block=block, client=client)
    pairs: tuple = ()
    if method == 2:
        fit, robot_fit, boot = _method_2(robot, base, empty, loaded, p, bootstrap_seed, **read)
    else:
        runs = open_runs(robot, empty, loaded, processing_of(p), read_block(block), paired=method == 3,
                         position_tol=position_tol, convention=convention, gains=gains)
        check_wrist_motion(robot, runs.q_range, [s.source for s in runs.loaded_scans])
        solve = {1: _method_1, 3: _method_3, 4: _method_4}[method]
        fit, robot_fit, boot = solve(robot, base, runs, known, bootstrap_seed, client)
        pairs = runs.pairs
    values, std, rel = payload_estimates(fit)
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


def _method_1(robot, base, runs: Runs, known, seed, client):
    # eq. 22: the robot's known part (the fit's own columns) moved to the right-hand side.
    columns = RunColumns(robot, known.base)
    folded = fold_rows(robot, runs, {"loaded": columns}, method_1_rows(known.beta, drop_rest(runs)), PAYLOAD_NAMES,
                       seed, client)
    fit = folded.solve()
    return fit, None, folded.bootstrap_std(fit)


def _method_3(robot, base, runs: Runs, known, seed, client):
    # eq. 28: the empty run's torques (its Y alone: no column) replace W chi.
    columns = {"loaded": RunColumns(robot), "empty": RunColumns(robot, payload=False)}  # the empty run: its torques
    folded = fold_rows(robot, runs, columns, method_3_rows(drop_rest(runs)), PAYLOAD_NAMES, seed, client)
    fit = folded.solve()
    return fit, None, folded.bootstrap_std(fit)


def _method_4(robot, base, runs: Runs, known, seed, client):
    names = tuple(base.names) + PAYLOAD_NAMES
    columns = {"empty": RunColumns(robot, base, payload=False), "loaded": RunColumns(robot, base)}
    folded = fold_rows(robot, runs, columns, method_4_rows(drop_rest(runs)), names, seed, client)
    fit = folded.solve()
    boot = folded.bootstrap_std(fit)
    return fit, result_subset(fit, base.names), None if boot is None else boot[[names.index(n) for n in PAYLOAD_NAMES]]


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


def _method_2(robot, base, empty, loaded, p, seed, *, convention, gains, block, client):
    from identify.fitting.fit import fit

    # One processing for both runs (their difference is the payload): not chosen on each run.
    processing = Processing(**{"estimate_delay": False, "cross_validate": False, **p})
    options = dict(base=base, gains=gains, convention=convention, block=block, client=client)
    loaded_fit = fit(robot, loaded, processing, bootstrap_seed=None if seed is None else seed + 1, **options)
    check_wrist_motion(robot, loaded_fit.passes.q_range, loaded_fit.passes.sources)
    empty_fit = fit(robot, empty, processing, bootstrap_seed=seed, **options)
    fit_v, fit_t = empty_fit.result, loaded_fit.result
    if fit_v.names != fit_t.names:
        raise ValueError(f"payload method 2: the empty and loaded fits have different columns ({fit_v.names} and "
                         f"{fit_t.names}): their difference is not the payload's")
    delta = fit_t.values - fit_v.values                    # eq. 23
    cov = fit_t.covariance + fit_v.covariance
    Kc = grouping_relations(robot, base)
    rows = np.flatnonzero(np.any(Kc != 0, axis=1))         # only relations that hold the payload
    at = [fit_t.names.index(base.names[r]) for r in rows]
    # Generalised LS on eqs. 24-27: each relation weighted by the precision of its Delta beta,
    # so that, e.g., Mc leans on the well identified MX2R rather than on ZZ1R.
    C = cov[np.ix_(at, at)]
    L = np.linalg.cholesky(C)
    A = np.linalg.solve(L, Kc[rows])
    b = np.linalg.solve(L, delta[at])
    system = compress(A, b)
    sol = solve_system(system, PAYLOAD_NAMES, method="payload-2")
    # The covariance of Delta beta is known (not estimated from this small system): eq. 13 with
    # sigma_rho = 1 for whitened relations.
    Rinv = np.linalg.inv(system.R)
    covc = Rinv @ Rinv.T
    std = np.sqrt(np.diag(covc))
    result = IdentificationResult(PAYLOAD_NAMES, sol.values, std, 100 * std / np.abs(sol.values),
                                  sol.sigma_rho, sol.cond, sol.cond_unweighted, np.zeros(0), np.zeros(0),
                                  len(rows), "payload-2", covc)
    boot = None
    if seed is not None:
        # Each run's segment bootstrap (independent draws: two experiments), their difference per draw
        # (eq. 23) through the same whitened relations (eqs. 24-27): the spread of the payload.
        deltas = (loaded_fit.passes.bootstrap_draws - empty_fit.passes.bootstrap_draws)[:, at]
        deltas = deltas[~np.isnan(deltas).any(axis=1)]  # rank-deficient draws
        if deltas.shape[0] < 2:
            boot = np.full(len(PAYLOAD_NAMES), np.nan)
        else:
            chi, *_ = np.linalg.lstsq(A, np.linalg.solve(L, deltas.T), rcond=None)
            boot = np.nanstd(chi.T, axis=0, ddof=1)
    return result, fit_t, boot


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
