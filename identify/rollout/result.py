"""What a rollout found: per window length, the end-position and end-velocity errors of each model and
of the constant-velocity guess on the same windows, the windows skipped, and a few windows' paths."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from identify.estimation.results import json_number

__all__ = ["GUESS", "Rollout", "WindowPath", "WindowScores"]

#: The constant-velocity guess q(t0) + q̇(t0)·L (its end velocity q̇(t0)), scored beside the models.
GUESS = "guess"


def _listed(a: np.ndarray) -> list:
    return [json_number(v) for v in np.asarray(a, dtype=float)]


@dataclass(frozen=True, eq=False)
class WindowPath:
    """One window's positions for a figure: t (N+1,) [s]; recorded (N+1, n) [rad]; paths: model name
    (and GUESS) -> (N+1, n) [rad], model angles."""

    t: np.ndarray
    recorded: np.ndarray
    paths: dict[str, np.ndarray]


@dataclass(frozen=True, eq=False)
class WindowScores:
    """The windows of one length: asked_s and length_s [s] (round(L x rate) samples of the first segment,
    ``samples``); position, velocity: name (each model, and GUESS) -> (W, n) end errors q_model(t0+L) -
    q_recorded(t0+L) [rad] and of q̇ [rad/s] on the W windows scored; skipped_rest: windows where no
    joint moves on any sample; skipped_bridged: windows with a sample bridged over lost packets;
    diverged: name -> windows where MuJoCo reset an unstable simulation (their errors NaN); paths: a
    few windows for a figure."""

    asked_s: float
    length_s: float
    samples: int
    position: dict[str, np.ndarray]
    velocity: dict[str, np.ndarray]
    skipped_rest: int = 0
    skipped_bridged: int = 0
    diverged: dict[str, int] = field(default_factory=dict)
    paths: tuple[WindowPath, ...] = ()

    @property
    def windows(self) -> int:
        return int(next(iter(self.position.values())).shape[0])

    def rms(self, name: str, kind: str = "position") -> np.ndarray:
        """(n,) RMS end error of ``name`` per joint over the windows [rad or rad/s] (NaN windows left out)."""
        e = (self.position if kind == "position" else self.velocity)[name]
        return np.sqrt(np.nanmean(e ** 2, axis=0))

    def beats_guess(self, name: str) -> np.ndarray:
        """(n,) share of the windows where model ``name``'s end position is nearer the recorded than the guess's."""
        return np.mean(np.abs(self.position[name]) < np.abs(self.position[GUESS]), axis=0)

    def to_dict(self, models: tuple[str, ...]) -> dict[str, Any]:
        return {"window_s": self.asked_s, "length_s": self.length_s, "samples_per_window": self.samples,
                "windows_scored": self.windows, "windows_skipped_at_rest": self.skipped_rest,
                "windows_skipped_bridged": self.skipped_bridged,
                "end_position_rms_rad": {m: _listed(self.rms(m)) for m in (*models, GUESS)},
                "end_velocity_rms_rad_s": {m: _listed(self.rms(m, "velocity")) for m in (*models, GUESS)},
                "beats_guess_share": {m: _listed(self.beats_guess(m)) for m in models},
                "diverged_windows": {m: int(self.diverged.get(m, 0)) for m in models}}


@dataclass(frozen=True, eq=False)
class Rollout:
    """A rollout validation (identify.rollout.run): ``source``; ``models``: the models simulated
    ("identified", then "nominal" when the description has bodies); ``terms``: per model, each term
    beyond MuJoCo's joint properties and where it is carried; ``nominal``: what the nominal model is, or
    why there is none; start_velocity ("filtered", "recorded"), cutoff_hz (its filter), delay_s (torques
    advanced), threshold (rad/s: a window where no joint reaches it is at rest), step_s and substeps (of
    the first segment: MuJoCo's step and steps per sample), windows: per length asked."""

    source: str
    models: tuple[str, ...]
    terms: dict[str, tuple[str, ...]]
    nominal: str
    start_velocity: str
    cutoff_hz: float
    delay_s: float
    threshold: float
    step_s: float
    substeps: int
    windows: tuple[WindowScores, ...]
    payload: bool = False

    def header(self) -> str:
        speed = (f"the filtered derivative (cut-off {self.cutoff_hz:.4g} Hz)" if self.start_velocity == "filtered"
                 else "the recorded q̇")
        return (f"Rollout on {self.source} in MuJoCo (the MJCF of rx90 export --mjcf"
                + (" with the payload" if self.payload else "") + f"; step {1e3 * self.step_s:.4g} ms, "
                f"{self.substeps} per sample): from the recorded q and {speed} at each window's start, the recorded "
                f"joint torques (gains applied, delay {1e3 * self.delay_s:.3g} ms) held over each sample; windows "
                f"where no joint reaches {self.threshold:g} rad/s are at rest, not scored")

    def table(self) -> str:
        """The terminal table: per window length and model, the RMS end errors per joint and the share
        of windows beating the constant-velocity guess."""
        lines = [self.header()]
        n = next(iter(self.windows[0].position.values())).shape[1]
        joints = "  ".join(f"{'j' + str(j + 1):>6}" for j in range(n))
        for w in self.windows:
            skipped = f"{w.skipped_rest} at rest skipped" + (f", {w.skipped_bridged} with bridged samples skipped"
                                                              if w.skipped_bridged else "")
            lines.append(f"window {w.asked_s:g} s ({w.samples} samples, {w.length_s:.4g} s): {w.windows} windows scored, "
                         f"{skipped}")
            for kind, unit in (("position", "mrad"), ("velocity", "mrad/s")):
                lines.append(f"  {f'end-{kind} RMS error [{unit}]':<32}{joints}")
                for m in (*self.models, GUESS):
                    lines.append(f"    {m:<30}" + "  ".join(f"{1e3 * v:6.3g}" for v in w.rms(m, kind)))
            lines.append(f"  {'beats the guess [% of windows]':<32}{joints}")
            for m in self.models:
                lines.append(f"    {m:<30}" + "  ".join(f"{100 * v:6.0f}" for v in w.beats_guess(m)))
            for m, count in w.diverged.items():
                if count:
                    lines.append(f"  {m}: {count} window(s) where MuJoCo reset an unstable simulation (left out)")
        lines.append(self.nominal)
        for m in self.models:
            for term in self.terms.get(m, ()):
                lines.append(f"{m}: {term}")
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """The validation record's ``rollout`` entry (SI units: rad, rad/s)."""
        return {"source": self.source, "models": list(self.models), "nominal": self.nominal,
                "terms": {m: list(t) for m, t in self.terms.items()}, "start_velocity": self.start_velocity,
                "cutoff_hz": json_number(self.cutoff_hz), "delay_s": self.delay_s,
                "moving_threshold": self.threshold, "step_s": self.step_s, "substeps": self.substeps,
                "payload": self.payload, "guess": "q(t0) + q̇(t0)·L on the same windows",
                "windows": [w.to_dict(self.models) for w in self.windows]}
