"""``simulate``: a recording of the twin following a trajectory (see the package docstring)."""
from __future__ import annotations

import time
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

from ..defaults import TWIN_NOISE
from ..payloads import Payload, add_payload, as_payload
from ..recording import Recording
from .noise import CurrentSensor, NoiseProfile, _profile, quantise_positions, torque_noise_sigma
from .reference_motion import Trajectory, reference
from .servo import closed_loop, open_loop
from .truth import parameter_vector

if TYPE_CHECKING:  # for annotations only
    from ..description import Robot


def simulate(robot: Robot, trajectory: Trajectory, params: Mapping[str, float] | Any | None = None,
             payload: str | Path | Payload | None = None, noise: str | NoiseProfile = TWIN_NOISE,
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

__all__ = ["simulate"]
