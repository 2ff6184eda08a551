"""Notebook plots of a trajectory (matplotlib is imported only when a plot is asked for)."""
from __future__ import annotations

from typing import Any

import numpy as np


def _pyplot() -> Any:
    try:
        import matplotlib.pyplot as plt
    except ImportError as exc:  # plotting is optional: the rest of the package works without it
        raise ImportError("excitation plots need matplotlib (pip install matplotlib)") from exc
    return plt


def plot_trajectory(traj: Any, rate: float = 250.0, axes: Any = None) -> Any:
    """Three stacked panels: q [deg, Staubli angles], qd [deg/s], qdd [deg/s^2] against t [s]."""
    plt = _pyplot()
    t, q, qd, qdd = traj.sample(rate, closed=True)
    if axes is None:
        fig, axes = plt.subplots(3, 1, sharex=True, figsize=(9, 7))
    else:
        fig = np.ravel(axes)[0].figure
    panels = ((np.degrees(q + traj.controller_offsets), "q [deg]"), (np.degrees(qd), "qd [deg/s]"),
              (np.degrees(qdd), "qdd [deg/s²]"))
    for ax, (values, label) in zip(np.ravel(axes), panels):
        for j in range(values.shape[1]):
            ax.plot(t, values[:, j], lw=1.0, label=f"joint {j + 1}")
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    np.ravel(axes)[0].legend(ncol=traj.n, fontsize="small", loc="upper right")
    np.ravel(axes)[0].set_title(f"excitation trajectory, cond = {traj.cond:.1f} ({traj.cond_rate:g} Hz)")
    np.ravel(axes)[-1].set_xlabel("t [s]")
    return fig


def plot_limit_usage(traj: Any, ax: Any = None) -> Any:
    """Grouped bars: fraction of each limit used per joint (1 = at the limit), from traj.usage."""
    plt = _pyplot()
    if ax is None:
        fig, ax = plt.subplots(figsize=(8, 3.5))
    else:
        fig = ax.figure
    kinds = ("position", "velocity", "acceleration", "torque")
    joints = np.arange(1, traj.n + 1)
    width = 0.8 / len(kinds)
    for i, kind in enumerate(kinds):
        values = np.nan_to_num(getattr(traj.usage, kind), nan=0.0)
        ax.bar(joints + (i - 1.5) * width, values, width, label=kind)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xticks(joints)
    ax.set_xlabel("joint")
    ax.set_ylabel("max |x| / limit")
    ax.legend(fontsize="small")
    return fig
