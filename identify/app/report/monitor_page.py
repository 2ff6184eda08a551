"""The report of ``rx90 monitor``: contact events, thresholds, the residual against them."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .figures import _pyplot, figure
from .page import Column, Page, Section, Summary, Table, Text, write_page


def residual_figure(envelope: tuple[np.ndarray, ...], events: list[Mapping[str, Any]]) -> Any:
    """Per joint: the residual's envelope (min/max per block of samples) against ± the threshold
    with its friction slack; contact events shaded."""
    plt = _pyplot()
    t, lo, hi, level, _ = envelope
    n = lo.shape[1]
    fig, axes = plt.subplots(n, 1, figsize=(9, 1.4 * n), sharex=True)
    for j, ax in enumerate(np.atleast_1d(axes)):
        ax.fill_between(t, lo[:, j], hi[:, j], color="C0", lw=0.6, step="post", label="residual r")
        ax.plot(t, level[:, j], color="C3", lw=0.7, drawstyle="steps-post", label="± threshold")
        ax.plot(t, -level[:, j], color="C3", lw=0.7, drawstyle="steps-post")
        for e in events:
            ax.axvspan(e["start_s"], e["end_s"], color="C1", alpha=0.25, lw=0)
        ax.set_ylabel(f"r{j + 1} [N·m]")
    np.atleast_1d(axes)[0].legend(loc="upper right", fontsize=8)
    np.atleast_1d(axes)[-1].set_xlabel("t [s] from the first sample")
    fig.suptitle("Momentum residual against the thresholds (contact events shaded)")
    return fig


def monitor_page(record: Mapping[str, Any], envelope: tuple[np.ndarray, ...] | None) -> Page:
    events = list(record["events"])
    n = len(record["thresholds_nm"])
    ev_table = Table("events", "Contact events (times from the recording's first sample)",
                     (Column("start", "s", decimals=3), Column("end", "s", decimals=3), Column("joints", text=True))
                     + tuple(Column(f"peak {j + 1}", "N·m", decimals=2) for j in range(n)),
                     tuple((e["start_s"], e["end_s"], ",".join(map(str, e["joints"])), *e["peak_nm"]) for e in events))
    joints = Table("joints", "Per joint: observer gain, threshold and the smallest external torque reported within "
                   "50 ms, moving and at rest (static friction cannot be told from an external torque)",
                   (Column("joint", decimals=0), Column("K_O", "rad/s", decimals=1), Column("threshold", "N·m", decimals=3),
                    Column("detectable moving", "N·m", decimals=2), Column("detectable at rest", "N·m", decimals=2)),
                   tuple((j + 1, record["gain"][j], record["thresholds_nm"][j], record["detectable_moving_nm"][j],
                          record["detectable_rest_nm"][j]) for j in range(n)))
    blocks: list[Any] = [ev_table] if events else [Text(("No contact event.",))]
    if envelope is not None:
        blocks.append(figure("fig-residual", "Residual envelope against ± threshold (with the friction slack)",
                             residual_figure(envelope, events)))
    summary = Summary(f"{len(events)} contact event(s) in {record['duration_s']:.3f} s",
                      (("Recording", str(record.get("source", ""))), ("Identification", str(record.get("identification", ""))),
                       ("Fit SHA-256", str(record.get("fit_sha256", ""))[:16]),
                       ("Thresholds from", str(record.get("thresholds_from", "")))))
    return Page("Contact monitor", str(record.get("source", "")), summary,
                (Section("events", "Events", tuple(blocks)), Section("joints", "Thresholds", (joints,))))


def write_monitor_report(path: str | os.PathLike, record: Mapping[str, Any],
                         envelope: tuple[np.ndarray, ...] | None) -> Path:
    return write_page(path, monitor_page(record, envelope))
