"""Content of the excitation report: the envelope along time, as a table and figures.

:func:`along_time` evaluates, on samples of the trajectory, the tool point's path (frame 0), the
largest Cartesian point speed, the largest joint velocity and acceleration as fractions of the
experiment's limits, the lowest height above the envelope's floor and the smallest clearance
between capsules (and obstacle boxes); :func:`worst` and :func:`figures` present them. The
application puts them in its HTML report (identify.app.report).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from .constraints import evaluate_heights, evaluate_speeds
from .model import ExcitationModel

if TYPE_CHECKING:
    import rx90sym


@dataclass(frozen=True, eq=False)
class EnvelopeSeries:
    """Along time t (N,) [s]: tool (N, 3) [m, frame 0]; speed (N,) [m/s] largest point speed;
    velocity, acceleration (N,) largest |qd|/qd_max and |qdd|/qdd_max over the joints; height
    (N,) [m] lowest point above z_min; clearance (N,) [m] smallest capsule clearance (inf: none);
    speed_max [m/s], clearance_margin [m]."""

    t: np.ndarray
    tool: np.ndarray
    speed: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    height: np.ndarray
    clearance: np.ndarray
    speed_max: float
    clearance_margin: float


def along_time(robot: rx90sym.Robot, model: ExcitationModel, trajectory: Any, tool_point: Any,
               rate: float = 100.0, clearance_margin: float = 0.03) -> EnvelopeSeries:
    """The envelope's quantities on samples of ``trajectory`` at ``rate`` [Hz]."""
    t, q, qd, qdd = trajectory.sample(rate, closed=True)
    qs = ca.SX.sym("q", robot.n)
    t0n = robot.forward_kinematics(qs)[0]
    tool_f = ca.Function("tool", [qs], [ca.mtimes(t0n, ca.DM([*tool_point, 1.0]))[:3]])
    tool = np.asarray(tool_f.map(len(t), "serial")(q.T)).T
    speeds = evaluate_speeds(model, q, qd)
    heights = evaluate_heights(model, q)
    lim = model.limits
    clearance = (model.collision.exact(q) if model.collision is not None else np.full(len(t), np.inf))
    return EnvelopeSeries(
        t, tool, np.zeros(len(t)) if speeds is None else speeds.max(axis=1),
        np.max(np.abs(qd) / lim.qd_max, axis=1), np.max(np.abs(qdd) / lim.qdd_max, axis=1),
        np.full(len(t), np.inf) if heights is None else heights.min(axis=1) - model.z_min,
        clearance, float(model.speed_max or np.inf), clearance_margin)


def worst(s: EnvelopeSeries) -> list[tuple[str, str, float | None, float | None, str]]:
    """Per quantity: (name, unit, worst value, its time [s], limit); None where not checked."""
    rows = [("largest point speed", s.speed, "max", f"{s.speed_max:g} m/s", "m/s"),
            ("joint velocity / limit", s.velocity, "max", "1", ""),
            ("joint acceleration / limit", s.acceleration, "max", "1", ""),
            ("lowest point above the floor", s.height, "min", "0 m", "m"),
            ("smallest clearance", s.clearance, "min", f"0 m ({s.clearance_margin:g} m kept by the optimiser)", "m")]
    out = []
    for name, x, kind, limit, unit in rows:
        if not np.all(np.isfinite(x)):
            out.append((name, unit, None, None, "not checked"))
            continue
        k = int(np.argmax(x) if kind == "max" else np.argmin(x))
        out.append((name, unit, float(x[k]), float(s.t[k]), limit))
    return out


def figures(s: EnvelopeSeries) -> list[tuple[str, str, Any]]:
    """(id, caption, matplotlib figure): the tool path's projections, and the limits along time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path, axes = plt.subplots(1, 3, figsize=(12, 3.6))
    for ax, (i, j, name) in zip(axes, ((0, 1, "x-y (top)"), (0, 2, "x-z (side)"), (1, 2, "y-z (front)"))):
        ax.plot(s.tool[:, i], s.tool[:, j], lw=0.8)
        ax.plot(s.tool[0, i], s.tool[0, j], "o", label="start and end")
        ax.set_title(name)
        ax.set_xlabel("xyz"[i] + " [m]")
        ax.set_ylabel("xyz"[j] + " [m]")
        ax.axis("equal")
    axes[0].legend(fontsize=7)
    timeline, ax = plt.subplots(4, 1, figsize=(10, 8), sharex=True)
    ax[0].plot(s.t, s.speed)
    ax[0].axhline(s.speed_max, color="r", ls="--")
    ax[0].set_ylabel("point speed [m/s]")
    ax[1].plot(s.t, s.velocity, label="velocity")
    ax[1].plot(s.t, s.acceleration, label="acceleration")
    ax[1].axhline(1.0, color="r", ls="--")
    ax[1].set_ylabel("joints / limit")
    ax[1].legend(fontsize=7)
    ax[2].plot(s.t, s.height)
    ax[2].axhline(0.0, color="r", ls="--")
    ax[2].set_ylabel("above floor [m]")
    if np.all(np.isfinite(s.clearance)):
        ax[3].plot(s.t, s.clearance)
        ax[3].axhline(0.0, color="r", ls="--")
    ax[3].set_ylabel("clearance [m]")
    ax[3].set_xlabel("t [s]")
    return [("fig-tool-path", "Tool point path, projections in frame 0", path),
            ("fig-envelope-time", "Speeds, joint limits, height and clearance along time (limits dashed)", timeline)]
