"""The twin: a simulated robot that produces recordings (DESIGN.md, "The twin").

``simulate(robot, trajectory, params, payload, noise, seed)`` returns a
:class:`rx90sym.recording.Recording` of joint positions and joint-side motor torques at 250 Hz,
the torques the identification model expects: ``tau + Gamma_s(q) = IDM(q, qd, qdd; chi)``
(eqs. 1-2, 5, 16-18; the spring is added back to axis 2 by identification).

Noise profiles (see :func:`profiles`):

- ``"ideal"``: tau = IDM(q_ref) - spring(q_ref) exactly, positions exact;
- ``"quantised"``: the same motion with encoder quantisation and Gaussian torque noise;
- ``"realistic"``: the robot follows the reference through a simulated closed loop (PD +
  feed-forward with a 10 %-off nominal model, zero-order hold at the servo rate, fixed-step RK4
  on the true dynamics), with model mismatch the identification model does not contain
  (motor torque ripple, Stribeck friction, smooth Coulomb friction), encoder quantisation and
  torque noise. The recorded torque is the command that produced the recorded motion.

The closed loop is a CasADi ``mapaccum`` of RK4 servo steps, generated as C, compiled once and
cached on disk (``rx90sym.compiled.cache_dir()``); without a C compiler CasADi's VM runs it.
"""
from __future__ import annotations

import time
import warnings
from dataclasses import asdict, dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Mapping

import casadi as ca
import numpy as np
from scipy.interpolate import CubicHermiteSpline

from .compiled import compiled_function
from .parameters import checked_values
from .payloads import Payload, add_payload, as_payload
from .recording import Recording

if TYPE_CHECKING:  # for annotations only
    from .description import Robot

# Output samples per compiled call of the closed loop: long enough that Python's per-call cost
# is negligible, short enough that a 1 s padding at the end costs little.
CHUNK_SAMPLES = 250


# --------------------------------------------------------------------------- true parameters
def default_parameters(robot: Robot, path: str | Path | None = None) -> dict[str, float]:
    """True standard parameters of the twin, name -> value [SI].

    Without ``path``: for the bundled RX90 file the twin's physically consistent set reproducing
    Table 3 (made by scripts/make_rx90_params.py; NOT the file's [nominal] table), otherwise the
    robot's nominal parameters (rx90sym.nominal_parameters: URDF inertials or the robot file's
    [nominal] table); a robot with none is refused. With ``path``: a JSON parameter file (see
    rx90sym.nominal.read_parameter_file).
    """
    from .nominal import nominal_parameters, read_parameter_file, twin_parameter_file

    twin_file = twin_parameter_file(robot) if path is None else None
    values = read_parameter_file(robot, twin_file) if twin_file is not None else nominal_parameters(robot, path)
    if values is None:
        raise ValueError(f"no default parameters for robot {robot.name!r} ({robot.source or 'built in code'}): "
                         f"it has neither a [nominal] table nor URDF inertials; pass a parameter file "
                         f"(JSON name -> value, or the JSON of 'rx90 identify --method consistent')")
    return values


def _checked_parameters(robot: Robot, table: Any, where: str) -> dict[str, float]:
    if not isinstance(table, dict):
        raise ValueError(f"{where}: field 'parameters' must map names to numbers")
    return checked_values(table, robot.parameter_names, f"{where} (robot {robot.name!r})")


def parameter_vector(robot: Robot, params: Mapping[str, float] | Any | None) -> np.ndarray:
    """chi (n_params,) from None (the default set), a name -> value mapping or a vector."""
    if params is None:
        return robot.parameter_vector(default_parameters(robot))
    if isinstance(params, Mapping):
        return robot.parameter_vector(_checked_parameters(robot, dict(params), "params"))
    chi = np.asarray(params, dtype=float)
    if chi.shape != (len(robot.parameter_names),) or not np.all(np.isfinite(chi)):
        raise ValueError(f"params: expected {len(robot.parameter_names)} finite standard "
                         f"parameters of robot {robot.name!r}, got shape {chi.shape}")
    return chi.copy()


# --------------------------------------------------------------------------- noise profiles
@dataclass(frozen=True)
class NoiseProfile:
    """How far the twin's recording is from the identification model.

    encoder_counts: counts per motor revolution (positions quantised on the motor side, then
        seen through the gears, so the joint step is 2 pi / counts / |N|); None = exact.
    torque_noise: sigma of the Gaussian torque noise of joint j as a fraction of the RMS of
        joint j's noiseless torque over the motion.
    closed_loop: simulate the servo loop (otherwise the robot is exactly on the reference).
    bandwidth_hz, damping: PD gains Kp = J w^2, Kd = 2 zeta J w (w = 2 pi bandwidth, J the
        joint's diagonal inertia at the start, from the nominal model).
    feedforward_error: the controller's feed-forward model is (1 - this) * the true parameters
        of the robot with its payload (a CS8 is told the tool's load).
    servo_rate_hz: controller and RK4 integration rate (rounded up to a multiple of the rate).
    ripple: motor torque ripple, amplitude of each harmonic as a fraction of the joint's torque
        scale: its rated torque robot.limits.tau_max, or where the robot file gives none, the peak
        |torque| of the motion with the true parameters; ripple_harmonics: orders in the motor
        angle (motor angle = Rq q).
    ripple_gear: gear ratio assumed for the ripple's motor angle when the robot gives none (all
        gear ratios 1: a file without [transmission]), with a warning. Without it the ripple of
        6 and 12 cycles per motor turn would sit at 6 and 12 cycles per joint turn, inside the
        identification band, and bias the fit (RX90 without gears: 40/54 base parameters within
        3 sigma instead of 52-54/54, benchmarks/spring_and_ripple.py);
        with it the ripple has the same torque amplitude and the frequencies of a geared arm.
    stribeck: extra static friction at zero speed as a fraction of FS_j,
        stribeck * FS_j * exp(-(qd / stribeck_velocity)^2) * sign(qd) [N m].
    coulomb_smoothing: the plant's Coulomb friction is FS tanh(qd / this) [rad/s] (a finite
        slope at zero speed, needed by the fixed-step integrator).
    """

    name: str
    description: str
    encoder_counts: float | None = None
    torque_noise: float = 0.0
    closed_loop: bool = False
    bandwidth_hz: float = 10.0
    damping: float = 1.0
    feedforward_error: float = 0.1
    servo_rate_hz: float = 4000.0
    ripple: float = 0.0
    ripple_harmonics: tuple[int, ...] = (6, 12)
    ripple_gear: float = 50.0
    stribeck: float = 0.0
    stribeck_velocity: float = 0.05
    coulomb_smoothing: float = 0.002


_PROFILES = (
    NoiseProfile("ideal", "exact torques IDM(q_ref) - spring(q_ref), exact positions (float64)"),
    NoiseProfile("quantised", "positions on the reference, quantised by 2^19-count motor "
                 "encoders; Gaussian torque noise of 1.5 % of each joint's torque RMS",
                 encoder_counts=2.0**19, torque_noise=0.015),
    NoiseProfile("realistic", "closed-loop tracking (PD at 10 Hz bandwidth + feed-forward "
                 "10 % off; 4 kHz servo, RK4), motor torque ripple "
                 "(6 and 12 cycles per motor turn, 0.25 % of rated torque each), Stribeck "
                 "friction (+10 % of FS below ~0.05 rad/s), Coulomb friction FS tanh(qd / 0.002 "
                 "rad/s), 2^19-count motor encoders, Gaussian torque noise of 1.5 % of each "
                 "joint's torque RMS",
                 encoder_counts=2.0**19, torque_noise=0.015, closed_loop=True, ripple=0.0025,
                 stribeck=0.1),
)


def profiles() -> dict[str, NoiseProfile]:
    """The named noise profiles: "ideal", "quantised", "realistic" (see NoiseProfile)."""
    return {p.name: p for p in _PROFILES}


def _profile(noise: str | NoiseProfile) -> NoiseProfile:
    if isinstance(noise, NoiseProfile):
        return noise
    table = profiles()
    if noise not in table:
        raise ValueError(f"noise: unknown profile {noise!r}, expected one of {sorted(table)} "
                         f"or a NoiseProfile")
    return table[noise]


# --------------------------------------------------------------------------- the reference
Trajectory = Any  # .sample(rate) -> (t, q, qd, qdd), a tuple of arrays, or a callable t -> (q, qd, qdd)


def reference(robot: Robot, trajectory: Trajectory, rate: float, oversample: int = 1,
              duration: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Reference (t, q, qd, qdd) on the grid t0 + k / (rate * oversample) [s, rad, rad/s, rad/s^2].

    The number of grid points is oversample * (number of output samples), so every
    ``oversample``-th point is an output sample time.
    """
    if not np.isfinite(rate) or rate <= 0:
        raise ValueError(f"rate must be > 0 Hz, got {rate}")
    fine = rate * oversample
    if hasattr(trajectory, "sample"):
        t, q, qd, qdd = (np.asarray(a, dtype=float) for a in trajectory.sample(fine))
        _check_reference(robot, t, q, qd, qdd)
        keep = len(t) - len(t) % oversample
        if duration is not None:
            keep = min(keep, int(np.floor(duration * rate + 1e-9)) * oversample)
        return t[:keep], q[:keep], qd[:keep], qdd[:keep]
    if callable(trajectory):
        if duration is None:
            raise ValueError("trajectory: a callable t -> (q, qd, qdd) needs a duration [s]")
        t = np.arange(int(np.floor(duration * rate + 1e-9)) * oversample) / fine
        q, qd, qdd = _evaluate_callable(trajectory, t, robot.n)
        _check_reference(robot, t, q, qd, qdd)
        return t, q, qd, qdd
    try:
        t, q, qd, qdd = (np.asarray(a, dtype=float) for a in trajectory)
    except (TypeError, ValueError):
        raise ValueError("trajectory: expected an object with .sample(rate), a tuple "
                         "(t, q, qd, qdd) of arrays or a callable t -> (q, qd, qdd)") from None
    _check_reference(robot, t, q, qd, qdd)
    span = t[-1] - t[0] if duration is None else min(duration, t[-1] - t[0] + 1 / rate)
    count = int(np.floor(span * rate + 1e-9)) + (1 if duration is None else 0)
    tf = t[0] + np.arange(count * oversample) / fine
    if len(tf) <= len(t) and np.allclose(t[:len(tf)], tf, rtol=0, atol=1e-9 / fine):
        return t[:len(tf)], q[:len(tf)], qd[:len(tf)], qdd[:len(tf)]  # already on the grid
    # Cubic Hermite on (q, qd) and on (qd, qdd): exact at the given samples, C1 between them.
    tc = np.clip(tf, t[0], t[-1])
    q_f = CubicHermiteSpline(t, q, qd, axis=0)(tc)
    qd_f = CubicHermiteSpline(t, qd, qdd, axis=0)(tc)
    qdd_f = np.stack([np.interp(tc, t, qdd[:, j]) for j in range(robot.n)], axis=1)
    return tf, q_f, qd_f, qdd_f


def _evaluate_callable(f: Callable, t: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    try:
        out = tuple(np.asarray(a, dtype=float) for a in f(t))
        if len(out) == 3 and all(a.shape == (len(t), n) for a in out):
            return out
    except (TypeError, ValueError):
        pass  # not vectorised: evaluate sample by sample below
    rows = [tuple(np.asarray(a, dtype=float).reshape(n) for a in f(float(tk))) for tk in t]
    return tuple(np.array([r[i] for r in rows]) for i in range(3))


def _check_reference(robot: Robot, t: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> None:
    if t.ndim != 1 or len(t) < 2:
        raise ValueError(f"trajectory: t must be 1-D with >= 2 samples, got shape {t.shape}")
    for name, a in (("q", q), ("qd", qd), ("qdd", qdd)):
        if a.shape != (len(t), robot.n):
            raise ValueError(f"trajectory: {name} must have shape ({len(t)}, {robot.n}), got {a.shape}")
        bad = np.argwhere(~np.isfinite(a))
        if len(bad):
            raise ValueError(f"trajectory: {name}{bad[0, 1] + 1} is not finite at row {bad[0, 0]}")
    if np.any(np.diff(t) <= 0):
        raise ValueError(f"trajectory: t must increase (row {int(np.argmax(np.diff(t) <= 0)) + 1})")


# --------------------------------------------------------------------------- plant model (SX)
def coulomb_torques(robot: Robot, qd: Any, chi: Any, sign: Callable[[Any], Any]) -> Any:
    """Coulomb terms of eq. 5 and eqs. 17-18 with a given sign function (SX) [N m]."""
    fs = robot.parameter_index([f"FS{j}" for j in range(1, robot.n + 1)])
    tau = [chi[fs[j]] * sign(qd[j]) for j in range(robot.n)]
    if robot.coupling is not None:
        a, b = robot.coupling.joints
        fsm = chi[robot.parameter_index([f"FSM{b + 1}"])[0]]
        if robot.coupling.coulomb_sign == "paper":
            tau[a] = tau[a] + fsm * sign(qd[b])   # eq. 17
            tau[b] = tau[b] + fsm * sign(qd[a])   # eq. 18
        else:
            s = sign(qd[a] + qd[b])
            tau[a], tau[b] = tau[a] + fsm * s, tau[b] + fsm * s
    return ca.vertcat(*tau)


def coulomb_mask(robot: Robot) -> np.ndarray:
    """1 for every parameter except the Coulomb ones (FSj, FSM): chi * mask has no Coulomb term."""
    mask = np.ones(len(robot.parameter_names))
    for i, p in enumerate(robot.parameter_names):
        if p.startswith("FS"):
            mask[i] = 0.0
    return mask


def mass_and_bias(robot: Robot, q: Any, qd: Any, chi: Any, sign: Callable[[Any], Any]) -> tuple[ca.SX, ca.SX]:
    """(M(q), b(q, qd)) with IDM = M qdd + b, Coulomb friction through ``sign`` (SX).

    The IDM is affine in qdd, so M = d IDM / d qdd is exact.
    """
    qdd = ca.SX.sym("qdd", robot.n)
    tau = robot.inverse_dynamics(q, qd, qdd, chi * coulomb_mask(robot)) + coulomb_torques(robot, qd, chi, sign)
    return ca.jacobian(tau, qdd), ca.substitute(tau, qdd, ca.SX.zeros(robot.n))


def _tanh_sign(smoothing: Any) -> Callable[[Any], Any]:
    return lambda v: ca.tanh(v / smoothing)


def forward_dynamics(robot: Robot, smoothing: float = 0.0) -> ca.Function:
    """casadi.Function (q, qd, tau, chi) -> qdd [rad/s^2] of the model, solving
    IDM(q, qd, qdd; chi) = tau (tau = everything applied at the joints: motors + spring).

    smoothing > 0 [rad/s]: Coulomb friction FS tanh(qd / smoothing) instead of FS sign(qd).
    """
    n = robot.n
    q, qd, u = (ca.SX.sym(s, n) for s in ("q", "qd", "tau"))
    chi = ca.SX.sym("chi", len(robot.parameter_names))
    M, bias = mass_and_bias(robot, q, qd, chi, _tanh_sign(smoothing) if smoothing > 0 else ca.sign)
    return ca.Function("forward_dynamics", [q, qd, u, chi], [ca.solve(M, u - bias)],
                       ["q", "qd", "tau", "chi"], ["qdd"])


def mass_matrix(robot: Robot) -> ca.Function:
    """casadi.Function (q, chi) -> M(q) (n x n) [kg m^2], rotor inertias and coupling included."""
    n = robot.n
    q, qd, qdd = (ca.SX.sym(s, n) for s in ("q", "qd", "qdd"))
    chi = ca.SX.sym("chi", len(robot.parameter_names))
    M = ca.jacobian(robot.inverse_dynamics(q, qd, qdd, chi), qdd)
    return ca.Function("mass_matrix", [q, chi], [M], ["q", "chi"], ["M"])


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


# --------------------------------------------------------------------------- measurement
def quantise_positions(robot: Robot, q: np.ndarray, counts: float) -> np.ndarray:
    """Joint positions read through motor encoders of ``counts`` per revolution [rad]:
    q_motor = Rq q is rounded to the encoder step, then mapped back (q = Rq^-1 q_motor)."""
    step = 2 * np.pi / counts
    qm = np.round(q @ np.asarray(robot.Rq).T / step) * step
    return np.linalg.solve(np.asarray(robot.Rq), qm.T).T


def torque_noise_sigma(tau: np.ndarray, fraction: float) -> np.ndarray:
    """sigma_j = fraction * RMS_j(tau) [N m]."""
    return fraction * np.sqrt(np.mean(tau**2, axis=0))


@dataclass(frozen=True)
class CurrentSensor:
    """The twin records motor currents instead of torques: i = (Rt diag(k))^-1 tau + i0 + noise.

    gains: (n,) drive gains, N·m/A, on the side ``side`` ("motor": tau = Rt diag(k) (i - i0),
        "joint": tau = diag(k) (i - i0)), as :class:`identify.io.gains.DriveGains` reads them;
    offsets: (n,) current offsets i0, A (None: 0);
    noise: standard deviation of the Gaussian current noise, A (a number or one per motor).
    """

    gains: tuple[float, ...]
    side: str = "motor"
    offsets: tuple[float, ...] | None = None
    noise: float | tuple[float, ...] = 0.0

    def currents(self, robot: Robot, tau: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Motor currents (N, n), A, that produce the joint torques ``tau`` (N, n), N·m."""
        k = np.asarray(self.gains, dtype=float).reshape(-1)
        if k.shape != (robot.n,) or not np.all(np.isfinite(k)) or np.any(k == 0):
            raise ValueError(f"CurrentSensor: expected {robot.n} finite non-zero gains, got {k.tolist()}")
        if self.side not in ("motor", "joint"):
            raise ValueError(f"CurrentSensor: side must be 'motor' or 'joint', got {self.side!r}")
        gain = np.diag(k) if self.side == "joint" else np.asarray(robot.Rt, dtype=float) @ np.diag(k)
        i = np.linalg.solve(gain, np.asarray(tau, dtype=float).T).T
        i0 = np.zeros(robot.n) if self.offsets is None else np.asarray(self.offsets, dtype=float)
        noise = np.broadcast_to(np.asarray(self.noise, dtype=float), (robot.n,))
        return i + i0 + rng.normal(size=i.shape) * noise


# --------------------------------------------------------------------------- simulate
def simulate(robot: Robot, trajectory: Trajectory, params: Mapping[str, float] | Any | None = None,
             payload: str | Path | Payload | None = None, noise: str | NoiseProfile = "realistic",
             seed: int = 0, rate: float = 250.0, duration: float | None = None,
             currents: CurrentSensor | None = None) -> Recording:
    """Simulate the robot on a trajectory and record positions and motor torques at ``rate``.

    trajectory: object with ``.sample(rate) -> (t, q, qd, qdd)``, a tuple (t, q, qd, qdd) of
        arrays, or a callable t -> (q, qd, qdd) (then ``duration`` [s] is required); Khalil
        angles [rad, rad/s, rad/s^2].
    params: true standard parameters (mapping or vector; default: default_parameters(robot)).
    payload: "tables_4", "tables_5", a JSON path, a mapping of XXc..Mc, or None.
    noise: "ideal", "quantised", "realistic" (see profiles()) or a NoiseProfile.
    seed: seeds every random draw (ripple phases, torque noise): same seed, same recording.
    currents: record motor currents through these drive gains instead of torques (tau None,
        the true gains in meta["drive_gains"]).
    Returns a Recording with tau = motor torques, spring not added (tau + spring = IDM).
    """
    start = time.perf_counter()
    profile = _profile(noise)
    chi_robot = parameter_vector(robot, params)
    payload_values = None if payload is None else as_payload(payload)
    chi = chi_robot if payload_values is None else add_payload(robot, chi_robot, payload_values)
    plant_seed, noise_seed = np.random.SeedSequence(seed).spawn(2)
    oversample = int(np.ceil(profile.servo_rate_hz / rate - 1e-9)) if profile.closed_loop else 1
    t, q, qd, qdd = reference(robot, trajectory, rate, oversample, duration)
    if profile.closed_loop:
        run = closed_loop(robot, t, q, qd, qdd, chi, (1 - profile.feedforward_error) * chi,
                          profile, np.random.default_rng(plant_seed), oversample)
    else:
        run = open_loop(robot, t, q, qd, qdd, chi)
    sigma = torque_noise_sigma(run.tau, profile.torque_noise)
    tau = run.tau + np.random.default_rng(noise_seed).normal(size=run.tau.shape) * sigma
    q_rec = run.q if profile.encoder_counts is None else quantise_positions(robot, run.q, profile.encoder_counts)
    error = run.q - run.q_ref
    meta = {
        "generator": "rx90sym.twin.simulate",
        "profile": asdict(profile),
        "seed": int(seed),
        "rate_hz": float(rate),
        "servo_rate_hz": float(rate * oversample) if profile.closed_loop else None,
        "true_parameters": dict(zip(robot.parameter_names, map(float, chi_robot))),
        "payload": payload_values,
        "payload_source": None if payload is None else (
            "mapping" if isinstance(payload, Mapping) else str(payload)),
        "torque_noise_sigma": sigma.tolist(),
        "tracking_error_rms": np.sqrt(np.mean(error**2, axis=0)).tolist(),
        "tracking_error_max": np.max(np.abs(error), axis=0).tolist(),
        "elapsed_s": time.perf_counter() - start,
    }
    if currents is None:
        return Recording(t=run.t, q=q_rec, tau=tau, source=f"twin:{profile.name}", robot=robot.name,
                         meta=meta)
    # A third stream of draws, so that the torque noise of the same seed is unchanged.
    current_seed = np.random.SeedSequence([seed, 1]).spawn(1)[0]
    meta["drive_gains"] = asdict(currents)
    return Recording(t=run.t, q=q_rec, tau=None, source=f"twin:{profile.name}", robot=robot.name,
                     meta=meta, current=currents.currents(robot, tau, np.random.default_rng(current_seed)))


__all__ = [
    "CurrentSensor", "NoiseProfile", "TwinRun", "closed_loop", "controller_gains", "coulomb_torques",
    "default_parameters", "forward_dynamics", "mass_matrix", "open_loop", "parameter_vector",
    "profiles", "quantise_positions", "reference", "simulate", "torque_noise_sigma",
]
