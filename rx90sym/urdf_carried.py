"""What a URDF robot's moving links carry besides their own inertial (a hand, fingers, fixed
links): the exported link k is the fitted body minus them, and the consistent fit keeps that
difference physical too (rx90sym.physical.parameter_problems, ``carried``)."""
from __future__ import annotations

from typing import Mapping

import numpy as np

from .description import Robot
from .rigid_body import RigidBody
from .urdf_tree import relative_pose, zero_poses

__all__ = ["carried_bodies", "lumped_body"]


def lumped_body(chain, poses: dict, k: int, inertials: Mapping[str, RigidBody] | None = None,
                own: bool = True) -> RigidBody:
    """The inertials moving link k lumps (its own URDF link's too when ``own``), in that link's frame;
    ``inertials``: URDF link -> body in its frame (default: the file's ``<inertial>`` elements)."""
    link, out = chain.links[k], RigidBody.zero()
    inertials = chain.tree.inertials if inertials is None else inertials
    for c in chain.lumped[k]:
        if own or c != link:
            out = out + inertials[c].expressed_in_parent(*relative_pose(poses[link], poses[c]))
    return out


def _children(chain, poses: dict, k: int) -> RigidBody:
    """The inertials that moving link k carries besides its own URDF link's, in that link's frame."""
    return lumped_body(chain, poses, k, own=False)


def carried_bodies(robot: Robot) -> dict[str, tuple[np.ndarray, tuple[str, ...]]]:
    """What a URDF robot's moving links carry besides their own inertial (a hand, fingers, fixed
    links): ``{"k": (XX..M in Khalil frame k, the URDF links)}`` for each link k that carries any
    (empty for a robot file). The exported link k is the fitted body minus this one, which the
    consistent fit keeps physical too (rx90sym.physical.parameter_problems, ``carried``)."""
    if robot.urdf is None:
        return {}
    chain = robot.urdf
    poses = zero_poses(chain.tree)
    out = {}
    for k, link in enumerate(chain.links):
        names = tuple(c for c in chain.lumped[k] if c != link)
        if names:
            out[str(k + 1)] = (_children(chain, poses, k).expressed_in_child(*chain.link_to_khalil[k]).vector(), names)
    return out
