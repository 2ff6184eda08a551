"""Noise profiles of the twin and what its sensors do to the signals (encoders, torque noise, currents)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np


if TYPE_CHECKING:  # for annotations only
    from ..description import Robot


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
