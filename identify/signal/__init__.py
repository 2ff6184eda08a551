"""Signals: zero-phase filtering and derivatives (eq. 20), parallel decimation, resampling, run pairing, torque delay.

Import from the modules of this package (or from `identify` for the public API)."""
