"""Torque offsets on chosen joints: a constant OFFj in joint j's equation, as columns of the base.

``Robot(offsets=True)`` puts an offset on every joint; the cross-validated choice
(:func:`identify.selection.processing_choice.choose_processing`) gives one to the joints whose
held-back error it clearly lowers, through :class:`OffsetBase`. Asymmetric Coulomb friction
(FSPj, FSNj) and an offset are collinear on moving samples: a joint with the asymmetric form never
gets an offset (:func:`offset_joints`).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, Sequence

import numpy as np

import rx90sym

__all__ = ["OffsetBase", "offset_base", "offset_columns", "offset_joints", "result_offsets"]


@dataclass(frozen=True, eq=False)
class OffsetBase:
    """``base`` with one column OFFj (a 1 in joint j's row) per joint of ``joints`` (0-based), after
    its own columns; usable as ``base`` everywhere (friction columns may wrap it)."""

    base: Any
    joints: tuple[int, ...]

    @cached_property
    def names(self) -> tuple[str, ...]:
        return tuple(self.base.names) + tuple(f"OFF{j + 1}" for j in self.joints)

    @property
    def nb(self) -> int:
        return len(self.names)

    def regressor_batch(self, Q: Any, QD: Any, QDD: Any, out: np.ndarray | None = None) -> np.ndarray:
        """[Phi_b | OFF columns]: (N, n, nb)."""
        Phi_b = self.base.regressor_batch(Q, QD, QDD)
        full = np.concatenate([Phi_b, offset_columns(Phi_b.shape[0], Phi_b.shape[1], self.joints)], axis=2)
        if out is None:
            return full
        out[...] = full
        return out


def offset_columns(samples: int, n: int, joints: Sequence[int]) -> np.ndarray:
    """(samples, n, len(joints)): per joint of ``joints`` (0-based) a column of ones in that joint's rows
    (the offsets' columns, the same after any filter of unit gain)."""
    cols = np.zeros((samples, n, len(joints)))
    for k, j in enumerate(joints):
        cols[:, j, k] = 1.0
    return cols


def offset_joints(robot: rx90sym.Robot, base: Any) -> tuple[int, ...]:
    """The joints (0-based) that may get an offset: none when the robot has them already, every
    joint without an asymmetric Coulomb column (FSPj/FSNj) otherwise."""
    if robot.offsets or any(str(name).startswith("OFF") for name in base.names):
        return ()
    asymmetric = {j for j in robot.asymmetric_coulomb}
    return tuple(j for j in range(robot.n) if j not in asymmetric)


def offset_base(base: Any, joints: Sequence[int]) -> Any:
    """``base`` with offsets on ``joints`` (0-based; ``base`` itself when none), added to those it has:
    the offsets of an OffsetBase are joined, and inside friction columns (a presliding or friction form's
    wrapping) the columns they wrap get them (their own columns stay after them)."""
    from dataclasses import replace

    joints = tuple(sorted(int(j) for j in joints))
    if not joints:
        return base
    if isinstance(base, OffsetBase):
        return OffsetBase(base.base, tuple(sorted(set(base.joints) | set(joints))))
    if hasattr(base, "terms") and hasattr(base, "base"):  # friction columns: their Coulomb terms index the inner ones
        return replace(base, base=offset_base(base.base, joints))
    return OffsetBase(base, joints)


def result_offsets(result: Any, robot: rx90sym.Robot) -> tuple[int, ...]:
    """The joints (0-based) given an offset column OFFj by a fit (``result.names``) that the robot's own
    base parameters lack (the cross-validated choice's offsets)."""
    own = set(rx90sym.base_parameters(robot).names)
    return tuple(int(nm[3:]) - 1 for nm in result.names
                 if nm.startswith("OFF") and nm[3:].isdigit() and nm not in own)
