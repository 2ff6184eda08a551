"""Programs a controller runs: a URScript program (UR) and a 1 kHz joint-position stream (Franka).

UR (URScript manual, "servoj" and "movej"): the program moves with ``movej`` at low speed
(MOVEJ_SPEED, MOVEJ_ACCELERATION) to the start pose (if given) and to the trajectory's first
sample, then sends one ``servoj(q, 0, 0, t, lookahead_time, gain)`` per sample, t = the
controller's period (e-Series 500 Hz: 0.002 s; CB3 125 Hz: 0.008 s), and returns with ``movej``.
servoj blocks for t, so the samples play at the controller's rate. Without a start pose the
program first reads the arm's joint positions and stops (``popup``, ``halt``) unless every joint
is within START_TOLERANCE of the trajectory's first sample: the first ``movej`` then never
travels from an unchecked pose. lookahead_time (0.03-0.2 s)
smooths the target with a look-ahead filter (larger: smoother, more lag); gain (100-2000) is the
proportional gain (larger: tighter tracking, more overshoot); UR_LOOKAHEAD 0.1 s and UR_GAIN 300
are the URScript defaults' middle ground, documented in docs/excitation.md. Angles are the
controller's (model + controller offsets).

Franka (libfranka, "Robot and interface specifications"): a joint-position motion generator
receives one position per millisecond; the samples are checked against Franka's published joint
velocity, acceleration and jerk limits and the torque rate limit (1000 N m/s) before writing.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

import numpy as np

from rx90sym.files import atomic_write

UR_RATES = {"e-series": 500.0, "cb3": 125.0}  # [Hz] servoj period of each controller generation
UR_LOOKAHEAD = 0.1   # [s]
UR_GAIN = 300.0
MOVEJ_SPEED = 0.25   # [rad/s] approach and return moves
MOVEJ_ACCELERATION = 0.5  # [rad/s^2]
#: Without a start pose, the arm must already be this close to the first sample, every joint [rad].
START_TOLERANCE = 0.05

# Franka Emika, "Robot and interface specifications" (libfranka documentation), per joint.
FRANKA_VELOCITY = (2.1750, 2.1750, 2.1750, 2.1750, 2.6100, 2.6100, 2.6100)      # rad/s
FRANKA_ACCELERATION = (15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0)                  # rad/s^2
FRANKA_JERK = (7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0)         # rad/s^3
FRANKA_TORQUE_RATE = 1000.0                                                       # N m/s
FRANKA_RATE = 1000.0                                                              # Hz


def _vector(q: Sequence[float]) -> str:
    return "[" + ", ".join(f"{v:.9f}" for v in q) + "]"


def urscript(q: np.ndarray, rate: float, start_pose: Sequence[float] | None = None,
             lookahead: float = UR_LOOKAHEAD, gain: float = UR_GAIN, name: str = "excitation") -> str:
    """The URScript program for samples q (N, 6) [rad, controller angles] at ``rate`` [Hz]."""
    if not 0.03 <= lookahead <= 0.2:
        raise ValueError(f"servoj lookahead_time must be in [0.03, 0.2] s, got {lookahead}")
    if not 100.0 <= gain <= 2000.0:
        raise ValueError(f"servoj gain must be in [100, 2000], got {gain}")
    period = 1.0 / rate
    move = f"a={MOVEJ_ACCELERATION:g}, v={MOVEJ_SPEED:g}"
    lines = [f"def {name}():",
             f"  # {len(q)} servoj samples at {rate:g} Hz (t = {period:g} s), lookahead_time {lookahead:g} s, "
             f"gain {gain:g}; controller joint angles [rad]"]
    if start_pose is not None:
        lines.append(f"  movej({_vector(start_pose)}, {move})")
    else:  # the approach from wherever the arm is was not checked: it must already be at the start
        lines += [f"  start = {_vector(q[0])}",
                  "  now = get_actual_joint_positions()",
                  "  i = 0",
                  f"  while i < {q.shape[1]}:",
                  f"    if norm(now[i] - start[i]) > {START_TOLERANCE:g}:",
                  f'      popup("the arm is not within {START_TOLERANCE:g} rad of the trajectory\'s start on every '
                  'joint: move it there first (or plan with --start-pose)", title="excitation", error=True)',
                  "      halt",
                  "    end",
                  "    i = i + 1",
                  "  end"]
    lines.append(f"  movej({_vector(q[0])}, {move})")
    lines += [f"  servoj({_vector(row)}, 0, 0, {period:g}, {lookahead:g}, {gain:g})" for row in q]
    lines.append("  stopj(2.0)")
    back = start_pose if start_pose is not None else q[0]
    lines.append(f"  movej({_vector(back)}, {move})")
    lines.append("end")
    lines.append(f"{name}()")
    return "\n".join(lines) + "\n"


def parse_servoj(text: str) -> np.ndarray:
    """The servoj targets (N, n) of a URScript program written by :func:`urscript`."""
    rows = []
    for line in text.splitlines():
        line = line.strip()
        if line.startswith("servoj(["):
            rows.append([float(v) for v in line[len("servoj(["):line.index("]")].split(",")])
    return np.array(rows)


def write_urscript(path: str | os.PathLike, q: np.ndarray, rate: float,
                   start_pose: Sequence[float] | None = None, **options: float) -> Path:
    """Write :func:`urscript` atomically."""
    text = urscript(q, rate, start_pose, **options)
    return atomic_write(path, lambda f: f.write(text))


def franka_check(q: np.ndarray, tau: np.ndarray | None = None, rate: float = FRANKA_RATE,
                 qd: np.ndarray | None = None) -> list[str]:
    """Franka's limits broken by positions q (N, 7) [rad] at ``rate`` (finite differences, as
    libfranka checks them) and torques tau (N, 7) [N m] (torque rate), naming joint and time.
    qd (N, 7) [rad/s]: where a joint's velocity changes sign its model torque steps by twice its
    Coulomb friction (a step of the friction model, not of the motion): that joint's torque rate
    is not counted there."""
    out = []
    derivs = {"velocity": (np.diff(q, axis=0) * rate, FRANKA_VELOCITY, "rad/s")}
    derivs["acceleration"] = (np.diff(derivs["velocity"][0], axis=0) * rate, FRANKA_ACCELERATION, "rad/s^2")
    derivs["jerk"] = (np.diff(derivs["acceleration"][0], axis=0) * rate, FRANKA_JERK, "rad/s^3")
    if tau is not None:
        rate_tau = np.diff(tau, axis=0) * rate
        if qd is not None:
            rate_tau[np.sign(qd[1:]) != np.sign(qd[:-1])] = 0.0
        derivs["torque rate"] = (rate_tau, (FRANKA_TORQUE_RATE,) * q.shape[1], "N m/s")
    for kind, (x, limit, unit) in derivs.items():
        ratio = np.abs(x) / np.asarray(limit[:q.shape[1]])
        k, j = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
        if ratio[k, j] > 1.0:
            out.append(f"Franka {kind} limit of joint {j + 1} exceeded at t = {k / rate:.4f} s: "
                       f"{x[k, j]:.6g} {unit} (limit {limit[j]:g})")
    return out


def write_franka(path: str | os.PathLike, q: np.ndarray) -> Path:
    """One line per millisecond: the 7 joint positions [rad] a libfranka JointPositions motion
    generator returns (``franka::JointPositions{q}``), CSV with a header q1..q7."""
    header = ",".join(f"q{j + 1}" for j in range(q.shape[1]))
    body = "\n".join(",".join(f"{v:.9f}" for v in row) for row in q)
    return atomic_write(path, lambda f: f.write(header + "\n" + body + "\n"))
