"""Multi-start IPOPT optimisation of an excitation trajectory (exact CasADi derivatives).

Decision variables: the free coefficients Z of a rest-to-rest parameterisation (Fourier series or
via points), so rest at both ends holds by construction. Stages, each an IPOPT solve warm-started
from the previous one: the cond surrogate f_p for each p of ``OptimiserOptions.p_schedule``
(p = 0: the scale-free log-determinant; see criterion.py). IPOPT uses a limited-memory (L-BFGS) Hessian:
exact second derivatives of the criterion through the mapped regressor would cost far more per
iteration than they save in iterations for ~50 variables. The per-sample functions (regressor and
its adjoint, envelope rows, torques and their Jacobians) run as compiled C (kernels.py,
criterion_callback.py; ``OptimiserOptions(compiled=False)``: one CasADi graph in its VM).

Constraints: the kinematic limits (linear in Z) and the safety envelope's rows (heights, capsule
clearances, Cartesian speeds: envelope_rows.py, whose Jacobian goes through the joint samples) on a
grid fine enough for the margins to cover what happens between samples; the torque limits (nonlinear, with the most expensive
Jacobian, and rarely active on the RX90) lazily, cutting-plane style: every start is verified on the fine grid
(true limits, no margin), and if a limit is exceeded the worst times of each violated stretch join
the constraint set and the last stage is re-solved (``repairs`` rounds) from the iterate pulled
towards the centre pose until it holds the enlarged set (:meth:`_Problem.pulled_inside`). Only verified starts
compete; if none is feasible the request is an error.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import casadi as ca
import numpy as np

from .constraints import (Margins, check_limits, kinematic_constraints, position_bounds, range_centre,
                          torque_rows, violation_times)
from .envelope_rows import sample_rows, through_samples
from .criterion import symbols_like, gram_expression, regressor_samples, smooth_friction_regressor
from .criterion_callback import criterion_callbacks, evaluable_on_sx
from .objective import numeric_information
from .model import ExcitationModel
from .options import MAX_COND, OptimiserOptions, check_request
from .trajectory import Form, sample_times

_GOOD_STATUS = ("Solve_Succeeded", "Solved_To_Acceptable_Level", "Maximum_Iterations_Exceeded",
                "User_Requested_Stop", "Maximum_WallTime_Exceeded", "Search_Direction_Becomes_Too_Small")


# --------------------------------------------------------------------------- NLP
class _Deadline(ca.Callback):
    """IPOPT iteration callback that stops the solve once a wall-clock deadline has passed."""

    def __init__(self, nx: int, ng: int) -> None:
        ca.Callback.__init__(self)
        self.deadline = float("inf")
        self._sizes = {"f": 1, "x": nx, "lam_x": nx, "g": ng, "lam_g": ng, "lam_p": 0}
        self.construct("deadline", {})

    def get_n_in(self) -> int:
        return ca.nlpsol_n_out()

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return ca.nlpsol_out(i)

    def get_name_out(self, i: int) -> str:
        return "stop"

    def get_sparsity_in(self, i: int) -> ca.Sparsity:
        size = self._sizes[ca.nlpsol_out(i)]
        return ca.Sparsity.scalar() if ca.nlpsol_out(i) == "f" else ca.Sparsity.dense(size, 1)

    def eval(self, arg: Any) -> list[int]:
        return [1 if time.time() > self.deadline else 0]


class _Problem:
    """The NLP of one (model, form, options, constraint times): IPOPT solvers, one per stage."""

    def __init__(self, model: ExcitationModel, form: Form, options: OptimiserOptions,
                 kinematic_times: np.ndarray, torque_times: np.ndarray) -> None:
        self.model, self.form, self.options = model, form, options
        self.rest = form.rest_basis()
        self.n_free = self.rest.shape[1]
        self.kinematic_times = np.asarray(kinematic_times, dtype=float)
        self.torque_times = np.asarray(torque_times, dtype=float)
        x = ca.MX.sym("x", self.n_free * model.n)
        z = ca.reshape(x, self.n_free, model.n)  # column-major: x = Z.flatten(order="F")

        def samples(times: np.ndarray) -> tuple[ca.MX, ca.MX, ca.MX]:
            if times.size == 0:
                return tuple(ca.MX(model.n, 0) for _ in range(3))
            return tuple(ca.mtimes(ca.DM(b @ self.rest), z).T for b in form.basis(times))

        self.grid = sample_times(form.duration, options.grid_rate)
        objectives = self._criterion(x)
        g_kin, lo_kin, hi_kin = kinematic_constraints(model, *samples(self.kinematic_times), options.margins)
        m = options.margins
        g_env, lo_env, hi_env = self._rows(x, sample_rows(model, m.velocity, m.height, m.clearance),
                                           self.kinematic_times, 2)
        g_dyn, lo_dyn, hi_dyn = self._rows(x, torque_rows(model, m), self.torque_times, 3)
        g = ca.vertcat(g_kin, g_env, g_dyn)
        self.lbg = np.concatenate([lo_kin, lo_env, lo_dyn])
        self.ubg = np.concatenate([hi_kin, hi_env, hi_dyn])
        self.deadline = _Deadline(x.numel(), g.numel())
        # limited_memory_aug_solver "extended": the L-BFGS vectors join the augmented system
        # instead of 2 x history extra back-solves per iteration (Sherman-Morrison): IPOPT's own
        # CPU time 2.9 -> 1.5 s on a UR5 start, the same iterates to rounding.
        ipopt = {"ipopt.hessian_approximation": "limited-memory", "ipopt.limited_memory_aug_solver": "extended",
                 "ipopt.max_iter": options.max_iter,
                 "ipopt.tol": options.tol, "ipopt.acceptable_tol": options.acceptable_tol,
                 "ipopt.acceptable_iter": options.acceptable_iter,
                 "ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": False,
                 "error_on_fail": False, "iteration_callback": self.deadline}
        ipopt.update({f"ipopt.{key}": value for key, value in options.ipopt})
        self.stage_values = ca.Function("stages", [x], objectives)
        self.solvers = [ca.nlpsol(f"excitation_{c.replace('-', '_')}{p}", "ipopt", {"x": x, "f": f, "g": g}, ipopt)
                        for (c, p), f in zip(options.stages, objectives)]

    def _criterion(self, x: ca.MX) -> list[ca.MX]:
        """The criterion of each stage at x: compiled samples and a BLAS Gram matrix
        (criterion_callback.py), or with ``compiled=False`` (or a regressor CasADi cannot
        evaluate on SX) one CasADi graph."""
        model, form, options = self.model, self.form, self.options
        objective = options.criterion
        regressor = _row_weighted(smooth_friction_regressor(model.regressor, model.names, options.sign_eps),
                                  objective.row_weights(model.n))
        stages = [p for _, p in options.stages]
        if options.compiled and evaluable_on_sx(regressor):
            bases = [b @ self.rest for b in form.basis(self.grid)]
            self._callbacks = criterion_callbacks(regressor, objective, stages, bases, model.n, form.duration,
                                                  model.name)
            return [cb(x) for cb in self._callbacks]
        z = ca.reshape(x, self.n_free, model.n)
        q, qd, qdd = (ca.mtimes(ca.DM(b @ self.rest), z).T for b in form.basis(self.grid))
        info = objective.information(gram_expression(regressor, q, qd, qdd), form.duration)
        return [objective.expression(info, p) for p in stages]

    def _rows(self, x: ca.MX, rows: tuple[ca.Function, np.ndarray, np.ndarray] | None, times: np.ndarray,
              inputs: int) -> tuple[ca.MX, np.ndarray, np.ndarray]:
        """Nonlinear rows f(q, qd[, qdd]) (the envelope's: heights, clearances, Cartesian speeds,
        imposed from the start since a repair from a point in collision rarely recovers; the
        motor torques, lazily) at ``times``, with the chain-rule Jacobian of envelope_rows.py."""
        if rows is None or times.size == 0:
            return ca.MX(0, 1), np.zeros(0), np.zeros(0)
        f, lo, hi = rows
        bases = [b @ self.rest for b in self.form.basis(times)[:inputs]]
        g = through_samples(f, bases, self.model.n, self.options.compiled)(x)
        return g, np.tile(lo, times.size), np.tile(hi, times.size)

    def with_extra_times(self, times: np.ndarray) -> "_Problem":
        """The same problem with every limit also imposed at ``times`` [s]; the first time round,
        the torque limits are also imposed on the whole constraint grid (an active limit would
        otherwise just move its violation elsewhere)."""
        torque = self.torque_times if self.torque_times.size else self.kinematic_times
        return _Problem(self.model, self.form, self.options, np.union1d(self.kinematic_times, times),
                        np.union1d(torque, times))

    def pulled_inside(self, x: np.ndarray, factor: float = 0.9, tries: int = 20) -> np.ndarray:
        """x pulled towards the motionless centre pose (factor per try) until it holds every
        row of this NLP (margins included), or x itself when no try does: a repair then starts
        feasible. From the violating iterate IPOPT spent 60 of 199 iterations of an RX90 repair in
        its restoration phase and 100 more climbing back to the criterion it had."""
        g = self.solvers[-1].get_function("nlp_g")
        centre = self.form.constant(range_centre(self.model)).flatten(order="F")
        trial = x
        for _ in range(tries):
            values = np.asarray(g(trial, [])).ravel()
            if np.all(values >= self.lbg) and np.all(values <= self.ubg):
                return trial
            trial = centre + factor * (trial - centre)
        return x

    def solve(self, x0: np.ndarray, stage: int, deadline: float) -> tuple[np.ndarray, int, str]:
        """One IPOPT stage from x0 (stopped at the epoch time ``deadline``); returns (x,
        iterations, status)."""
        self.deadline.deadline = deadline
        solver = self.solvers[stage]
        sol = solver(x0=x0, lbg=self.lbg, ubg=self.ubg)
        stats = solver.stats()
        return np.asarray(sol["x"]).ravel(), int(stats["iter_count"]), str(stats["return_status"])

    def coefficients(self, x: np.ndarray) -> np.ndarray:
        """Full coefficients C (m, n) from the decision vector."""
        return self.rest @ x.reshape(self.n_free, self.model.n, order="F")


# --------------------------------------------------------------------------- starts
def initial_free(model: ExcitationModel, form: Form, rng: np.random.Generator,
                 fraction: tuple[float, float], times: np.ndarray,
                 margins: Margins) -> np.ndarray:
    """Random free coefficients Z whose kinematics hold on ``times``: each joint's motion is
    scaled to a random fraction of its room (positions about a random offset near the centre of
    the range, velocities, accelerations)."""
    n = model.n
    lo, hi = position_bounds(model, margins.position)
    centre = range_centre(model)
    half = np.where(np.isfinite(hi - lo), 0.5 * (hi - lo), 0.0)
    q_ref = centre + rng.uniform(-0.2, 0.2, n) * half
    motion = form.random_free(rng, n)
    scales = kinematic_room(model, form, motion, q_ref, times, margins)
    scales *= rng.uniform(*fraction, n)
    z = form.constant(q_ref) + motion * scales
    from .envelope import shrink_to_envelope  # a start inside the envelope: IPOPT keeps it there

    return shrink_to_envelope(model, form, z, form.constant(centre), times, margins)


def kinematic_room(model: ExcitationModel, form: Form, motion: np.ndarray, q_ref: np.ndarray,
                   times: np.ndarray, margins: Margins) -> np.ndarray:
    """Largest s_j (n,) such that q_ref + s_j * motion_j holds position, velocity and acceleration
    limits (with margins) at ``times``; q_ref must lie inside the position bounds."""
    lim = model.limits
    rest = form.rest_basis()
    dq, dqd, dqdd = (b @ rest @ motion for b in form.basis(times))
    lo, hi = position_bounds(model, margins.position)
    room_q = np.minimum(hi - q_ref, q_ref - lo)
    if np.any(room_q <= 0.0):
        raise ValueError("excitation: the reference position lies outside the position limits")
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.minimum.reduce([
            room_q / np.max(np.abs(dq), axis=0),
            (1.0 - margins.velocity) * lim.qd_max / np.max(np.abs(dqd), axis=0),
            (1.0 - margins.acceleration) * lim.qdd_max / np.max(np.abs(dqdd), axis=0),
        ])
    return np.where(np.isfinite(s), s, 1.0)


# --------------------------------------------------------------------------- one start
@dataclass(frozen=True, eq=False)
class StartResult:
    """What one start gave. index: 1-based start number (its random draw is
    default_rng([seed, index]), so it does not depend on which process runs it or in what order).
    score: the criterion on the cond_rate samples (nan when infeasible or rank deficient);
    skipped: why the start did not run ("" when it ran)."""

    index: int
    coefficients: np.ndarray | None = None
    iterations: int = 0
    status: str = ""
    report: Any = None
    cond: float = float("nan")
    score: float = float("nan")
    surrogate_cond: float = float("nan")
    time_s: float = 0.0
    failure: str = ""
    skipped: str = ""


def start_rng(seed: int, index: int) -> np.random.Generator:
    """The random generator of start ``index`` of a multi-start with ``seed``."""
    return np.random.default_rng([int(seed), int(index)])


def run_starts(model: ExcitationModel, form: Form, options: OptimiserOptions, seed: int,
               indices: Sequence[int], deadline: float | None = None,
               on_result: Callable[[StartResult], None] | None = None) -> list[StartResult]:
    """Run the given starts one after the other with one NLP (built once); pure apart from time.

    deadline: epoch time [s] (time.time()) after which solves stop and later starts are skipped
    (reported as such); None: no deadline (the default: results do not depend on the machine).
    on_result: called with each StartResult as soon as it is known (progress lines).
    """
    check_request(model, form, options)
    grid = sample_times(form.duration, options.constraint_grid_rate(form.max_frequency_hz))
    torque = sample_times(form.duration, options.torque_rate) if options.torque_rate else np.zeros(0)
    problem = _Problem(model, form, options, grid, torque)
    limit = float("inf") if deadline is None else float(deadline)
    out = []
    for k in indices:
        if time.time() >= limit:
            out.append(StartResult(int(k), skipped="time budget spent before it began"))
            if on_result is not None:
                on_result(out[-1])
            continue
        t0 = time.perf_counter()
        z0 = initial_free(model, form, start_rng(seed, k), options.start_fraction, grid, options.margins)
        x, iterations, status, report = _solve_start(problem, z0.flatten(order="F"), limit)
        coefficients = problem.coefficients(x)
        score = cond = surrogate = float("nan")
        failure = ""
        if report.feasible:
            cond, score = _score(model, form, coefficients, options)
            if not cond <= MAX_COND:  # within limits, but some base parameter is not excited
                failure = f"the best motion within the limits leaves W rank deficient (cond {cond:.3g})"
                score = float("nan")
            elif options.stages[-1][1] > 0:
                surrogate = float(np.exp(0.5 * float(problem.stage_values(x)[-1])))
        else:
            failure = "; ".join(report.violations[:3])
        out.append(StartResult(int(k), coefficients, iterations, status, report, cond, score, surrogate,
                               time.perf_counter() - t0, failure))
        if on_result is not None:
            on_result(out[-1])
    return out


def _solve_start(problem: _Problem, x0: np.ndarray, deadline: float
                 ) -> tuple[np.ndarray, int, str, Any]:
    """All stages from x0, then fine-grid verification with repair rounds."""
    options, model, form = problem.options, problem.model, problem.form
    x, iterations, status = x0, 0, "not run"
    for stage in range(len(problem.solvers)):
        x_new, it, status = problem.solve(x, stage, deadline)
        iterations += it
        if status in _GOOD_STATUS and np.all(np.isfinite(x_new)):
            x = x_new  # a failed stage (e.g. restoration failure) keeps the previous iterate
    report = _verify(model, form, problem.coefficients(x), options.verify_rate)
    repairs = 0
    while not report.feasible and repairs < options.repairs and time.time() < deadline:
        repairs += 1
        t_fine, q, qd, qdd = _fine_samples(form, problem.coefficients(x), options.verify_rate)
        problem = problem.with_extra_times(violation_times(model, t_fine, q, qd, qdd))
        x_new, it, status = problem.solve(problem.pulled_inside(x), len(problem.solvers) - 1, deadline)
        iterations += it
        if status not in _GOOD_STATUS or not np.all(np.isfinite(x_new)):
            # A failed repair is not a result (IPOPT's restoration can end on a shrunken motion that
            # holds the limits but excites nothing: cond 3e4 on a 10 s RX90 start): the start stays
            # infeasible and is reported as such.
            break
        x = x_new
        report = _verify(model, form, problem.coefficients(x), options.verify_rate)
    if repairs:
        status = f"{status}, {repairs} repair{'s' if repairs > 1 else ''}"
    return x, iterations, status, report


def _fine_samples(form: Form, coefficients: np.ndarray, rate: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    t = sample_times(form.duration, rate, closed=True)
    return (t, *form.evaluate(coefficients, t))


def _verify(model: ExcitationModel, form: Form, coefficients: np.ndarray, rate: float) -> Any:
    t, q, qd, qdd = _fine_samples(form, coefficients, rate)
    return check_limits(model, q, qd, qdd, rate)


def _score(model: ExcitationModel, form: Form, coefficients: np.ndarray,
           options: OptimiserOptions) -> tuple[float, float]:
    """(cond of the raw W, criterion value to minimise) on the cond_rate samples, true sign."""
    t = sample_times(form.duration, options.cond_rate)
    q, qd, qdd = form.evaluate(coefficients, t)
    phi = regressor_samples(model.regressor, q, qd, qdd)
    w = np.concatenate([phi[:, j, :] for j in range(phi.shape[1])], axis=0)
    sv = np.linalg.svd(w, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    objective = options.criterion
    if objective.name == "cond" and objective.prior is None and objective.noise_std is None:
        return cond, cond
    return cond, objective.value(numeric_information(phi, objective, form.duration))


def _row_weighted(regressor: ca.Function, weights: np.ndarray) -> ca.Function:
    """diag(weights) Phi_b: rows divided by the expected noise of their joint."""
    if np.all(weights == 1.0):
        return regressor
    sym = symbols_like(regressor)
    phi = ca.mtimes(ca.diag(ca.DM(weights)), regressor(*sym))
    return ca.Function(f"{regressor.name()}_weighted", list(sym), [phi], ["q", "qd", "qdd"], ["Phi"])
