"""The bodies of an identified model beside the prior's: per link mass, centre of mass and principal
inertias (what a user checks against the maker's data sheet)."""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rx90sym.physical import INERTIAL_FIELDS
from rx90sym.rigid_body import RigidBody

__all__ = ["bodies_table", "link_body"]


def link_body(values: Mapping[str, float], j: int | str) -> RigidBody | None:
    """Link ``j``'s body from standard parameters (None when they do not hold it)."""
    try:
        return RigidBody.from_vector(np.array([float(values[f"{p}{j}"]) for p in INERTIAL_FIELDS]))
    except KeyError:
        return None


def bodies_table(n: int, standard: Mapping[str, float], prior: Mapping[str, float] | None) -> str:
    """Per link: mass [kg] (and the prior's, their ratio), centre of mass in frame j [m] and principal
    inertias at it [kg m^2], beside the prior's where it has a body; the whole arm's mass last."""
    head = (f"{'link':<5}{'mass kg':>9}{'prior':>9}{'ratio':>7}   {'CoG m (frame j)':<27}{'prior CoG':<27}"
            f"principal inertias at CoG kg m^2 (prior)")
    lines, total, total0 = [head], 0.0, 0.0
    for j in range(1, n + 1):
        body, pb = link_body(standard, j), link_body(prior, j) if prior is not None else None
        if body is None:
            continue
        total += body.m
        c, I = body.com_inertia() if body.m > 0 else (np.full(3, np.nan), np.full((3, 3), np.nan))
        if pb is not None and pb.m > 0:
            total0 += pb.m
            pc, pI = pb.com_inertia()
            lines.append(f"{j:<5}{body.m:9.3f}{pb.m:9.3f}{body.m / pb.m:7.2f}   {_vec(c):<27}{_vec(pc):<27}"
                         f"{_vec(np.linalg.eigvalsh(I), '.3g')} ({_vec(np.linalg.eigvalsh(pI), '.3g')})")
        else:
            lines.append(f"{j:<5}{body.m:9.3f}{'—':>9}{'—':>7}   {_vec(c):<27}{'—':<27}{_vec(np.linalg.eigvalsh(I), '.3g')}")
    ratio = f"{total / total0:7.2f}" if total0 > 0 else f"{'—':>7}"
    lines.append(f"{'arm':<5}{total:9.3f}{(f'{total0:9.3f}' if total0 > 0 else f'{chr(8212):>9}')}{ratio}")
    return "\n".join(lines)


def _vec(x: np.ndarray, fmt: str = "+.3f") -> str:
    return "[" + " ".join(f"{v:{fmt}}" for v in x) + "]"
