"""Defaults of the payload identification (standard library only: ``rx90 payload --help`` shows
them without importing the methods)."""
from __future__ import annotations

__all__ = ["MASS_TOL"]

#: Tolerance of the weighed mass in the constrained fit [kg]: |Mc − mass| <= MASS_TOL (a kitchen or
#: parcel scale's error on a few kilograms).
MASS_TOL = 0.05
