"""The safety envelope as applied, for people: the JSON block of ``rx90 excite --json`` and the
lines printed with every trajectory (envelope.py builds the envelope).

Angles here are the controller's (q_controller = q_model + controller_offsets: what the user
types and what the logs hold), labelled as such; given ranges and a given centre pose are
reported exactly as given.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .envelope import Envelope, fixed_heights
from .model import ExcitationModel

if TYPE_CHECKING:
    import rx90sym
    from .robot_geometry import ArmGeometry


def describe(envelope: Envelope, geometry: ArmGeometry, model: ExcitationModel) -> dict[str, Any]:
    """JSON-ready description of the envelope as applied (printed with every trajectory); joint
    ranges and the centre pose in controller angles [rad]."""
    lim, offsets = model.limits, np.asarray(model.controller_offsets, float)
    caps = model.collision.capsules if model.collision is not None else None
    ranges = (np.asarray(envelope.position_limits, float) if envelope.position_limits is not None
              else np.c_[lim.q_min + offsets, lim.q_max + offsets])
    if envelope.centre is not None:
        centre = [float(v) + 0.0 for v in envelope.centre]
    else:  # found in model angles: no -0.0 nor 1e-17 residues of the offsets in what is printed
        centre = None if model.centre is None else (np.round(model.centre + offsets, 12) + 0.0).tolist()
    return {
        "angles": "controller", "controller_offsets_rad": offsets.tolist(),
        "mounting_plane_z_m": geometry.mounting_z, "mounting_plane_source": geometry.mounting_source,
        "margin_above_mounting_m": envelope.margin, "floor_above_mounting_m": envelope.floor,
        "z_min_m": model.z_min,
        "height_points": list(model.point_names[0]),
        "max_point_speed_m_s": envelope.max_speed, "speed_points": list(model.point_names[1]),
        "position_limits_rad": ranges.tolist(),
        "velocity_limits_rad_s": lim.qd_max.tolist(), "velocity_scale": envelope.velocity_scale,
        "acceleration_limits_rad_s2": lim.qdd_max.tolist(), "acceleration_scale": envelope.acceleration_scale,
        "urdf_default_acceleration": envelope.urdf_acceleration,
        "centre_pose_rad": centre,
        "centre_given": envelope.centre is not None,
        "capsules_source": geometry.source,
        "capsules": None if caps is None else [{"name": n, "radius_m": r} for n, r in zip(caps.names, caps.radii)],
        "self_collision": bool(model.collision is not None and model.collision.self_collision),
        "pairs_checked": 0 if caps is None else len(caps.pairs),
        "obstacles": [] if model.collision is None else [[*b.lo, *b.hi] for b in model.collision.boxes],
        "fixed_points_below_z_min": [],
    }


def describe_robot(envelope: Envelope, geometry: ArmGeometry, model: ExcitationModel,
                   robot: rx90sym.Robot) -> dict[str, Any]:
    """:func:`describe` plus the points no joint moves that lie below z_min (left out: the floor
    then cuts the arm's fixed part, which the user should know)."""
    out = describe(envelope, geometry, model)
    caps = model.collision.capsules if model.collision is not None else None
    if caps is not None:
        out["fixed_points_below_z_min"] = [f"{n} at z = {z:.4f} m" for n, z in fixed_heights(robot, geometry, caps)
                                           if z < model.z_min]
    return out


def summary_lines(info: dict[str, Any]) -> list[str]:
    """Human-readable lines of :func:`describe` (printed by ``rx90 excite``), angles in the
    description's convention (controller angles)."""
    deg, angles = np.degrees, info.get("angles", "controller")
    pos = ", ".join(f"[{deg(lo):.0f}, {deg(hi):.0f}]" for lo, hi in info["position_limits_rad"])
    return [
        f"safety envelope: no moving point below z = {info['z_min_m']:.3f} m in frame 0 (mounting plane z = "
        f"{info['mounting_plane_z_m']:.3f} m: {info['mounting_plane_source']}; margin {info['margin_above_mounting_m']:g} m"
        + (f"; floor {info['floor_above_mounting_m']:g} m above the mounting plane"
           if info["floor_above_mounting_m"] is not None else "") + ")",
        f"  joint ranges [deg, {angles} angles]: {pos}",
        f"  velocities x{info['velocity_scale']:g}: {', '.join(f'{v:.3g}' for v in info['velocity_limits_rad_s'])} rad/s; "
        f"accelerations x{info['acceleration_scale']:g}: {', '.join(f'{v:.3g}' for v in info['acceleration_limits_rad_s2'])} rad/s^2"
        + (" (URDF: no acceleration limits given, conservative default)" if info["urdf_default_acceleration"] else ""),
        f"  Cartesian speed <= {info['max_point_speed_m_s']:g} m/s at the tool point and {len(info['speed_points']) - 1} capsule ends",
        f"  self-collision: {info['pairs_checked']} capsule pairs ({len(info['capsules'] or [])} capsules from "
        f"{info['capsules_source']}); {len(info['obstacles'])} obstacle box(es)",
        f"  centre pose [deg, {angles} angles]: {', '.join(f'{v:.1f}' for v in deg(info['centre_pose_rad']))}"
        + (" (given)" if info["centre_given"] else ""),
    ] + ([f"  note: {len(info['fixed_points_below_z_min'])} point(s) no joint moves lie below z_min and are "
          f"left out (the floor cuts the arm's fixed part), e.g. {info['fixed_points_below_z_min'][0]}"]
         if info.get("fixed_points_below_z_min") else [])
