"""The report's figures (matplotlib, no display): torques, residuals, parameters with 2σ, trajectory."""
from __future__ import annotations

import io
from typing import Any

import numpy as np

from .page import Figure


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # no display: files only
    import matplotlib.pyplot as plt

    return plt


#: Points of the figures: a recording's positions and torques are thinned to at most this many.
REPORT_POINTS = 20_000


def thinned(validation: Any, points: int = REPORT_POINTS) -> Any:
    """A validation's samples for a figure: every k-th sample scored, at most ``points``."""
    from dataclasses import replace

    every = slice(None, None, -(-validation.t.size // points))
    base, user = validation.baseline_predicted, validation.user_predicted
    return replace(validation, t=validation.t[every], measured=validation.measured[every],
                   predicted=validation.predicted[every], moving=validation.moving[every],
                   baseline_predicted=None if base is None else base[every],
                   user_predicted=None if user is None else user[every])


def figure(fig_id: str, caption: str, fig: Any) -> Figure:
    """A page :class:`Figure` from a matplotlib figure (PNG at 90 dpi; the figure is closed)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    _pyplot().close(fig)
    return Figure(fig_id, caption, buf.getvalue())


def torque_figure(validation: Any, title: str) -> Any:
    """Measured vs predicted torque per joint (N m)."""
    plt = _pyplot()
    n = validation.measured.shape[1]
    fig, axes = plt.subplots(n, 1, figsize=(9, 1.6 * n), sharex=True)
    for j, ax in enumerate(np.atleast_1d(axes)):
        ax.plot(validation.t, validation.measured[:, j], lw=0.8, label="measured")
        ax.plot(validation.t, validation.predicted[:, j], lw=0.8, label="predicted")
        moving = getattr(validation, "moving", None)
        if moving is not None and not moving[:, j].all():
            ax.fill_between(validation.t, 0, 1, where=~moving[:, j], transform=ax.get_xaxis_transform(),
                            color="0.85", lw=0, label="at rest")
        ax.set_ylabel(f"Γ{j + 1} [N·m]")
    np.atleast_1d(axes)[0].legend(loc="upper right", fontsize=8)
    np.atleast_1d(axes)[-1].set_xlabel("t [s]")
    fig.suptitle(title)
    return fig


def residual_figure(validation: Any, title: str) -> Any:
    """Residual (measured - predicted) per joint (N m)."""
    plt = _pyplot()
    n = validation.measured.shape[1]
    fig, axes = plt.subplots(n, 1, figsize=(9, 1.4 * n), sharex=True)
    for j, ax in enumerate(np.atleast_1d(axes)):
        ax.plot(validation.t, validation.measured[:, j] - validation.predicted[:, j], lw=0.7, color="C3")
        ax.set_ylabel(f"ρ{j + 1}")
    np.atleast_1d(axes)[-1].set_xlabel("t [s]")
    fig.suptitle(title)
    return fig


def parameter_figure(result: Any, truth: dict | None = None, title: str = "Parameters with 2σ") -> Any:
    """Estimates with their 2 sigma bars (and the truth when known), every bar inside the axes.

    Values of one sign within a factor 30 of each other (drive gains) get a linear axis, so that
    their differences show; others a symmetric log axis whose linear part is 1e-3 of the largest
    magnitude (a payload's Mc of kilograms beside its near-zero inertia products)."""
    plt = _pyplot()
    c = len(result.names)
    fig, ax = plt.subplots(figsize=(max(8, 0.22 * c), 4))
    x = np.arange(c)
    values = np.asarray(result.values, dtype=float)
    bars = 2 * np.nan_to_num(np.asarray(result.std, dtype=float), nan=0.0)
    ax.errorbar(x, values, yerr=bars, fmt="o", ms=3, capsize=2, label="estimate ± 2σ")
    shown = [values - bars, values + bars]
    if truth:
        ref = np.array([truth.get(n, np.nan) for n in result.names], dtype=float)
        ax.plot(x, ref, "x", color="k", ms=4, label="truth")
        shown.append(ref)
    ends = np.concatenate(shown)
    ends = ends[np.isfinite(ends)]
    mags = np.abs(values[np.isfinite(values) & (values != 0)])
    one_sign = mags.size == values.size and (np.all(values > 0) or np.all(values < 0))
    if one_sign and mags.max() <= 30 * mags.min():
        pad = 0.08 * (ends.max() - ends.min() or abs(ends.max()) or 1.0)
        ax.set_ylim(ends.min() - pad, ends.max() + pad)
    elif ends.size:
        top = float(np.abs(ends).max()) or 1.0
        ax.set_yscale("symlog", linthresh=1e-3 * top)
        ax.set_ylim(min(ends.min(), 0.0) * 1.5 - 1e-3 * top, max(ends.max(), 0.0) * 1.5 + 1e-3 * top)
    ax.set_xticks(x, result.names, rotation=90, fontsize=7)
    ax.axhline(0, color="0.7", lw=0.5)
    ax.legend(fontsize=8)
    ax.set_title(title)
    return fig


def trajectory_figure(t: np.ndarray, q: np.ndarray, title: str = "Trajectory (Khalil angles)") -> Any:
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(9, 3))
    for j in range(q.shape[1]):
        ax.plot(t, q[:, j], lw=0.9, label=f"q{j + 1}")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("q [rad]")
    ax.legend(fontsize=8, ncol=q.shape[1])
    ax.set_title(title)
    return fig
