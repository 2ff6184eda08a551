"""Self-contained HTML report: tables and figures (PNG embedded as base64), one file."""
from __future__ import annotations

import base64
import html
import io
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from rx90sym.files import atomic_write

if TYPE_CHECKING:  # for annotations only
    import rx90sym


@dataclass(frozen=True)
class Section:
    """A titled block of the report: preformatted text (a table) and/or figures (id, caption, fig)."""

    title: str
    text: str = ""
    figures: tuple = ()


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # no display: files only
    import matplotlib.pyplot as plt

    return plt


def _png(fig: Any) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    _pyplot().close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


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
    """Estimates with their 2 sigma bars (and the truth when known)."""
    plt = _pyplot()
    c = len(result.names)
    fig, ax = plt.subplots(figsize=(max(8, 0.22 * c), 4))
    x = np.arange(c)
    ax.errorbar(x, result.values, yerr=2 * result.std, fmt="o", ms=3, capsize=2, label="estimate ± 2σ")
    if truth:
        ax.plot(x, [truth.get(n, np.nan) for n in result.names], "x", color="k", ms=4, label="truth")
    ax.set_xticks(x, result.names, rotation=90, fontsize=7)
    ax.set_yscale("symlog", linthresh=0.05)
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


def render(title: str, sections: Sequence[Section]) -> str:
    """The HTML text of a report."""
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>",
             "<style>body{font-family:sans-serif;max-width:1100px;margin:auto}"
             "pre{background:#f6f6f6;padding:8px;overflow-x:auto}figure{margin:12px 0}"
             "img{max-width:100%}</style></head><body>", f"<h1>{html.escape(title)}</h1>"]
    for s in sections:
        parts.append(f"<h2>{html.escape(s.title)}</h2>")
        if s.text:
            parts.append(f"<pre>{html.escape(s.text)}</pre>")
        for fig_id, caption, fig in s.figures:
            parts.append(f"<figure id='{html.escape(fig_id)}'><img alt='{html.escape(caption)}' "
                         f"src='data:image/png;base64,{_png(fig)}'><figcaption>{html.escape(caption)}"
                         f"</figcaption></figure>")
    parts.append("</body></html>")
    return "\n".join(parts)


def write_report(path: str | os.PathLike, title: str, sections: Sequence[Section]) -> Path:
    """Write the report atomically (temporary file, then rename): never a half-written file."""
    text = render(title, sections)
    return atomic_write(path, lambda handle: handle.write(text))


def identification_sections(robot: rx90sym.Robot, result: Any, recordings: Sequence[Any],
                            validation: Any = None, essential: Any = None,
                            truth: dict | None = None, fit_prediction: Any = None,
                            model: Any = None, extra_tables: Sequence[str] = ()) -> list[Section]:
    """The standard sections of an identification run.

    model: the FitModel (model and filtering recorded in the JSON), shown first; extra_tables:
    further text blocks of the parameter section (e.g. the bootstrap σ table)."""
    sections = []
    if model is not None:
        sections.append(Section("Model and filtering", "\n".join(
            f"{k}: {v}" for k, v in model.to_dict().items() if k != "gains")))
    sections.append(Section("Identified parameters", "\n\n".join([result.table(), *extra_tables]), (
        ("fig-parameters", "Base parameters with 2σ bars", parameter_figure(result, truth)),)))
    if essential is not None:
        sections.append(Section("Essential parameters", essential.table()))
    if fit_prediction is not None:
        sections.append(Section("Fit: measured vs predicted torques", "", (
            ("fig-torques", "Measured and predicted joint torques", torque_figure(fit_prediction, fit_prediction.source)),
            ("fig-residuals", "Residuals per joint", residual_figure(fit_prediction, "Residuals")))))
    if validation is not None:
        sections.append(Section("Cross-validation (all samples and while moving)", validation.table(), (
            ("fig-validation", "Torque prediction on the validation motion",
             torque_figure(validation, validation.source)),)))
    if recordings:
        rec = recordings[0]
        sections.append(Section("Trajectory", f"{rec.source}: {len(rec.t)} samples", (
            ("fig-trajectory", "Joint positions of the first recording",
             trajectory_figure(np.asarray(rec.t), np.asarray(rec.q))),)))
    return sections
