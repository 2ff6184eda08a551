"""The result: an excitation trajectory, its samples and its files."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .constraints import LimitReport
from rx90sym.files import write_json

from .export import write_csv
from .fourier import FourierSeries
from .model import renamed_offsets
from .via_points import ViaPointSpline

Form = FourierSeries | ViaPointSpline


@dataclass(frozen=True)
class SolveInfo:
    """How a trajectory was obtained (all times in s)."""

    method: str                 # "ipopt multi-start" or "random"
    seed: int
    starts: int = 0             # starts run
    feasible_starts: int = 0
    iterations: int = 0         # IPOPT iterations of the kept start (all stages)
    total_iterations: int = 0   # over all starts
    time_s: float = 0.0
    status: str = ""            # IPOPT return status of the kept start's last stage
    surrogate_cond: float = float("nan")  # exp(f_p / 2) on the optimisation grid
    grid_rate_hz: float = float("nan")
    best_start: int = 0         # number of the kept start (1-based)
    skipped_starts: tuple[int, ...] = ()  # starts not run (time budget)
    criterion_value: float = float("nan")  # the criterion of the kept start (see objective.py)


@renamed_offsets
@dataclass(frozen=True, eq=False)
class Trajectory:
    """A rest-to-rest excitation trajectory in Khalil angles.

    coefficients: Fourier (2L+1, n) rows [q0, a_1..a_L, b_1..b_L] [rad, rad/s], or via-point
    positions (K, n) [rad]. cond: condition number of the unscaled, unweighted base observation
    matrix on ``cond_rate`` [Hz] samples (true sign for Coulomb friction). usage: limit usage
    checked on the fine grid.
    """

    form: Form
    coefficients: np.ndarray
    cond: float
    criterion: str
    controller_offsets: np.ndarray
    usage: LimitReport
    info: SolveInfo
    cond_rate: float = 250.0
    parameter_names: tuple[str, ...] | None = field(default=None)
    envelope: dict[str, Any] | None = field(default=None)  # the safety envelope applied (envelope_description.describe, controller angles)

    def __post_init__(self) -> None:
        for name in ("coefficients", "controller_offsets"):
            a = np.array(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        if self.coefficients.shape[0] != self.form.n_coefficients:
            raise ValueError(f"trajectory: {self.coefficients.shape[0]} coefficient rows for a form "
                             f"with {self.form.n_coefficients}")

    # ----------------------------------------------------------------- description
    @property
    def n(self) -> int:
        """Number of joints."""
        return self.coefficients.shape[1]

    @property
    def duration(self) -> float:
        """T [s]."""
        return self.form.duration

    @property
    def harmonics(self) -> int | None:
        """L (Fourier form), None for via points."""
        return getattr(self.form, "harmonics", None)

    @property
    def base_frequency(self) -> float | None:
        """w_f = 2 pi / T [rad/s] (Fourier form), None for via points."""
        return getattr(self.form, "base_frequency", None)

    # ----------------------------------------------------------------- samples
    def sample(self, rate: float = 250.0, closed: bool = False
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(t [s] (N,), q [rad], qd [rad/s], qdd [rad/s^2] (N, n)) in Khalil angles.

        t_k = k / rate over one period, N = round(T rate) samples (t = T excluded: it repeats
        t = 0); closed=True appends t = T, where the robot is back at rest at its start.
        """
        t = sample_times(self.duration, rate, closed)
        q, qd, qdd = self.form.evaluate(self.coefficients, t)
        return t, q, qd, qdd

    def start_position(self) -> np.ndarray:
        """q(0) = q(T) [rad], Khalil angles: where the robot must be before starting."""
        return self.form.evaluate(self.coefficients, [0.0])[0][0]

    # ----------------------------------------------------------------- files
    def save(self, path: str | os.PathLike, rate: float = 250.0) -> Path:
        """CSV at ``rate`` [Hz], Staubli angles, t = 0..T, header t,q1..qn,dq1..dqn,ddq1..ddqn.

        Units s, rad, rad/s, rad/s^2. Written atomically (temporary file + os.replace).
        """
        t, q, qd, qdd = self.sample(rate, closed=True)
        n = self.n
        header = (["t"] + [f"q{j}" for j in range(1, n + 1)] + [f"dq{j}" for j in range(1, n + 1)]
                  + [f"ddq{j}" for j in range(1, n + 1)])
        rows = np.hstack([t[:, None], q + self.controller_offsets, qd, qdd])
        return write_csv(path, header, rows)

    def summary(self) -> dict[str, Any]:
        """JSON-ready description: form, coefficients, criterion, cond, limit usage, optimiser."""
        out: dict[str, Any] = dict(self.form.describe())
        # Neutral words: the model's angles (Khalil) and the controller's = model + controller offsets.
        out["angles"] = "model"
        out["controller_offsets_rad"] = self.controller_offsets.tolist()
        if isinstance(self.form, FourierSeries):
            parts = self.form.split(self.coefficients)
            out["coefficients"] = {
                "q0_rad": parts["q0"].tolist(), "a_rad_s": parts["a"].tolist(),
                "b_rad_s": parts["b"].tolist(),
                "series": "q_i(t) = q0_i + sum_l a_il/(l wf) sin(l wf t) - b_il/(l wf) cos(l wf t)",
            }
        else:
            out["via_positions_rad"] = self.coefficients.tolist()
        out["start_position_rad"] = self.start_position().tolist()
        out["criterion"] = self.criterion
        out["cond"] = self.cond
        out["cond_rate_hz"] = self.cond_rate
        if self.parameter_names is not None:
            out["base_parameters"] = len(self.parameter_names)
        out["limits_usage"] = self.usage.to_dict()
        if self.envelope is not None:
            out["envelope"] = self.envelope
        info = {k: (list(v) if isinstance(v, tuple) else v) for k, v in vars(self.info).items()}
        out["optimiser"] = {k: (None if isinstance(v, float) and not np.isfinite(v) else v)
                            for k, v in info.items()}
        return out

    def save_json(self, path: str | os.PathLike) -> Path:
        """Write :meth:`summary` as JSON, atomically."""
        return write_json(path, self.summary())

    # ----------------------------------------------------------------- plots
    def plot(self, rate: float = 250.0, axes: Any = None) -> Any:
        """Positions, velocities and accelerations against time, each as a fraction of its limit
        when limits are given; returns the matplotlib figure (see excitation.plotting)."""
        from .plotting import plot_trajectory

        return plot_trajectory(self, rate=rate, axes=axes)


def sample_times(duration: float, rate: float, closed: bool = False) -> np.ndarray:
    """k / rate for k = 0..round(T rate) - 1 (plus T when closed) [s]."""
    if not np.isfinite(rate) or rate <= 0.0:
        raise ValueError(f"sample rate must be > 0 Hz, got {rate}")
    count = int(round(duration * rate))
    if count < 2:
        raise ValueError(f"sample rate {rate} Hz gives fewer than 2 samples over {duration} s")
    t = np.arange(count) / rate
    return np.append(t, duration) if closed else t
