"""Settings of the excitation optimiser and the check of a request before any solve.

:class:`OptimiserOptions` holds the grids, stages and IPOPT settings of optimiser.py;
:func:`check_request` refuses, before anything is built, a request that no trajectory can satisfy
or that the optimisation grid cannot resolve.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .constraints import Margins, kinematic_grid_rate, range_centre
from .model import ExcitationModel
from .objective import Objective
from .trajectory import Form

MAX_COND = 1e6  # above this W is numerically rank deficient: the trajectory identifies nothing


@dataclass(frozen=True)
class OptimiserOptions:
    """Settings of :func:`optimise_model` (defaults chosen for the RX90, 20 s, 5 harmonics).

    criterion: a name of defaults.OBJECTIVES or an :class:`Objective` (with the noise, reference
        magnitudes, selection and prior information it needs); "cond" is the raw cond(W).
    grid_rate [Hz]: optimisation grid for the criterion (must exceed twice the highest harmonic).
        The smooth terms need little (the trapezoid rule is spectrally accurate on a periodic
        trajectory); the Coulomb columns set the rate: 20 Hz with sign_eps = 0.1 rad/s gave
        cond 24.5 on average over 4 RX90 starts against 26.4 at 10 Hz (24.5 at 40 Hz, 2.6x slower).
    constraint_rate [Hz]: grid on which the limits are imposed with their margins; None: the
        rate at which the margins provably cover kinematic overshoot between samples
        (constraints.kinematic_grid_rate), never below 4 x the highest harmonic. Fewer constraint
        rows make each IPOPT iteration cheaper (the L-BFGS update costs back-solves per row).
    torque_rate [Hz]: grid on which torque limits are imposed from the start; None (default):
        nowhere at first; after a fine-grid violation, on the constraint grid plus the violating
        times. (Lazily, a start on the RX90 takes 12 s instead of 110 s: the torque Jacobian
        dominates every iteration, while the torque limits are rarely active.)
    verify_rate [Hz]: independent fine grid on which every limit is checked after the solve.
    cond_rate [Hz]: rate of the samples on which the reported cond is computed (controller rate).
    max_frequency [Hz]: highest harmonic allowed (keeps clear of structural resonances).
    sign_eps [rad/s]: tanh(qd / eps) replaces sign(qd) in the criterion during optimisation.
    p_schedule: cond surrogate stages, 0 = scale-free log-determinant warm start. Measured on
        the RX90 (20 Hz grid, 4 starts): (4, 16) mean cond 24.5 in 10 s per start, (0, 4, 16)
        24.9 in 16 s, (4, 16, 64) 24.7 in 18 s: the log-determinant warm start is available but
        does not pay for itself here.
    max_iter: IPOPT iterations per stage; tol, acceptable_tol, acceptable_iter: IPOPT stopping
        tests (an "acceptable" point held for acceptable_iter iterations ends the stage).
    repairs: re-solves allowed when the fine-grid check finds a violation.
    start_fraction: random starts use this fraction (uniform in the interval) of each joint's
        kinematic room.
    ipopt: extra IPOPT options as (name, value) pairs, e.g. (("linear_solver", "ma27"),).
    compiled: evaluate the per-sample functions of the NLP (regressor, envelope rows, torques,
        their derivatives) as compiled C, cached on disk (kernels.py, criterion_callback.py);
        False: all in CasADi's VM, one graph (the same numbers to rounding, several times slower).
    """

    criterion: str | Objective = "cond"
    grid_rate: float = 20.0
    constraint_rate: float | None = None
    torque_rate: float | None = None
    verify_rate: float = 1000.0
    cond_rate: float = 250.0
    max_frequency: float = 2.0
    margins: Margins = field(default_factory=Margins)
    sign_eps: float = 0.1
    p_schedule: tuple[int, ...] = (4, 16)
    max_iter: int = 300
    tol: float = 1e-6
    acceptable_tol: float = 1e-4
    acceptable_iter: int = 10
    repairs: int = 4
    start_fraction: tuple[float, float] = (0.4, 0.9)
    ipopt: tuple[tuple[str, Any], ...] = ()
    compiled: bool = True

    def __post_init__(self) -> None:
        if isinstance(self.criterion, str):
            object.__setattr__(self, "criterion", Objective(self.criterion, rate=self.cond_rate))
        for name in ("grid_rate", "verify_rate", "cond_rate", "max_frequency", "sign_eps", "tol"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0.0:
                raise ValueError(f"options: {name} must be > 0, got {value!r}")
        if self.verify_rate < self.grid_rate:
            raise ValueError(f"options: verify_rate {self.verify_rate} Hz must not be below "
                             f"grid_rate {self.grid_rate} Hz")
        for name in ("constraint_rate", "torque_rate"):
            value = getattr(self, name)
            if value is not None and not 0.0 < value <= self.verify_rate:
                raise ValueError(f"options: {name} must be in (0, verify_rate], got {value}")
        if not self.p_schedule or any(p < 0 or (p & (p - 1)) != 0 for p in self.p_schedule):
            raise ValueError(f"options: p_schedule must hold powers of two or 0, got {self.p_schedule}")
        lo, hi = self.start_fraction
        if not 0.0 < lo <= hi <= 1.0:
            raise ValueError(f"options: start_fraction must satisfy 0 < lo <= hi <= 1, got {self.start_fraction}")

    def constraint_grid_rate(self, max_frequency_hz: float) -> float:
        """Rate [Hz] of the constraint grid for a form whose highest harmonic is given."""
        if self.constraint_rate is not None:
            return float(self.constraint_rate)
        rate = max(kinematic_grid_rate(max_frequency_hz, self.margins), 4.0 * max_frequency_hz)
        return float(min(rate, self.verify_rate))

    @property
    def stages(self) -> tuple[tuple[str, int], ...]:
        """(criterion, p) of each IPOPT stage."""
        name = self.criterion.name
        if not name.startswith("cond"):
            return ((name, 0),)
        return tuple((name, int(p)) for p in self.p_schedule)


# --------------------------------------------------------------------------- request checks
def check_request(model: ExcitationModel, form: Form, options: OptimiserOptions) -> None:
    """Refuse, with a ValueError, requests no trajectory can satisfy or the grid cannot resolve."""
    f_max = form.max_frequency_hz
    if f_max > options.max_frequency:
        raise ValueError(
            f"excitation request: highest frequency {f_max:.3g} Hz (harmonics / duration) is above "
            f"max_frequency {options.max_frequency:.3g} Hz: lengthen the trajectory or use fewer "
            f"harmonics")
    if f_max >= 0.5 * options.grid_rate:
        raise ValueError(
            f"excitation request: highest frequency {f_max:.3g} Hz is at or above the Nyquist "
            f"frequency {0.5 * options.grid_rate:.3g} Hz of the {options.grid_rate:.3g} Hz "
            f"optimisation grid: raise grid_rate")
    n_grid = int(round(form.duration * options.grid_rate))
    if n_grid * model.n < model.n_base or n_grid < 4:
        raise ValueError(f"excitation request: {n_grid} grid samples x {model.n} joints cannot "
                         f"determine {model.n_base} base parameters: raise grid_rate or duration")
    if model.collision is not None and model.collision.clearance is not None:
        centre = range_centre(model)
        exact = float(model.collision.exact(centre[None, :])[0])
        cover = float(np.min(np.asarray(model.collision.clearance(centre))))  # what IPOPT imposes
        if exact < 0.0 or cover < options.margins.clearance:
            raise ValueError(
                f"excitation request: the link capsules touch (each other or an obstacle box) or "
                f"come within the {options.margins.clearance:g} m clearance margin at the centre of "
                f"the joint ranges (clearance {exact:.4f} m, {cover:.4f} m with the optimiser's ball "
                f"cover): smaller radii, move the box, or no self-collision check")
    if model.heights is not None:
        z = np.asarray(model.heights(range_centre(model))).ravel()
        if np.any(z < model.z_min):
            raise ValueError(f"excitation request: at the centre of the joint ranges a point is at "
                             f"z = {z.min():.3f} m, below the floor z_min = {model.z_min} m")
