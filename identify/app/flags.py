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


def checked_peaks(sources: Sequence[object], robot: object, block: int, torques: object = None,
                  units: bool = True) -> list:
    """Each recording source (identify.io.blocks) read once block by block: checked as a file is and, with
    ``units``, refused when its positions do not fit the robot (degrees, swapped q/qd groups, out of
    range: identify.io.units.check_units); returns the peak |torque| of each block, (1, n) arrays of
    ``torques(rec)`` (default the recorded torques; a block where it gives None has none)."""
    import numpy as np

    from identify.io.units import check_units

    peaks = []
    for src in sources:
        for rec in src.scan(block):
            new = rec.select(slice(int(rec.meta.get("new_from", 0)), None))
            if units:
                check_units(new.t, new.q, new.dq, robot, src.source)
            tau = new.tau if torques is None else torques(new)
            if tau is not None and len(tau):
                peaks.append(np.max(np.abs(np.asarray(tau, dtype=float)), axis=0)[None, :])
    return peaks


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
    """Print each warning, then raise on an error flag (exit 2; its message carries the option hint)."""
    from identify.fitting.plausibility import raise_errors

    errors = [f for f in flags if f.severity == "error"]
    warnings = [f for f in flags if f.severity != "error"]
    for f in warnings:  # first: what they say may be the cause of the error (a torque sign, a gain)
        progress(f"warning: {with_hint(f)}")
    if errors:
        raise ValueError("; ".join(with_hint(f) for f in errors))
    raise_errors(flags)
    return warnings


def flag_lines(flags: Sequence[Flag]) -> str:
    """Lines printed under a result table ('' without flags)."""
    return "\n".join(f"flag [{f.code}]: {with_hint(f)}" for f in flags)
