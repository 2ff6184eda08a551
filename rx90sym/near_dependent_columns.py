"""A base-parameter set whose rank depends on the rank threshold: the model's fault, not the motion's.

The base columns' regressor, stacked on random states (the richest motion there is) with each
column scaled to norm 1, has singular values of order 0.1-1 for a sound model (measured on every
bundled robot, with and without offsets, and the test URDFs: the smallest over the largest is
0.13-0.18) and exactly 0 for a dependency, which the base parameters have grouped away (below
:data:`rx90sym.base_parameters.RANK_TOL`). A singular value in between (:data:`GAP_TOP` and
below) is a column that is almost, but not exactly, a combination of the others: typically a
joint origin written 1.5708 for pi/2, which tilts an axis by 3.7e-6 rad and keeps a rotor inertia
apart from the link inertia it should be grouped with (rx90sym.urdf_snap). No motion identifies
such a column: its estimate is the difference of two huge numbers. :func:`rank_gap` finds it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .base_parameters import RANK_TOL, BaseParameters, stacked_regressor
from .parameters import split_name

#: Singular values (relative to the largest) at or below this and above RANK_TOL are in the gap.
GAP_TOP = 1e-3
#: A column is named when its weight in a gap singular vector is at least this share of the largest.
NAMED_SHARE = 0.1


@dataclass(frozen=True)
class RankGap:
    """Near-dependent base columns: ``columns`` (parameter names) and their 1-based ``joints``;
    ``gap``: the singular values in the gap and ``signal`` the smallest above it, relative to
    the largest; ``threshold``: the rank threshold the base parameters used (relative)."""

    columns: tuple[str, ...]
    joints: tuple[int, ...]
    gap: tuple[float, ...]
    signal: float
    threshold: float

    def message(self) -> str:
        gap = ", ".join(f"{s:.2g}" for s in self.gap)
        return (f"the base-parameter regressor's rank depends on the rank threshold: its normalised singular "
                f"values fall from {self.signal:.3g} to {gap} (rank threshold {self.threshold:g}), columns "
                f"{', '.join(self.columns)} of joint{'s' if len(self.joints) > 1 else ''} "
                f"{', '.join(map(str, self.joints))} are almost but not exactly dependent (the model's "
                f"geometry, not the motion)")


def rigid_base(base: Any) -> BaseParameters:
    """The rigid-body BaseParameters inside a base with spring or friction columns."""
    while not isinstance(base, BaseParameters) and hasattr(base, "base"):
        base = base.base
    if not isinstance(base, BaseParameters):
        raise TypeError(f"rank_gap: expected base parameters, got {type(base).__name__}")
    return base


def _joint_of(name: str) -> int | None:
    try:
        return split_name(name[:-1] if name.endswith("R") else name)[1]
    except ValueError:
        return None


def rank_gap(base: Any, samples: int = 60, seed: int = 0) -> RankGap | None:
    """The near-dependent columns of ``base`` (module docstring), None for a sound model."""
    bp = rigid_base(base)
    W = stacked_regressor(bp.robot, samples, seed)[:, list(bp.independent)]
    norms = np.linalg.norm(W, axis=0)
    if W.shape[1] == 0 or not np.all(norms > 0):
        return None
    _, s, Vt = np.linalg.svd(W / norms, full_matrices=False)
    rel = s / s[0]
    weak = np.flatnonzero((rel <= GAP_TOP) & (rel > RANK_TOL))
    if weak.size == 0:
        return None
    weight = np.abs(Vt[weak]).max(axis=0)
    named = [i for i in np.argsort(-weight) if weight[i] >= NAMED_SHARE * weight.max()]
    names = tuple(bp.names[i] for i in sorted(named))
    joints = sorted({j for j in map(_joint_of, names) if j is not None})
    strong = rel[rel > GAP_TOP]
    return RankGap(names, tuple(joints), tuple(float(rel[i]) for i in weak),
                   float(strong.min()) if strong.size else float("nan"), RANK_TOL)
