"""Limits an excitation trajectory must hold at every sample, symbolic (for IPOPT) and numeric.

Joint positions, velocities and accelerations are linear in the coefficients, so on the
optimisation grid they are linear constraints (:func:`kinematic_constraints`).
Motor torques come from the inverse dynamic model with the nominal parameters minus the spring
torque (:func:`torque_rows`), Cartesian heights, speeds and clearances from the forward
geometric model (envelope_rows.py): nonlinear. On the optimisation grid every limit is tightened
by a margin (the trajectory also moves between grid points, see :func:`kinematic_grid_rate`);
:func:`check_limits` then verifies the true
limits, without margin, on an independent fine grid (1 kHz by default), which is what decides
feasibility; :func:`violation_times` tells the optimiser where to add constraints when it fails.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from .kernels import evaluate_samples, symbols_like
from .model import ExcitationModel

_KINDS = ("position", "velocity", "acceleration", "torque")
TORQUE_UNCHECKED = ("not checked: no nominal parameters were given, so the motor torques of this "
                    "motion are unknown (give them: rx90 excite --params FILE)")


@dataclass(frozen=True)
class Margins:
    """How much of each limit the optimiser keeps in reserve on its grid.

    position, velocity, acceleration, torque: fractions of the limit (of the half range for
    positions, about its centre); height: metres above the floor; clearance: metres between link
    capsules and from obstacle boxes (the links move centimetres between grid points).
    """

    position: float = 0.02
    velocity: float = 0.02
    acceleration: float = 0.02
    torque: float = 0.05
    height: float = 0.01
    clearance: float = 0.03

    def __post_init__(self) -> None:
        for name in ("position", "velocity", "acceleration", "torque"):
            value = getattr(self, name)
            if not 0.0 <= value < 1.0:
                raise ValueError(f"margins: {name} must be a fraction in [0, 1), got {value}")
        for name in ("height", "clearance"):
            if getattr(self, name) < 0.0:
                raise ValueError(f"margins: {name} must be >= 0 m, got {getattr(self, name)}")


@dataclass(frozen=True, eq=False)
class LimitReport:
    """Limit usage per joint on a grid: max |x| / x_max (positions: excursion / half range about
    the centre of the range), 1.0 = at the limit; nan where the limit is unknown (inf)."""

    rate: float
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    torque: np.ndarray
    min_height: float | None = None
    z_min: float | None = None
    violations: tuple[str, ...] = field(default=())
    torque_note: str = ""  # why torques were not checked (no nominal parameters), "" when they were
    min_clearance: float | None = None  # [m] smallest capsule clearance (collision model), or None
    max_speed: float | None = None  # [m/s] largest Cartesian point speed (envelope), or None
    speed_max: float | None = None  # [m/s] its limit

    @property
    def feasible(self) -> bool:
        """True when every limit holds at every sample of the grid."""
        return not self.violations

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (NaN written as None)."""
        def clean(a: np.ndarray) -> list[float | None]:
            return [None if not np.isfinite(v) else round(float(v), 6) for v in a]

        out: dict[str, Any] = {"checked_at_hz": self.rate, "feasible": self.feasible}
        out.update({kind: clean(getattr(self, kind)) for kind in _KINDS})
        if self.torque_note:
            out["torque"] = self.torque_note
        if self.min_clearance is not None:  # inf when nothing is checked (e.g. --no-self-collision)
            out["min_clearance_m"] = clean(np.array([self.min_clearance]))[0]
        if self.max_speed is not None:
            out["max_point_speed_m_s"] = round(float(self.max_speed), 6)
            out["point_speed_limit_m_s"] = self.speed_max
        if self.min_height is not None:
            out["min_height_m"] = round(float(self.min_height), 6)
            out["z_min_m"] = self.z_min
        out["violations"] = list(self.violations)
        return out


# --------------------------------------------------------------------------- bounds with margins
def position_bounds(model: ExcitationModel, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """[lower, upper] position bounds (n,) [rad], the range shrunk by ``margin`` about its centre."""
    lim = model.limits
    with np.errstate(invalid="ignore"):  # a joint without position limits: inf - inf
        centre, half = 0.5 * (lim.q_max + lim.q_min), 0.5 * (lim.q_max - lim.q_min)
        lo = np.where(np.isfinite(half), centre - (1.0 - margin) * half, -np.inf)
        hi = np.where(np.isfinite(half), centre + (1.0 - margin) * half, np.inf)
    return lo, hi


def range_centre(model: ExcitationModel) -> np.ndarray:
    """The model's centre pose when it has one (inside the safety envelope, envelope.py), else the
    centre of each joint range [rad] (0 where the range is unbounded)."""
    if model.centre is not None:
        return np.array(model.centre)
    lim = model.limits
    centre = 0.5 * (lim.q_max + lim.q_min)
    return np.where(np.isfinite(centre), centre, 0.0)


def kinematic_grid_rate(max_frequency_hz: float, margins: Margins) -> float:
    """Grid rate [Hz] at which the margins cover what a band-limited motion can do between samples.

    For a trigonometric polynomial x of highest angular frequency W, Bernstein's inequality gives
    |x''| <= W^2 max|x|; at a maximum x' = 0, so the nearest sample (at most h/2 away) is below the
    maximum by at most W^2 h^2 / 8 max|x|. Velocities and accelerations therefore hold everywhere
    when W^2 h^2 / 8 <= margin; positions (an offset plus such a polynomial, whose amplitude is at
    most the full range, twice the half range the margin refers to) when W^2 h^2 / 4 <= margin.
    Exact for the Fourier form; for via points and for torques the fine-grid check decides.
    Returns 0 when a margin is 0 (no rate suffices: the caller uses its own grid).
    """
    w = 2.0 * np.pi * max_frequency_hz
    h = min(np.sqrt(4.0 * margins.position), np.sqrt(8.0 * margins.velocity),
            np.sqrt(8.0 * margins.acceleration)) / w
    return 1.0 / h if h > 0.0 else 0.0


# --------------------------------------------------------------------------- symbolic (IPOPT)
class _Rows:
    """Accumulates constraint rows (g, lbg, ubg); rows with an infinite limit are left out
    rather than given infinite bounds."""

    def __init__(self) -> None:
        self.parts: list[ca.MX] = []
        self.lows: list[np.ndarray] = []
        self.highs: list[np.ndarray] = []

    def add(self, expr: ca.MX, lo: np.ndarray, hi: np.ndarray) -> None:
        keep = np.flatnonzero(np.isfinite(lo) | np.isfinite(hi))
        if keep.size == 0 or expr.shape[1] == 0:
            return
        self.parts.append(ca.vec(expr[keep.tolist(), :]))  # column-major: joint fastest
        self.lows.append(np.tile(lo[keep], expr.shape[1]))
        self.highs.append(np.tile(hi[keep], expr.shape[1]))

    def result(self) -> tuple[ca.MX, np.ndarray, np.ndarray]:
        if not self.parts:
            return ca.MX(0, 1), np.zeros(0), np.zeros(0)
        return ca.vertcat(*self.parts), np.concatenate(self.lows), np.concatenate(self.highs)


def kinematic_constraints(model: ExcitationModel, q: ca.MX, qd: ca.MX, qdd: ca.MX,
                          margins: Margins) -> tuple[ca.MX, np.ndarray, np.ndarray]:
    """(g, lbg, ubg) on MX samples (n x N): position, velocity and acceleration limits with
    margins (linear in the coefficients). The envelope's nonlinear rows (heights, clearances,
    Cartesian speeds) are envelope_rows.py's; the 1 kHz check verifies every point exactly."""
    lim = model.limits
    rows = _Rows()
    lo, hi = position_bounds(model, margins.position)
    rows.add(q, lo, hi)
    for expr, bound, m in ((qd, lim.qd_max, margins.velocity), (qdd, lim.qdd_max, margins.acceleration)):
        rows.add(expr, -(1.0 - m) * bound, (1.0 - m) * bound)
    return rows.result()


def torque_rows(model: ExcitationModel, margins: Margins) -> tuple[ca.Function, np.ndarray, np.ndarray] | None:
    """(f, lo, hi): the motor torque limits with margin at one sample, f(q, qd, qdd) -> the
    torques (inverse dynamics with the nominal parameters, minus the spring) of the joints with a
    finite limit, and their bounds; imposed lazily, through envelope_rows.through_samples. None
    when the model has no torques or no finite torque limit."""
    lim = model.limits
    keep = np.flatnonzero(np.isfinite(lim.tau_max))
    if model.torque is None or keep.size == 0:
        return None
    sym = symbols_like(model.torque)
    tau = model.torque(*sym)[keep.tolist()]
    bound = (1.0 - margins.torque) * lim.tau_max[keep]
    return ca.Function("motor_torque_rows", sym, [tau], ["q", "qd", "qdd"], ["tau"]), -bound, bound


# --------------------------------------------------------------------------- numeric (verification)
def evaluate_torque(model: ExcitationModel, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """Motor torques (N, n) [N m] on samples (N, n); zeros when the model has none."""
    if model.torque is None:
        return np.zeros_like(q)
    return evaluate_samples(model.torque, q, qd, qdd)[:, :, 0]


def evaluate_speeds(model: ExcitationModel, q: np.ndarray, qd: np.ndarray) -> np.ndarray | None:
    """Cartesian speeds (N, k) [m/s] of the envelope's points on samples (N, n), or None."""
    if model.speeds is None:
        return None
    return np.sqrt(np.maximum(evaluate_samples(model.speeds, q, qd)[:, :, 0], 0.0))


def evaluate_heights(model: ExcitationModel, q: np.ndarray) -> np.ndarray | None:
    """Heights (N, k) [m] of the points that must stay above the floor, or None."""
    if model.heights is None:
        return None
    return evaluate_samples(model.heights, q)[:, :, 0]


def check_limits(model: ExcitationModel, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                 rate: float, rtol: float = 1e-9) -> LimitReport:
    """Verify every limit, without margin, on samples (N, n) taken at ``rate`` [Hz]."""
    lim = model.limits
    centre = 0.5 * (lim.q_max + lim.q_min)
    with np.errstate(invalid="ignore", divide="ignore"):
        up = (q - centre) / (lim.q_max - centre)
        down = (centre - q) / (centre - lim.q_min)
        usage = {
            "position": _usage(np.maximum(up, down), lim.q_max - lim.q_min),
            "velocity": _usage(np.abs(qd) / lim.qd_max, lim.qd_max),
            "acceleration": _usage(np.abs(qdd) / lim.qdd_max, lim.qdd_max),
            "torque": (_usage(np.abs(evaluate_torque(model, q, qd, qdd)) / lim.tau_max, lim.tau_max)
                       if model.torque is not None else np.full(q.shape[1], np.nan)),
        }
    violations = []
    for kind, values in usage.items():
        for j in np.flatnonzero(values > 1.0 + rtol):
            violations.append(f"{kind} limit of joint {j + 1} exceeded: {values[j]:.4f} x limit")
    min_height = None
    if model.heights is not None and model.z_min is not None:
        z = evaluate_heights(model, q)
        min_height = float(np.min(z))
        if min_height < model.z_min - 1e-12:
            k = int(np.argmin(np.min(z, axis=0)))
            name = model.point_names[0][k] if len(model.point_names[0]) > k else f"point {k + 1}"
            violations.append(f"{name} at z = {min_height:.4f} m below the lowest allowed "
                              f"z_min = {model.z_min} m")
    max_speed = None
    if model.speeds is not None:
        v = evaluate_speeds(model, q, qd)
        max_speed = float(np.max(v))
        if max_speed > model.speed_max * (1.0 + rtol):
            k = int(np.argmax(np.max(v, axis=0)))
            name = model.point_names[1][k] if len(model.point_names[1]) > k else f"point {k + 1}"
            violations.append(f"Cartesian speed of {name} {max_speed:.4f} m/s above the limit "
                              f"{model.speed_max:g} m/s")
    min_clearance = None
    if model.collision is not None:
        min_clearance = float(np.min(model.collision.exact(q)))
        if min_clearance < -1e-12:
            violations.append(f"collision: link capsules {-min_clearance:.4f} m into each other or "
                              f"into an obstacle box")
    note = "" if model.torque is not None else TORQUE_UNCHECKED
    return LimitReport(rate, usage["position"], usage["velocity"], usage["acceleration"],
                       usage["torque"], min_height, model.z_min, tuple(violations), note, min_clearance,
                       max_speed, model.speed_max)


def _usage(ratio: np.ndarray, limit: np.ndarray) -> np.ndarray:
    """max over samples of ratio per joint, nan where the limit is unknown."""
    out = np.max(ratio, axis=0) if ratio.shape[0] else np.zeros(ratio.shape[1])
    return np.where(np.isfinite(limit), out, np.nan)


def violation_times(model: ExcitationModel, t: np.ndarray, q: np.ndarray, qd: np.ndarray,
                    qdd: np.ndarray, limit: int = 32) -> np.ndarray:
    """Times [s] of the worst sample of each run of samples that exceed a limit (no margin);
    at most ``limit`` of them, worst first. Used to add constraint points where a solve failed."""
    lim = model.limits
    centre = 0.5 * (lim.q_max + lim.q_min)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratios = [np.maximum((q - centre) / (lim.q_max - centre), (centre - q) / (centre - lim.q_min)),
                  np.abs(qd) / lim.qd_max, np.abs(qdd) / lim.qdd_max]
        if model.torque is not None:
            ratios.append(np.abs(evaluate_torque(model, q, qd, qdd)) / lim.tau_max)
    excess = np.max(np.nan_to_num(np.hstack(ratios), nan=0.0), axis=1) - 1.0
    if model.heights is not None and model.z_min is not None:
        excess = np.maximum(excess, model.z_min - np.min(evaluate_heights(model, q), axis=1))
    if model.collision is not None:
        excess = np.maximum(excess, -model.collision.exact(q))
    if model.speeds is not None:
        excess = np.maximum(excess, np.max(evaluate_speeds(model, q, qd), axis=1) / model.speed_max - 1.0)
    bad = excess > 0.0
    if not np.any(bad):
        return np.zeros(0)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], bad.astype(int), [0]])))
    peaks = [start + int(np.argmax(excess[start:stop])) for start, stop in zip(edges[::2], edges[1::2])]
    peaks.sort(key=lambda i: -excess[i])
    return np.sort(t[peaks[:limit]])
