"""The generalised-momentum observer on an identified model, one compiled CasADi step per sample.

Residual (De Luca & Mattone 2005; Haddadin, De Luca, Albu-Schäffer 2017, eq. 28):

    r = K_O (p − ∫ (τ + Cᵀq̇ − g − f + r) dt − p₀),   so that ṙ = K_O (τ_ext − r)

with p = M(q) q̇ and β = g − Cᵀq̇ from the fit's base parameters (:mod:`rx90sym.momentum`; rotor
inertias and the wrist coupling included) and τ − f the fit's own actuation model: drive gains
(τ = Rt·diag(k)·(i − i0) on a current effort), spring torque added as the fit added it to the
measured torque, friction of the fit's columns (Coulomb, viscous, coupling, asymmetric Coulomb,
offsets; the smooth forms through the fit's own CasADi friction function). At rest (|driver speed|
below the fit's ``min_velocity``) the Coulomb term is 0 whatever the fit's rest policy (its rest
torque lies anywhere in [−FS, FS]: the observer cannot tell it from an external torque); rest
policy "none" keeps the sign of the speed.

Discretisation (exact for p linear and u = τ − f − β at its mean over each period T): with
a = exp(−K_O T), r_k = a r_{k−1} + (1 − a) ((p_k − p_{k−1})/T − (u_k + u_{k−1})/2).
The friction the observer cannot know (a Coulomb term within ±FS while its driver speed is below
:data:`SLACK_BAND` × the rest threshold: rest, reversals) enters the residual through the same
K_O/(s + K_O); so does the slack d_j, the Coulomb levels of joint j's slow terms passed through that
filter (same discretisation), which the thresholds ride on: joint j is active above T_j + d_j and
released below ``release``·T_j + d_j (hysteresis). The step also carries the time since the first
active joint (−1 when none). State layout: [p, u, r, active, slack (n each), elapsed (1)].
"""
from __future__ import annotations

import ctypes
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

import rx90sym
from rx90sym.compiled import _c_compiler, shared_library
from rx90sym.momentum import base_momentum_regressors

from identify.monitor.defaults import DEFAULT_GAIN
from identify.observation.processing import DEFAULT_MIN_VELOCITY

__all__ = ["DEFAULT_GAIN", "FRICTION_KINDS", "ObserverModel", "observer_model"]

#: Parameter kinds of the actuation model (friction, offsets): absent from p and β.
FRICTION_KINDS = ("FS", "FV", "FVM", "FSM", "FSP", "FSN", "OFF", "FST", "FP")
#: A Coulomb term counts as uncertain (slack) while its driver speed is below this many times the
#: fit's rest threshold (the friction of real joints turns over a band of speeds, not at one).
SLACK_BAND = 2.0
#: The slack's level: this many times the Coulomb level (static friction and the Stribeck rise at low
#: speed exceed the sliding level FS, typically by 10-30 %; the realistic twin by 10 %).
SLACK_FACTOR = 1.25

_RUNNER = r"""
/* Runs {name} sample after sample: state S (in/out) carried from one sample to the next. */
int {name}_run(long long N, long long n, const double* Q, const double* QD, const double* E,
               const double* DT, const double* P, double* S, double* OUT,
               long long* iw, double* w) {{
  const casadi_real* arg[{sz_arg}];
  casadi_real* res[{sz_res}];
  long long ns = {ns};
  for (long long i = 0; i < N; ++i) {{
    arg[0] = Q + i * n; arg[1] = QD + i * n; arg[2] = E + i * n;
    arg[3] = i ? OUT + (i - 1) * ns : S; arg[4] = DT + i; arg[5] = P;
    res[0] = OUT + i * ns;
    if ({name}(arg, res, iw, w, 0)) return 1;
  }}
  if (N > 0) for (long long k = 0; k < ns; ++k) S[k] = OUT[(N - 1) * ns + k];
  return 0;
}}
"""


def _kind(name: str) -> str:
    try:
        return rx90sym.parameters.split_name(name.split("_")[0])[0]
    except ValueError:
        return ""


@dataclass(frozen=True, eq=False)
class ObserverModel:
    """The observer's step on one fit: ``step`` (q, qd, effort, state, dt, params) -> next state,
    params = [K_O (n) rad/s, thresholds (n) N·m, release ratio, base values, friction values,
    (current effort) gain matrix and current offsets] (:meth:`params`): the compiled code depends
    on the robot and the model's structure only. ``effort``: "torque" [N·m] or "current" [A]."""

    robot: rx90sym.Robot
    step: ca.Function
    effort: str
    fs: np.ndarray          # (n,) the most the friction slack reaches per joint [N·m]
    name: str
    values: np.ndarray      # the fit's values after [K_O, T, release] in params

    def params(self, gain: np.ndarray, thresholds: np.ndarray, release: float) -> np.ndarray:
        """The step's parameter vector: [K_O (n), T (n), release, the fit's values]."""
        return np.concatenate([gain, thresholds, [release], self.values])

    @property
    def n(self) -> int:
        return self.robot.n

    @property
    def state_size(self) -> int:
        return 5 * self.robot.n + 1

    def initial_state(self) -> np.ndarray:
        """The state before the first sample (r = 0, nothing active, elapsed −1)."""
        s = np.zeros(self.state_size)
        s[-1] = -1.0
        return s

    @cached_property
    def _lib(self) -> tuple[Any, np.ndarray, np.ndarray]:
        f = self.step
        cc = _c_compiler()
        if cc is None:
            raise RuntimeError("the contact monitor needs a C compiler (set CC)")
        cg = ca.CodeGenerator(f"{self.name}.c", {"with_header": False, "casadi_int": "long long int"})
        cg.add(f)
        source = cg.dump() + _RUNNER.format(name=self.name, sz_arg=max(f.sz_arg(), 1),
                                            sz_res=max(f.sz_res(), 1), ns=self.state_size)
        lib = ctypes.CDLL(str(shared_library(source, self.name, ("-O3",))))
        run = getattr(lib, f"{self.name}_run")
        run.restype = ctypes.c_int
        run.argtypes = [ctypes.c_longlong, ctypes.c_longlong] + [ctypes.c_void_p] * 9
        return run, np.zeros(max(f.sz_iw(), 1), dtype=np.int64), np.zeros(max(f.sz_w(), 1))

    def runner(self) -> Any:
        """The compiled C function ``run(N, n, Q, QD, E, DT, P, S, OUT, iw, w)`` (pointers) and
        its work buffers (iw, w): what :class:`ContactMonitor` calls once per sample."""
        return self._lib

    def run(self, Q: np.ndarray, QD: np.ndarray, E: np.ndarray, DT: np.ndarray, params: np.ndarray,
            state: np.ndarray) -> np.ndarray:
        """N samples in sequence: (N, n) arrays and (N,) periods [s]; ``state`` (updated in place);
        returns the (N, 5n + 1) states after each sample."""
        run, iw, w = self._lib
        arrays = [np.ascontiguousarray(a, dtype=float) for a in (Q, QD, E)]
        DT = np.ascontiguousarray(DT, dtype=float)
        P = np.ascontiguousarray(params, dtype=float)
        N = DT.shape[0]
        if any(a.shape != (N, self.n) for a in arrays) or state.shape != (self.state_size,):
            raise ValueError(f"observer: inputs must be (N, {self.n}) with N = {N}")
        out = np.empty((N, self.state_size))
        if run(N, self.n, *(a.ctypes.data for a in arrays), DT.ctypes.data, P.ctypes.data,
               state.ctypes.data, out.ctypes.data, iw.ctypes.data, w.ctypes.data):
            raise RuntimeError("observer: compiled step failed")
        return out


def _rigid_base(base: Any) -> Any:
    """The symbolic base inside a fit's columns (its friction columns, the offsets the cross-validated choice
    added: identify.observation.offsets.OffsetBase)."""
    from identify.friction.columns import inner_columns
    from identify.observation.offsets import OffsetBase

    base = inner_columns(base)
    return base.base if isinstance(base, OffsetBase) else base


def _rigid_values(fit: Any, base: Any) -> np.ndarray:
    values = dict(zip(fit.result.names, fit.result.values))
    return np.array([values.get(nm, 0.0) for nm in base.names])


def _friction(fit: Any, q: ca.SX, qd: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX, list[str]]:
    """The fit's actuation torque at q̈ = 0 (friction, offsets), Coulomb 0 at rest, as SX of (q, q̇)
    and of the symbols ``fv`` of its friction values (so that one compiled step serves every fit
    of the same robot and model); the uncertain Coulomb level per joint (the terms whose driver is
    below the slack band); the most the slack reaches per joint (SLACK_FACTOR × the sum of the
    magnitudes of FS, FSP/FSN, FSM, FST on the joint's row); returns (f, slack, fv, most, names)."""
    from identify.friction.columns import form_columns
    from identify.friction.forms import friction_function
    from identify.observation.rest import coulomb_terms

    robot, forms = fit.robot, form_columns(fit.base)
    inner = _rigid_base(fit.base)
    phi = inner.regressor(q, qd, ca.SX.zeros(robot.n, 1))
    names = list(inner.names)
    # Offsets the cross-validated choice added (OFFj beyond the robot's columns): a constant on joint j.
    added = [nm for nm in fit.result.names if _kind(nm) == "OFF" and nm not in names]
    used = [nm for nm in names if _kind(nm) in FRICTION_KINDS] + [
        nm for nm in fit.result.names if _kind(nm) == "FST"] + added
    fv = ca.SX.sym("fv", len(used))
    sym = {nm: fv[k] for k, nm in enumerate(used)}
    terms = coulomb_terms(robot, names)
    coulomb = {t.column for t in terms}
    rows = [ca.SX(0) for _ in range(robot.n)]
    slack = [ca.SX(0) for _ in range(robot.n)]
    most = [ca.SX(0) for _ in range(robot.n)]
    policies = fit.rest if isinstance(fit.rest, tuple) else (fit.rest,) * robot.n
    vmin = fit.min_velocity
    band = SLACK_BAND * (vmin if vmin else DEFAULT_MIN_VELOCITY)
    for c, nm in enumerate(names):
        if nm not in sym or c in coulomb:
            continue
        rows = [rows[j] + phi[j, c] * sym[nm] for j in range(robot.n)]
    for nm in added:
        rows[int(nm[3:]) - 1] += sym[nm]
    for t in terms:
        v = ca.mtimes(ca.DM(t.driver).T, qd)
        own = sum(abs(d) for d in t.driver) == 1 and t.driver[t.row] == 1
        form = forms.form_of(t.row) if forms is not None and own else "coulomb"
        cols = [phi[t.row, t.column]] if form == "coulomb" else ca.vertsplit(
            friction_function(form)(v, forms.scales[t.row])[0])
        term = cols[0] * sym[t.name]
        level = ca.fabs(sym[t.name])
        if form == "stribeck" and f"FST{t.row + 1}" in sym:
            term = term + cols[1] * sym[f"FST{t.row + 1}"]
            level = ca.fmax(level, ca.fabs(sym[f"FST{t.row + 1}"]))
        most[t.row] = most[t.row] + SLACK_FACTOR * level
        slack[t.row] = slack[t.row] + ca.if_else(ca.fabs(v) < band, SLACK_FACTOR * level, 0)
        if vmin is not None and policies[t.row] != "none":
            term = ca.if_else(ca.fabs(v) >= vmin, term, 0)
        rows[t.row] = rows[t.row] + term
    return ca.vertcat(*rows), ca.vertcat(*slack), fv, ca.vertcat(*most), used


def supported(fit: Any) -> str:
    """'' when the monitor can evaluate this fit, else why not."""
    base = _rigid_base(fit.base)
    if not isinstance(base, rx90sym.BaseParameters):
        return (f"the fit's columns ({type(base).__name__}: an identified spring) are not supported by the "
                f"contact monitor yet: fit with the robot's spring table")
    extra = [nm for nm in fit.result.names if nm not in base.names and _kind(nm) not in ("FST", "FP", "OFF")]
    if extra:
        return f"the fit has parameters {extra[:4]} the contact monitor does not model"
    return ""


def observer_model(fit: Any, effort: str | None = None) -> ObserverModel:
    """The observer on ``fit`` (a :class:`identify.Fit`); effort "torque" or "current" (None:
    current when the fit has drive gains, else torque)."""
    why = supported(fit)
    if why:
        raise ValueError(why)
    robot = fit.robot
    gains = fit.gains
    effort = effort or ("current" if gains is not None else "torque")
    if effort not in ("torque", "current"):
        raise ValueError(f"effort must be 'torque' or 'current', got {effort!r}")
    if effort == "current" and gains is None:
        raise ValueError("effort 'current' needs a fit with drive gains (rx90 identify --gains)")
    n = robot.n
    base = _rigid_base(fit.base)
    q, qd, e = (ca.SX.sym(s, n) for s in ("q", "qd", "effort"))
    theta = ca.SX.sym("theta", base.nb)
    phi_p, phi_beta = base_momentum_regressors(base)(q, qd)
    p, beta = ca.mtimes(phi_p, theta), ca.mtimes(phi_beta, theta)
    friction, unknown, fv, most, used = _friction(fit, q, qd)
    values = dict(zip(fit.result.names, fit.result.values))
    tail = [_rigid_values(fit, base), np.array([values.get(nm, 0.0) for nm in used], dtype=float)]
    symbols = [theta, fv]
    if effort == "current":
        Gs, i0 = ca.SX.sym("G", n, n), ca.SX.sym("i0", n)
        G = np.diag(gains.gains) if gains.side == "joint" else np.asarray(robot.Rt) @ np.diag(gains.gains)
        tau = ca.mtimes(Gs, e - i0)
        symbols += [ca.vec(Gs), i0]
        tail += [G.ravel(order="F"), np.asarray(gains.current_offsets, dtype=float)]
    else:
        tau = e
    spring = robot.spring_torque(q) if fit.filtering()["spring"] and robot.spring is not None else 0
    u = tau + spring - friction - beta
    state, dt = ca.SX.sym("state", 5 * n + 1), ca.SX.sym("dt")
    K, T, release = ca.SX.sym("K", n), ca.SX.sym("T", n), ca.SX.sym("release")
    params = ca.vertcat(K, T, release, *symbols)
    p_prev, u_prev, r_prev = state[:n], state[n:2 * n], state[2 * n:3 * n]
    active_prev, slack_prev, elapsed_prev = state[3 * n:4 * n], state[4 * n:5 * n], state[5 * n]
    h = ca.fmax(dt, 1e-12)
    a = ca.exp(-K * h)
    w = (p - p_prev) / h - (u + u_prev) / 2
    r = ca.if_else(dt > 0, a * r_prev + (1 - a) * w, r_prev)
    slack = ca.if_else(dt > 0, a * slack_prev + (1 - a) * unknown, unknown)  # starts at the first sample's level
    mag = ca.fabs(r)
    active = ca.if_else(mag > T + slack, 1, ca.if_else(mag < release * T + slack, 0, active_prev))
    anyone = ca.mmax(active)
    elapsed = ca.if_else(anyone > 0.5, ca.if_else(elapsed_prev >= 0, elapsed_prev + ca.fmax(dt, 0), 0), -1)
    nxt = ca.cse(ca.densify(ca.vertcat(p, u, r, active, slack, elapsed)))
    name = f"{robot.name}_momentum_observer_{effort}".replace("-", "_")
    step = ca.Function(name, [q, qd, e, state, dt, params], [nxt], ["q", "qd", "effort", "state", "dt", "params"],
                       ["next"])
    fs = np.asarray(ca.Function("most", [fv], [most])(tail[1]).full()).ravel()
    return ObserverModel(robot, step, effort, fs, name, np.concatenate(tail))
