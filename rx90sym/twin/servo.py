"""The twin's closed loop (PD + feed-forward, RK4 at the servo rate, compiled) and its open-loop counterpart."""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Mapping

import casadi as ca
import numpy as np

from ..compiled import compiled_function
from ..forward_dynamics import _tanh_sign, mass_and_bias, mass_matrix
from .noise import NoiseProfile

if TYPE_CHECKING:  # for annotations only
    from ..description import Robot


# Output samples per compiled call of the closed loop: long enough that Python's per-call cost
# is negligible, short enough that a 1 s padding at the end costs little.
CHUNK_SAMPLES = 250

@dataclass(frozen=True)
class _Layout:
    """Where each quantity sits in the closed loop's parameter vector p."""

    n: int
    npar: int
    harmonics: int

    def sizes(self) -> dict[str, int]:
        n = self.n
        return {"chi": self.npar, "chi_nom": self.npar, "kp": n, "kd": n, "stribeck": n,
                "stribeck_velocity": 1, "smoothing": 1, "ripple": n, "orders": self.harmonics,
                "phases": self.harmonics * n, "h": 1}

    def split(self, p: Any) -> dict[str, Any]:
        out, i = {}, 0
        for key, size in self.sizes().items():
            out[key] = p[i:i + size]
            i += size
        return out

    def pack(self, values: Mapping[str, Any]) -> np.ndarray:
        return np.concatenate([np.ravel(np.asarray(values[k], dtype=float)) for k in self.sizes()])


def ripple_transmission(robot: Robot, ripple_gear: float) -> tuple[np.ndarray, np.ndarray]:
    """(Rq, Rt) seen by the motor torque ripple: the robot's, or ``ripple_gear`` times the
    identity when the robot has no gear ratios (all 1)."""
    if np.all(np.abs(np.asarray(robot.gear_ratios, dtype=float)) == 1.0):
        eye = ripple_gear * np.eye(robot.n)
        return eye, eye.copy()
    return np.asarray(robot.Rq, dtype=float), np.asarray(robot.Rt, dtype=float)


def _servo_step(robot: Robot, layout: _Layout, ripple_gear: float = 1.0) -> ca.Function:
    """One servo period: (x = [q; qd], ref = [q_r; qd_r; qdd_r], p) -> (x_next, tau_cmd, qdd).

    tau_cmd = IDM(ref; chi_nom) - spring(q_r) + Kp (q_r - q) + Kd (qd_r - qd), held over the
    period (zero-order hold) while RK4 integrates the true plant
    IDM_smooth(q, qd, qdd; chi) + stribeck(qd) = tau_cmd + spring(q) + ripple(q).
    qdd is the plant's acceleration at the start of the period.
    """
    n = robot.n
    x = ca.SX.sym("x", 2 * n)
    ref = ca.SX.sym("ref", 3 * n)
    p = ca.SX.sym("p", sum(layout.sizes().values()))
    v = layout.split(p)
    q_r, qd_r, qdd_r = ref[:n], ref[n:2 * n], ref[2 * n:]
    spring = robot.spring_torque
    tau_cmd = (robot.inverse_dynamics(q_r, qd_r, qdd_r, v["chi_nom"]) - spring(q_r)
               + v["kp"] * (q_r - x[:n]) + v["kd"] * (qd_r - x[n:]))

    q, qd, u = (ca.SX.sym(s, n) for s in ("q", "qd", "u"))
    chi = v["chi"]
    sign = _tanh_sign(v["smoothing"])
    M, bias = mass_and_bias(robot, q, qd, chi, sign)
    fs = chi[robot.parameter_index([f"FS{j}" for j in range(1, n + 1)])]
    stribeck = v["stribeck"] * fs * ca.exp(-(qd / v["stribeck_velocity"]) ** 2) * sign(qd)
    Rq_ripple, Rt_ripple = ripple_transmission(robot, ripple_gear)
    theta_m = ca.mtimes(ca.DM(Rq_ripple), q)
    orders, phases = v["orders"], ca.reshape(v["phases"], layout.harmonics, n)
    ripple_m = ca.SX.zeros(n)
    for h in range(layout.harmonics):
        ripple_m += v["ripple"] * ca.sin(orders[h] * theta_m + phases[h, :].T)
    ripple = ca.mtimes(ca.DM(Rt_ripple), ripple_m)
    acc = ca.solve(M, u + spring(q) + ripple - bias - stribeck)
    plant = ca.Function("plant", [q, qd, u, p], [acc])

    def f(state: ca.SX) -> ca.SX:
        return ca.vertcat(state[n:], plant(state[:n], state[n:], tau_cmd, p))

    h = v["h"]
    k1 = f(x)
    k2 = f(x + h / 2 * k1)
    k3 = f(x + h / 2 * k2)
    k4 = f(x + h * k3)
    x_next = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return ca.Function("servo_step", [x, ref, p], [x_next, tau_cmd, k1[n:]],
                       ["x", "ref", "p"], ["x_next", "tau_cmd", "qdd"])


@lru_cache(maxsize=8)
def _closed_loop_function(robot: Robot, harmonics: int, steps: int, ripple_gear: float = 1.0) -> ca.Function:
    """``steps`` servo periods in one call (mapaccum), compiled to C when possible (memoised:
    building and loading it costs ~0.2 s; the shared library is cached on disk)."""
    layout = _Layout(robot.n, len(robot.parameter_names), harmonics)
    step = _servo_step(robot, layout, ripple_gear)
    run = step.mapaccum(f"{robot.name}_twin_loop", steps)
    return compiled_function(run)


# --------------------------------------------------------------------------- closed loop
@dataclass(frozen=True, eq=False)
class TwinRun:
    """States of a simulated motion at the output samples (Khalil angles, SI).

    t (N,) [s]; q, qd, qdd (N, n): actual motion [rad, rad/s, rad/s^2]; tau (N, n): noiseless
    joint-side motor torque (command) at t [N m]; q_ref (N, n): the reference.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    q_ref: np.ndarray


@lru_cache(maxsize=8)
def _velocity_jacobian(robot: Robot) -> ca.Function:
    """(q, qd, chi, smoothing) -> d qdd / d qd of the free plant [1/s] (memoised per robot)."""
    q, qd = ca.SX.sym("q", robot.n), ca.SX.sym("qd", robot.n)
    chi = ca.SX.sym("chi", len(robot.parameter_names))
    smoothing = ca.SX.sym("smoothing")
    M, bias = mass_and_bias(robot, q, qd, chi, _tanh_sign(smoothing))
    acc = ca.solve(M, -bias)
    return ca.Function("velocity_jacobian", [q, qd, chi, smoothing], [ca.jacobian(acc, qd), M])


def check_step_stability(robot: Robot, q0: np.ndarray, chi: np.ndarray, kd: np.ndarray,
                         profile: NoiseProfile, step: float) -> float:
    """h * |lambda|max of the velocity dynamics at rest at q0 (friction slope at zero speed,
    viscous friction, derivative gain); raises ValueError above 2.5 (RK4 is stable up to 2.78
    on the negative real axis). Returns the value."""
    A, M = (np.array(a) for a in _velocity_jacobian(robot)(q0, np.zeros(robot.n), chi, profile.coulomb_smoothing))
    A = A - np.linalg.solve(M, np.diag(kd))
    value = float(step * np.abs(np.linalg.eigvals(A)).max())
    if value > 2.5:
        raise ValueError(f"noise profile {profile.name!r}: servo step {step * 1e3:.3g} ms too long for "
                         f"the friction slope at zero speed (h*lambda = {value:.2f} > 2.5); raise "
                         f"servo_rate_hz or coulomb_smoothing")
    return value


def controller_gains(robot: Robot, q0: np.ndarray, chi_nominal: np.ndarray,
                     profile: NoiseProfile) -> tuple[np.ndarray, np.ndarray]:
    """Kp [N m/rad], Kd [N m s/rad] per joint from the nominal diagonal inertia at q0."""
    J = np.diag(np.array(mass_matrix(robot)(q0, chi_nominal)))
    w = 2 * np.pi * profile.bandwidth_hz
    return J * w**2, 2 * profile.damping * J * w


def rated_torques(robot: Robot, fallback: np.ndarray) -> np.ndarray:
    """Rated joint torques [N m]: robot.limits.tau_max, or ``fallback`` where unknown."""
    tau_max = np.asarray(robot.limits.tau_max, dtype=float)
    return np.where(np.isfinite(tau_max), tau_max, fallback)


def peak_torques(robot: Robot, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, chi: np.ndarray) -> np.ndarray:
    """max_t |IDM(q, qd, qdd; chi)| per joint [N m] (the torque scale of a robot without rated
    torques); 1 N m where a joint needs none."""
    tau = open_loop(robot, np.arange(len(q), dtype=float), q, qd, qdd, chi).tau
    peak = np.max(np.abs(tau), axis=0)
    return np.where(peak > 0, peak, 1.0)


def closed_loop(robot: Robot, t: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                chi: np.ndarray, chi_nominal: np.ndarray, profile: NoiseProfile,
                rng: np.random.Generator, oversample: int) -> TwinRun:
    """Run the servo loop on the reference sampled at the servo rate (every ``oversample``-th
    point is an output sample); the robot starts on the reference."""
    n = robot.n
    layout = _Layout(n, len(robot.parameter_names), len(profile.ripple_harmonics))
    kp, kd = controller_gains(robot, q[0], chi_nominal, profile)
    gears = np.abs(np.diag(ripple_transmission(robot, profile.ripple_gear)[0]))
    if profile.ripple > 0 and np.all(np.abs(np.asarray(robot.gear_ratios, dtype=float)) == 1.0):
        warnings.warn(f"twin: robot {robot.name!r} has no gear ratios; the motor torque ripple "
                      f"assumes motors geared {profile.ripple_gear:g}:1 (NoiseProfile.ripple_gear)",
                      stacklevel=3)
    rated = np.asarray(robot.limits.tau_max, dtype=float)
    if not np.all(np.isfinite(rated)):
        ds = slice(None, None, oversample)
        rated = rated_torques(robot, fallback=peak_torques(robot, q[ds], qd[ds], qdd[ds], chi))
    p = layout.pack({
        "chi": chi, "chi_nom": chi_nominal, "kp": kp, "kd": kd,
        # Stribeck amplitude = profile.stribeck * FS_j (FS_j read from chi inside the plant).
        "stribeck": np.full(n, profile.stribeck), "stribeck_velocity": profile.stribeck_velocity,
        "smoothing": profile.coulomb_smoothing,
        # Ripple is a motor property: its amplitude at the motor is the joint share / |N|.
        "ripple": profile.ripple * rated / gears,
        "orders": np.asarray(profile.ripple_harmonics, dtype=float),
        "phases": rng.uniform(0, 2 * np.pi, (len(profile.ripple_harmonics), n)),
        "h": (t[1] - t[0]),
    })
    check_step_stability(robot, q[0], chi, kd, profile, t[1] - t[0])
    steps = CHUNK_SAMPLES * oversample
    run = _closed_loop_function(robot, layout.harmonics, steps, float(profile.ripple_gear))
    ref = np.hstack([q, qd, qdd]).T  # (3n, N_fine)
    total = ref.shape[1]
    pad = (-total) % steps
    # Past the end the reference holds its last state; those states are not recorded.
    ref = np.hstack([ref, np.repeat(ref[:, -1:], pad, axis=1)])
    x = np.concatenate([q[0], qd[0]])
    X, TAU, QDD = [], [], []
    for start in range(0, ref.shape[1], steps):
        xs, taus, qdds = run(x, ref[:, start:start + steps], p)
        xs, taus, qdds = (np.array(a) for a in (xs, taus, qdds))
        X.append(np.hstack([x[:, None], xs[:, :-1]]))   # state at the start of each period
        TAU.append(taus)
        QDD.append(qdds)
        x = xs[:, -1]
    X, TAU, QDD = (np.hstack(a)[:, :total:oversample].T for a in (X, TAU, QDD))
    return TwinRun(t[::oversample], X[:, :n], X[:, n:], QDD, TAU, q[::oversample])


def open_loop(robot: Robot, t: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
              chi: np.ndarray) -> TwinRun:
    """The robot exactly on the reference: tau = IDM(q, qd, qdd; chi) - spring(q) [N m]."""
    N = len(t)
    f = robot.inverse_dynamics.map(N)
    tau = f(q.T, qd.T, qdd.T, np.repeat(chi[:, None], N, axis=1)).full().T
    tau = tau - robot.spring_torque_batch(q).reshape(N, robot.n)
    return TwinRun(t, q, qd, qdd, tau, q)
