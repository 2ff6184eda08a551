"""The rollout in a report: its table per window length (from the validation record's ``rollout``), a
figure of a few windows (recorded, each model, the constant-velocity guess), and the page of
``rx90 predict --report``."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from .cells import number
from .figures import _pyplot, figure
from .page import Cell, Column, Figure, Page, Section, Summary, Table, Text, write_page
from .summary import heldout_flags, heldout_table, next_steps
from .tables import validation_table

__all__ = ["predict_page", "rollout_blocks", "rollout_figure", "rollout_figures", "rollout_tables",
           "write_predict_report"]

#: Colours of the figure's lines, per model (the guess dashed).
_STYLE = {"recorded": dict(color="k", lw=1.4), "identified": dict(color="C0", lw=1.0),
          "nominal": dict(color="C2", lw=0.9), "guess": dict(color="C1", lw=0.9, ls="--")}


def rollout_tables(rollout: Mapping[str, Any]) -> tuple[Table, ...]:
    """Per window length: per model (and the guess) and joint, the RMS end-position [mrad] and
    end-velocity [mrad/s] errors, and the share of windows where the model beats the guess [%] (a model
    marked where it does not beat the guess's RMS)."""
    out = []
    for k, w in enumerate(rollout.get("windows") or []):
        pos, vel, share = (w.get(key) or {} for key in ("end_position_rms_rad", "end_velocity_rms_rad_s",
                                                          "beats_guess_share"))
        guess = pos.get("guess") or []
        n = len(guess)
        rows = []
        for name in pos:
            marks = ["" if name == "guess" or number(g) is None or number(v) is None else
                     ("ok" if v < g else "poor") for v, g in zip(pos[name], guess)]
            rows.append((name, "end position", "mrad",
                         *(Cell(None if v is None else 1e3 * v, mk) for v, mk in zip(pos[name], marks))))
        for name in vel:
            rows.append((name, "end velocity", "mrad/s", *(None if v is None else 1e3 * v for v in vel[name])))
        for name in share:
            rows.append((name, "beats the guess", "% windows", *(None if v is None else 100 * v for v in share[name])))
        columns = (Column("model", text=True), Column("RMS error of", text=True), Column("unit", text=True),
                   *(Column(f"j{j + 1}", digits=3) for j in range(n)))
        note = (f"{w.get('windows_scored')} windows of {w.get('samples_per_window')} samples scored, "
                f"{w.get('windows_skipped_at_rest')} at rest skipped"
                + (f", {w['windows_skipped_bridged']} with bridged samples skipped" if w.get("windows_skipped_bridged")
                   else "") + "; ✓ / ✗: the model's end-position RMS below / above the constant-velocity guess's.")
        out.append(Table(f"rollout-{k}", f"Rollout, windows of {w.get('window_s')} s: RMS end errors per joint",
                         columns, tuple(rows), note))
    return tuple(out)


def rollout_figure(paths: Sequence[Any], title: str) -> Any:
    """A few windows (columns) per joint (rows): the recorded positions, each model's and the guess's."""
    plt = _pyplot()
    n = paths[0].recorded.shape[1]
    fig, axes = plt.subplots(n, len(paths), figsize=(2.6 * len(paths) + 1.5, 1.35 * n), squeeze=False)
    for c, p in enumerate(paths):
        for j in range(n):
            ax = axes[j, c]
            ax.plot(p.t, p.recorded[:, j], label="recorded", **_STYLE["recorded"])
            for name, q in p.paths.items():
                ax.plot(p.t, q[:, j], label=name, **_STYLE.get(name, {}))
            ax.tick_params(labelsize=7)
            if c == 0:
                ax.set_ylabel(f"q{j + 1} [rad]", fontsize=8)
        axes[-1, c].set_xlabel("t [s]", fontsize=8)
    axes[0, 0].legend(fontsize=7, loc="best")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def rollout_blocks(rollout: Mapping[str, Any]) -> tuple:
    """The report's rollout blocks from the validation record's ``rollout``: how it ran, its tables."""
    terms = [f"{m}: {t}" for m, ts in (rollout.get("terms") or {}).items() for t in ts]
    text = Text((f"The model of rx90 export --mjcf in MuJoCo (step {1e3 * (number(rollout.get('step_s')) or 0):.4g} ms, "
                 f"{rollout.get('substeps')} per sample), from the recorded q and the "
                 + ("filtered derivative" if rollout.get("start_velocity") == "filtered" else "recorded q̇")
                 + f" at each window's start, under the recorded joint torques (gains applied, delay "
                 f"{1e3 * (number(rollout.get('delay_s')) or 0):.3g} ms) held over each sample; windows where no joint "
                 f"reaches {rollout.get('moving_threshold')} rad/s are at rest, not scored. Guess: "
                 f"{rollout.get('guess')}.", str(rollout.get("nominal", "")), *terms))
    return (text, *rollout_tables(rollout))


def rollout_figures(rollout: Any) -> tuple[Figure, ...]:
    """The figure of the first window length's windows (``rollout``: an identify.Rollout, or None)."""
    scores = getattr(rollout, "windows", None)
    if not scores or not scores[0].paths:
        return ()
    w = scores[0]
    return (figure("fig-rollout", f"Windows of {w.asked_s:g} s: recorded positions, the models' and the "
                   "constant-velocity guess's", rollout_figure(w.paths, f"Rollouts of {w.asked_s:g} s")),)


def predict_page(record: Mapping[str, Any], figures: Sequence[Figure] = (), validation: Any = None) -> Page:
    """``rx90 predict --report``: the held-out torque errors, then the rollout when asked."""
    flags = heldout_flags(record)
    rollout = record.get("rollout")
    facts = [("Recording", str(record.get("source", ""))), ("Identification", str(record.get("identification", "")))]
    if record.get("robot_warning"):
        facts.append(("Robot", str(record["robot_warning"])))
    headline = "Torques predicted on " + str(record.get("source", ""))
    if rollout:
        first = (rollout.get("windows") or [{}])[0]
        pos = first.get("end_position_rms_rad") or {}
        ident, guess = pos.get("identified") or [], pos.get("guess") or []
        beaten = sum(1 for a, b in zip(ident, guess) if number(a) is not None and number(b) is not None and a < b)
        headline += (f"; in MuJoCo the identified model's end-position RMS at {first.get('window_s')} s is below the "
                     f"constant-velocity guess's on {beaten} of {len(guess)} joints")
    sections = [Section("validation", "Held-out torques", (validation_table(record), *figures))]
    if rollout:
        sections.append(Section("rollout", "Rollout in MuJoCo", (*rollout_blocks(rollout),
                                                                   *rollout_figures(validation.rollout))))
    return Page("Prediction", str(record.get("identification", "")),
                Summary(headline, tuple(facts), heldout_table(record), tuple(flags), next_steps(flags)), tuple(sections))


def write_predict_report(path: str | os.PathLike, record: Mapping[str, Any], validation: Any) -> Path:
    """The page of ``rx90 predict --report`` (the JSON ``record`` it prints, the validation's figures)."""
    from .figures import thinned, torque_figure

    shown = thinned(validation)
    fig = figure("fig-validation", f"Torques on {validation.source} (grey: joint at rest)",
                 torque_figure(shown, validation.source))
    return write_page(path, predict_page(record, (fig,), validation))
