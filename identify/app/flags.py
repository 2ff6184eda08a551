"""Plausibility flags on the command line: errors stop the run (exit 2, nothing written), warnings
are printed with the option that addresses them and kept for the JSON and the report."""
from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

from .common import progress

if TYPE_CHECKING:  # annotations only: the method is imported when a command runs
    from identify.fitting.plausibility import Flag

#: The option that addresses each flag (the library's messages quote no options).
HINTS = {
    "gains_negative": "swap --empty and --loaded",
    "payload_mass_negative": "swap --empty and --loaded",
    "gain_unidentified": "--fix J=VALUE",
    "gain_uncertain": "--fix J=VALUE",
    "estimate_not_physical": "--method consistent",
    "consistency_margin_negative": "--method consistent",
    "payload_inertia_not_physical": "--constrained",
    "torque_scale": "--gains K1,..,Kn in N m/A",
    "gains_scale": "--mass in kg",
    "payload_mass_on_bound": "--mass, --mass-tol",
    "bodies_far_from_prior": "--robot, --gains",
    "consistent_cost_high": "--robot, --gains",
    "rank_threshold": "--snap RAD for a URDF --robot",
}


def given_gain_flags(gains: object) -> list[Flag]:
    """Gains given with --gains (a DriveGains): all negative stops, one negative is a warning."""
    import numpy as np

    from identify.fitting.plausibility import gain_flags

    return settle(gain_flags(gains.gains, np.zeros_like(gains.gains)))


def checked(rec: object, robot: object) -> object:
    """The recording, refused when its positions do not fit the robot (degrees, swapped q/qd
    groups, out of range: identify.io.units.check_units)."""
    from identify.io.units import check_units

    check_units(rec.t, rec.q, rec.dq, robot, rec.source)
    return rec


#: Codes whose hint is the consistent fit: given only when the flag's action is to use it (never for
#: estimates that a torque sign or gain explains: identify.fitting.plausibility.SUSPECT_TORQUES).
_CONSISTENT_HINTED = ("estimate_not_physical", "consistency_margin_negative")


def with_hint(flag: Flag) -> str:
    from identify.fitting.plausibility import CONSISTENT_ACTION

    hint = HINTS.get(flag.code)
    if flag.code in _CONSISTENT_HINTED and flag.action != CONSISTENT_ACTION:
        hint = None
    return flag.line() + (f" [{hint}]" if hint else "")


def settle(flags: Sequence[Flag]) -> list[Flag]:
    """Raise on an error flag (exit 2; its message carries the option hint); print each warning."""
    from identify.fitting.plausibility import raise_errors

    errors = [f for f in flags if f.severity == "error"]
    if errors:
        raise ValueError("; ".join(with_hint(f) for f in errors))
    warnings = raise_errors(flags)
    for f in warnings:
        progress(f"warning: {with_hint(f)}")
    return warnings


def flag_lines(flags: Sequence[Flag]) -> str:
    """Lines printed under a result table ('' without flags)."""
    return "\n".join(f"flag [{f.code}]: {with_hint(f)}" for f in flags)
