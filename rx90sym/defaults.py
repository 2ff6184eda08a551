"""Defaults of the model that a command's help shows: the tolerances URDF joint origins are snapped
with, the acceleration limits assumed for a URDF, the twin's noise profile (standard library only:
``rx90 --help`` shows them without importing NumPy or the URDF reader)."""
from __future__ import annotations

__all__ = ["SNAP_RAD", "SNAP_LENGTH_M", "MAX_SNAP_RAD", "MAX_SNAP_LENGTH_M", "ACCELERATION_PER_VELOCITY",
           "ACCELERATION_CAP", "ACCELERATION_DEFAULT_TEXT", "TWIN_NOISE"]

#: Default angle tolerance [rad] of :mod:`rx90sym.urdf_snap`. Catches every multiple of pi/2 up to
#: 2 pi written with two decimals or more (1.57: 8.0e-4 off; 3.14: 1.6e-3; 4.71: 2.4e-3; 6.28:
#: 3.2e-3; 1.571: 2.0e-4; 1.5708: 3.7e-6); an axis snapped wrongly moves by at most 4 mrad
#: (0.23 deg). docs/urdf.md.
SNAP_RAD = 4e-3
#: Default length tolerance [m]: residues such as 1e-6 m are zeros; 10 um is below any drawn offset.
SNAP_LENGTH_M = 1e-5
#: Largest accepted angle tolerance [rad] (beyond it a deliberate angle could be snapped).
MAX_SNAP_RAD = 0.01
#: Largest accepted length tolerance [m] (beyond it a drawn offset could be zeroed).
MAX_SNAP_LENGTH_M = 1e-3

#: A URDF has no acceleration limits: each joint's is assumed to be this many times its velocity limit
#: [1/s] (full speed in 0.5 s), at most ACCELERATION_CAP; the one assumption of every command and of
#: the library (the excitation's envelope used to apply it on top of a loader default of 10 rad/s^2).
ACCELERATION_PER_VELOCITY = 2.0
#: The assumed limit's ceiling, and the limit of a joint without a velocity limit [rad/s^2, m/s^2].
ACCELERATION_CAP = {"revolute": 10.0, "prismatic": 2.0}
#: The assumption in words (help texts, warnings).
ACCELERATION_DEFAULT_TEXT = (f"{ACCELERATION_PER_VELOCITY:g} x each joint's velocity limit per second, at most "
                             f"{ACCELERATION_CAP['revolute']:g} rad/s^2 ({ACCELERATION_CAP['prismatic']:g} m/s^2 "
                             f"prismatic)")

#: Noise profile of the twin (rx90sym.twin.simulate, rx90 simulate): the closed-loop robot with
#: encoder quantisation and torque noise (rx90sym.twin.noise.profiles).
TWIN_NOISE = "realistic"
