"""The rollout validation: a model in MuJoCo from the recorded state at the start of each window while the
arm moves, under the recorded joint torques, scored at the window's end beside the constant-velocity guess.

Exactly (docs/rollout.md): the model ``rx90 export --mjcf`` writes (identify.rollout.model), stepped at
the recording's period or a divisor of it (identify.rollout.simulate), from the recorded q and the start
velocity (the fit's filtered derivative, or the recorded q̇) at each window start, the recorded joint
torques (drive gains applied, advanced by the fit's delay) held over each sample as ``qfrc_applied``;
windows of round(L x rate) samples that do not overlap (identify.rollout.samples), those where no joint
reaches the rest threshold on any sample not scored; error q_model(t0+L) - q_recorded(t0+L) and the same
of q̇; the guess q(t0) + q̇(t0)·L on the same windows.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

import rx90sym

from identify.io.blocks import DEFAULT_BLOCK
from identify.observation.defaults import DEFAULT_MIN_VELOCITY
from identify.rollout.defaults import DEFAULT_START_VELOCITY, FIGURE_WINDOWS, window_lengths
from identify.rollout.model import nominal_model, simulator_model, simulator_parameters
from identify.rollout.result import GUESS, Rollout, WindowPath, WindowScores
from identify.rollout.samples import RolloutSource, Samples, WindowCutter
from identify.rollout.simulate import Simulator

__all__ = ["roll_out", "roll_out_fit"]


@dataclass
class _Tally:
    """The scores of one window length as the windows go by."""

    length: float
    names: tuple[str, ...]
    figure_at: list[int]
    position: dict[str, list] = field(default_factory=dict)
    velocity: dict[str, list] = field(default_factory=dict)
    rest: int = 0
    bridged: int = 0
    diverged: dict[str, int] = field(default_factory=dict)
    paths: list[WindowPath] = field(default_factory=list)
    samples: int = 0
    length_s: float = float("nan")

    def wants_path(self, index: int) -> bool:
        return bool(self.figure_at) and index >= self.figure_at[0] and len(self.paths) < FIGURE_WINDOWS

    def scores(self) -> WindowScores:
        n_names = (*self.names, GUESS)
        return WindowScores(self.length, self.length_s, self.samples,
                            {m: np.array(self.position[m]) for m in n_names},
                            {m: np.array(self.velocity[m]) for m in n_names},
                            self.rest, self.bridged, dict(self.diverged), tuple(self.paths))


def _figure_indices(total: int) -> list[int]:
    """Window numbers spread over the recording whose paths the figure shows (the next scored one when
    one is at rest)."""
    if total <= 0:
        return []
    return sorted({int(round(x)) for x in np.linspace(0, total - 1, FIGURE_WINDOWS + 2)[1:-1]})


def roll_out(robot: rx90sym.Robot, params: Mapping[str, float] | Sequence[float], recording: Any,
            windows: Any, *, cutoff: float, delay: float = 0.0, min_velocity: float | None = None,
            gains: Any = None, convention: str | None = None, block: int = DEFAULT_BLOCK,
            payload: Mapping[str, float] | None = None, friction: Mapping[str, Any] | None = None,
            extra: Mapping[str, float] | None = None, nominal: bool = True,
            velocity: str = DEFAULT_START_VELOCITY) -> Rollout:
    """Roll the model of ``params`` (standard parameters of ``robot``) out in MuJoCo over ``recording`` (a
    recording or a recording file) in windows of each length of ``windows`` [s] ("0.25,0.5" or numbers);
    module docstring.

    cutoff [Hz]: the filter of the start velocities (the fit's); delay [s]: the torques advanced by it
    (the fit's); min_velocity [rad/s]: the rest threshold (None: DEFAULT_MIN_VELOCITY); gains,
    convention, block: how a file is read (the fit's); payload: XXc..Mc on the flange of every model;
    friction, extra: the fit file's ``model.friction`` record and values beyond the standard parameters
    (smooth friction forms applied from the fit); nominal: also roll out the description's own bodies
    (identify.rollout.model.nominal_model); velocity: "filtered" or "recorded".

    ValueError (nothing computed): a window <= 0 or longer than the recording's longest segment, no
    window scored (the recording shorter than one window while moving), a body MuJoCo refuses.
    """
    lengths = window_lengths(windows)
    models = [simulator_model(robot, params, "identified", payload, friction, extra)]
    what = "nominal: not asked"
    if nominal:
        other, what = nominal_model(robot, params, payload, friction, extra)
        if other is not None:
            models.append(other)
    source = RolloutSource(robot, recording, cutoff, delay, velocity, gains, convention, block)
    spans = source.spans_s()
    for length in lengths:
        if length > max(spans):
            raise ValueError(f"{source.source}: a rollout window of {length:g} s is longer than the recording "
                             f"({max(spans):.4g} s of filtered samples"
                             + (" in its longest segment)" if len(spans) > 1 else ")"))
    threshold = DEFAULT_MIN_VELOCITY if min_velocity is None else float(min_velocity)
    names = tuple(m.name for m in models)
    cutters = {L: WindowCutter(L) for L in lengths}
    tallies = {}
    for L, cutter in cutters.items():
        total = sum(max(0, (p.length - 2 * p.edge - 1) // cutter.samples(p.rate)) for p in source.plans)
        tallies[L] = _Tally(L, names, _figure_indices(total), {m: [] for m in (*names, GUESS)},
                            {m: [] for m in (*names, GUESS)})
    sims = [Simulator(m) for m in models]
    for piece in source.pieces():
        for sim in sims:
            sim.set_period(1.0 / piece.rate)
        for L, cutter in cutters.items():
            for w in cutter.feed(piece):
                _score(robot, sims, w, tallies[L], threshold)
    for L, tally in tallies.items():
        if not tally.position[GUESS]:
            raise ValueError(f"{source.source}: no window of {L:g} s while the arm moves (every window of the recording "
                             f"is at rest below {threshold:g} rad/s or holds bridged samples: {tally.rest} at rest, "
                             f"{tally.bridged} bridged); the recording is shorter than one window while moving")
    first = sims[0]
    return Rollout(source.source, names, {m.name: m.terms for m in models}, what, velocity, float(cutoff),
                   float(delay), threshold, first.sm.model.opt.timestep, first.substeps,
                   tuple(tallies[L].scores() for L in lengths), payload is not None)


def _score(robot: rx90sym.Robot, sims: Sequence[Simulator], w: Samples, tally: _Tally, threshold: float) -> None:
    """One window: skipped (bridged samples; at rest) or rolled out by every model and scored."""
    if not w.measured.all():
        tally.bridged += 1
        return
    if not np.any(np.abs(w.speed) >= threshold):
        tally.rest += 1
        return
    keep = tally.wants_path(w.index)
    if not tally.samples:
        tally.samples = w.t.size - 1
        tally.length_s = tally.samples / w.rate
    duration = w.t[-1] - w.t[0]
    q0, v0 = robot.to_controller(w.q[0]), w.dq[0]
    paths = {}
    for sim in sims:
        q, v, path, unstable = sim.run(q0, v0, w.tau[:-1], keep)
        name = sim.sm.name
        if unstable:
            tally.diverged[name] = tally.diverged.get(name, 0) + 1
            q, v = np.full_like(q, np.nan), np.full_like(v, np.nan)
        tally.position[name].append(robot.to_model(q) - w.q[-1])
        tally.velocity[name].append(v - w.dq[-1])
        if keep:
            paths[name] = robot.to_model(path)
    tally.position[GUESS].append(w.q[0] + w.dq[0] * duration - w.q[-1])
    tally.velocity[GUESS].append(w.dq[0] - w.dq[-1])
    if keep:
        paths[GUESS] = w.q[0] + np.outer(w.t - w.t[0], w.dq[0])
        tally.paths.append(WindowPath(w.t.copy(), w.q.copy(), paths))
        tally.figure_at = [i for i in tally.figure_at if i > w.index]


def roll_out_fit(fit: Any, recording: Any, windows: Any, *, block: int | None = None, convention: str | None = None,
                payload: Mapping[str, float] | None = None, nominal: bool = True,
                velocity: str = DEFAULT_START_VELOCITY, delay: float | None = None) -> Rollout:
    """:func:`roll_out` of a fit's own model (identify.rollout.model.simulator_parameters: what ``rx90
    export --mjcf`` writes) with the fit's processing: its cut-off, torque delay (or ``delay`` [s]), rest
    threshold, drive gains, angle convention and block (``fit``: an identify.Fit)."""
    robot, params = simulator_parameters(fit)
    result = fit.result
    extra = dict(zip(result.names, (float(v) for v in result.values)))
    return roll_out(robot, params, recording, windows, cutoff=fit.cutoff, delay=fit.delay if delay is None else delay,
                   min_velocity=fit.min_velocity, gains=fit.gains, convention=convention or fit.model.convention,
                   block=block if block is not None else (fit.block or DEFAULT_BLOCK), payload=payload,
                   friction=fit.model.friction, extra=extra, nominal=nominal, velocity=velocity)
