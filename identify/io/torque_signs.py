"""Torque signs: a log whose joint torques (or motor currents) count positive the other way than the
robot's description, joint by joint.

``signs`` holds one factor per joint, 1 (as logged) or -1 (negated): the log's columns ``tau_j`` and
``i_j`` are multiplied by ``signs[j]`` as they are read, before drive gains (:func:`with_torque_signs`
on each part of :func:`identify.io.log_rules.log_parts`: every input form, every length). The
identification's check (identify.fitting.plausibility.torque_sign_flags) names the signs that make
the torques agree with the description's inverse dynamics.
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Sequence

import numpy as np

import rx90sym
from rx90sym.recording import Recording

__all__ = ["parse_torque_signs", "signs_text", "with_torque_signs"]


def parse_torque_signs(signs: str | Sequence[float] | None, robot: rx90sym.Robot,
                 where: str = "torque_signs") -> tuple[float, ...] | None:
    """The signs checked for ``robot``: a text ``"1,-1,1,..."`` or a sequence, one per joint, each 1 or -1
    (None: none given). ``where``: the option's name in the messages (e.g. ``--torque-signs``).

    Raises ValueError naming the count expected or every value that is not 1 or -1."""
    if signs is None:
        return None
    if isinstance(signs, str):
        cells = [c.strip() for c in signs.split(",")]
        values: list[float | str] = []
        for c in cells:
            try:
                values.append(float(c))
            except ValueError:
                values.append(c)
    else:
        values = list(signs)
    n = int(robot.n)
    if len(values) != n:
        raise ValueError(f"{where}: {len(values)} sign(s) given for the {n} joints of robot {robot.name!r}: give one "
                         f"per joint, 1 (as logged) or -1 (negated), e.g. {signs_text([1.0] * n)}")
    bad = [(j, v) for j, v in enumerate(values)
           if isinstance(v, (bool, str)) or not isinstance(v, (int, float)) or not (math.isfinite(v) and abs(v) == 1)]
    if bad:
        raise ValueError(f"{where}: " + ", ".join(f"joint {j + 1}'s sign {v!r}" if isinstance(v, str) else
                                                  f"joint {j + 1}'s sign {v:g}" for j, v in bad)
                         + f" {'is' if len(bad) == 1 else 'are'} not 1 or -1 (one per joint: 1 as logged, -1 negated)")
    return tuple(float(v) for v in values)


def signs_text(signs: Sequence[float]) -> str:
    """``1,-1,1,...``: the signs as the option takes them."""
    return ",".join(f"{int(s):d}" for s in signs)


def with_torque_signs(rec: Recording, signs: Sequence[float] | None) -> Recording:
    """``rec`` with its joint torques and motor currents multiplied by ``signs`` column by column (the
    log's columns ``tau_j`` and ``i_j``; ``signs`` None or all 1: ``rec`` itself)."""
    if signs is None or all(s == 1 for s in signs):
        return rec
    s = np.asarray(signs, dtype=float)
    return replace(rec, tau=None if rec.tau is None else rec.tau * s,
                   current=None if rec.current is None else rec.current * s)
