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
from ..forward_dynamics import coulomb_torques, forward_dynamics, mass_matrix
from .noise import CurrentSensor, NoiseProfile, profiles, quantise_positions, torque_noise_sigma
from .reference_motion import reference
from .run import simulate
from .servo import TwinRun, closed_loop, controller_gains, open_loop
from .truth import default_parameters, parameter_vector
__all__ = [
    "CurrentSensor", "NoiseProfile", "TwinRun", "closed_loop", "controller_gains", "coulomb_torques",
    "default_parameters", "forward_dynamics", "mass_matrix", "open_loop", "parameter_vector",
    "profiles", "quantise_positions", "reference", "simulate", "torque_noise_sigma",
]
