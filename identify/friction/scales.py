"""Separable least squares for friction nonlinear in a velocity scale (variable projection).

The smooth Coulomb FS·tanh(q̇/vs) and Stribeck (FS + (FST − FS)·exp(−(q̇/vs)²))·sign(q̇)
(identify.observation.friction) are linear in every parameter but the joint's velocity scale vs
[rad/s]. For given scales the linear parameters β are the least-squares solution (eq. 10); the
scales minimise the projected cost F(s) = ½‖D(Y − W(s)·β̂(s))‖² (Golub & Pereyra): the
gradient needs only ∂W/∂s at β̂ (β̂ optimal), CasADi's derivative of the form
(identify.observation.friction.friction_columns; tanh's evaluated in NumPy). D holds the paper's per-joint weights (eq. 11) of a first fit.

Procedure (:func:`velocity_scales`): one observation matrix whose Coulomb columns hold the
filtered, decimated driver speed v of every row (``FrictionBase`` form "probe"); the scales searched
on grids of scales tabulated as extra columns of per-joint triangular factors
(:mod:`identify.friction.scale_search`: the same code reads a log block by block), bounded to
:data:`SCALE_BOUNDS` (the lower bound raised to half the 2nd percentile of the joint's speeds: below
it a column fits a handful of rows). The columns are evaluated on the decimated speed (f(Dv) for the
parallel-filtered D·f(v): equal where the speed changes slowly over the decimation filter, i.e. for
vs above the speed change in a few decimated periods); the fit itself then uses the exact
parallel-filtered columns.

The presliding travel δ per joint (:func:`presliding_travels`) is separable the same way: the
magnitude FPj is linear, δ_j one of :data:`TRAVEL_CANDIDATES`, chosen by coordinate descent on the
projected cost (z is piecewise linear in 1/δ: a grid, not a gradient).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

import rx90sym
from identify.friction.scale_search import ScaleSearch, find_scales
from identify.friction.scale_table import LOW_SPEED_SHARE, SCALE_BOUNDS
from identify.observation.friction_model import PRESLIDING_PREFIX, FrictionBase, friction_probe
from identify.observation.matrix import Observation, observation_matrix

__all__ = ["LOW_SPEED_SHARE", "SCALE_BOUNDS", "TRAVEL_CANDIDATES", "PreslidingTravels", "VelocityScales",
           "presliding_travels", "smooth_probe", "travel_columns", "travels_of", "scales_from_observation", "smooth_joints", "velocity_scales"]


@dataclass(frozen=True)
class VelocityScales:
    """Velocity scale per joint of a smooth friction form: form (one, or one per joint); scales,
    std (n,) [rad/s] (nan for a joint without a Coulomb term or of the Coulomb form); at_bound (n,): the search stopped on a bound of
    :data:`SCALE_BOUNDS` (the data prefer a sign, or a viscous term); cost: the weighted cost F;
    converged: the search reported success (a grid search always ends; kept in the fit file)."""

    form: str | tuple[str, ...]
    scales: tuple[float, ...]
    std: tuple[float, ...]
    at_bound: tuple[bool, ...]
    cost: float
    converged: bool = True

    def to_json(self) -> dict[str, Any]:
        def num(v: float) -> float | None:
            return float(v) if np.isfinite(v) else None

        return {"form": self.form if isinstance(self.form, str) else list(self.form), "velocity_scale": [num(v) for v in self.scales],
                "velocity_scale_std": [num(v) for v in self.std], "at_bound": list(self.at_bound),
                "converged": self.converged}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> "VelocityScales":
        def num(v: float | None) -> float:
            return float("nan") if v is None else float(v)

        form = d["form"] if isinstance(d["form"], str) else tuple(str(f) for f in d["form"])
        return cls(form, tuple(num(v) for v in d["velocity_scale"]),
                   tuple(num(v) for v in d["velocity_scale_std"]), tuple(bool(b) for b in d.get("at_bound", ())),
                   float("nan"), bool(d.get("converged", True)))

    def summary(self) -> str:
        per_joint = not isinstance(self.form, str)
        cells = [f"j{j + 1} {self.form[j] + ' ' if per_joint else ''}{s:.4g} ± {d:.2g}{' (bound)' if b else ''}"
                 for j, (s, d, b) in enumerate(zip(self.scales, self.std, self.at_bound)) if np.isfinite(s)]
        coulomb = [f"j{j + 1}" for j, f in enumerate(self.form) if f == "coulomb"] if per_joint else []
        head = "friction per joint" if per_joint else f"friction {self.form}"
        return (f"{head}: velocity scale [rad/s] " + ", ".join(cells)
                + (f"; coulomb (no scale): {', '.join(coulomb)}" if coulomb else ""))


def smooth_joints(terms: Sequence[Any], form: str | Sequence[str]) -> tuple[dict[int, int], dict[int, str]]:
    """(joint -> its own Coulomb column, joint -> form of the joints whose scale is searched) of the
    own-joint Coulomb ``terms`` and the ``form`` (one, or one per joint: a Coulomb joint keeps sign(v))."""
    form_of = (lambda j: form) if isinstance(form, str) else (lambda j: form[j])
    own = {t.row: t.column for t in terms}
    forms = {t.row: form_of(t.row) for t in terms if form_of(t.row) in ("tanh", "stribeck")}
    if not forms:
        raise ValueError(f"friction form {form!r}: no joint with a Coulomb term has a velocity scale to search")
    return own, forms


def as_velocity_scales(found: ScaleSearch, form: str | Sequence[str], n: int) -> VelocityScales:
    """The search's result per joint (nan where no scale is searched)."""
    out_s, out_std, out_b = np.full(n, np.nan), np.full(n, np.nan), [False] * n
    for k, j in enumerate(found.joints):
        out_s[j], out_std[j], out_b[j] = found.scales[k], found.std[k], found.at_bound[k]
    return VelocityScales(form if isinstance(form, str) else tuple(form), tuple(out_s), tuple(out_std), tuple(out_b),
                          found.cost)


def observation_feed(obs: Observation, ids: np.ndarray | None = None) -> Any:
    """``feed(table)`` adding the probe observation's rows (``ids``: their time block, None: 0) joint by joint."""
    def feed(table: Any) -> None:
        for j in np.unique(obs.joint):
            rows = obs.joint == j
            table.add(int(j), obs.W[rows], obs.Y[rows], 0 if ids is None else ids[rows])
    return feed


def scales_from_observation(obs: Observation, terms: Sequence[Any], form: str | Sequence[str],
                            n: int) -> VelocityScales:
    """The velocity scales of ``form`` (one smooth form, or one form per joint: only the smooth
    joints' scales are searched, a Coulomb joint keeps sign(v)) from a probe observation (Coulomb
    columns = driver speed): :func:`identify.friction.scale_search.find_scales` on its rows."""
    own, forms = smooth_joints(terms, form)
    found = find_scales(observation_feed(obs), n, obs.W.shape[1], own, forms)[0]
    return as_velocity_scales(found, form, n)


def smooth_probe(robot: rx90sym.Robot, base: Any, form: str | Sequence[str]) -> tuple[FrictionBase, tuple[Any, ...]]:
    """(the probe columns of ``base``, its own Coulomb terms) for the scale search of ``form``; refused
    without a Coulomb term, or with asymmetric Coulomb (FS+, FS-: a smooth form has one magnitude)."""
    _, probe, terms, asymmetric = friction_probe(robot, base)
    if not terms:
        raise ValueError(f"friction form {form!r}: robot {robot.name!r} has no Coulomb parameter in its columns")
    if asymmetric:
        raise ValueError(f"friction form {form!r}: asymmetric Coulomb (FS+, FS-) on joint(s) "
                         f"{', '.join(map(str, asymmetric))} of {robot.name!r}: a smooth form has one magnitude per "
                         f"joint; give friction 'coulomb', or symmetric Coulomb on those joints")
    return probe, terms


def velocity_scales(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any, form: str | Sequence[str],
                    **options: Any) -> VelocityScales:
    """The velocity scale per joint of the smooth friction ``form`` ("tanh" | "stribeck", or one
    form per joint, "coulomb" on the joints without a scale) on
    ``recordings`` with the base columns ``base`` and the observation ``options`` of the fit
    (cutoff, decimate_to, min_velocity, rest, spring, delay: :func:`identify.observation_matrix`)."""
    base = base if base is not None else rx90sym.base_parameters(robot)
    probe, terms = smooth_probe(robot, base, form)
    obs = observation_matrix(robot, recordings, base=probe, **options)
    return scales_from_observation(obs, terms, form, robot.n)


# ---------------------------------------------------------------- presliding travel per joint
#: Presliding travels δ tried for every joint [rad] (docs/real-logs.md: the UR10e prefers the short
#: ones, the twin's Dahl state has 5 mrad).
TRAVEL_CANDIDATES = (0.25e-3, 0.5e-3, 1e-3, 2e-3, 5e-3, 10e-3)


@dataclass(frozen=True)
class PreslidingTravels:
    """The presliding travel δ [rad] per joint (nan: no presliding column, e.g. never at rest),
    chosen among ``candidates`` [rad] by the fit's weighted cost (``cost``: per joint, per
    candidate, the others at their choice)."""

    travels: tuple[float, ...]
    candidates: tuple[float, ...]
    cost: tuple[tuple[float, ...], ...]

    def to_json(self) -> dict[str, Any]:
        return {"presliding_travel": [float(v) if np.isfinite(v) else None for v in self.travels],
                "presliding_candidates": list(self.candidates),
                "presliding_cost": [[float(c) if np.isfinite(c) else None for c in row] for row in self.cost]}


def travel_columns(robot: rx90sym.Robot, base: Any, candidates: Sequence[float] = TRAVEL_CANDIDATES) -> FrictionBase:
    """The columns of the travel search: ``base``'s (its friction form and scales kept) with one column FPj_k
    per joint with a Coulomb term and per candidate travel k [rad]."""
    inner, _, terms, _ = friction_probe(robot, base)
    form = base.form if isinstance(base, FrictionBase) else "coulomb"
    scales = base.scales if isinstance(base, FrictionBase) else None
    return FrictionBase(inner, tuple((t.row, t.column, t.driver) for t in terms), form, scales, True,
                        None, tuple(float(d) for d in candidates))


def travels_of(robot: rx90sym.Robot, R: Sequence[np.ndarray], rows: Sequence[int], names: Sequence[str],
               candidates: Sequence[float] = TRAVEL_CANDIDATES) -> PreslidingTravels:
    """The travels chosen from the per-joint factors of the :func:`travel_columns` rows (whatever read them)."""
    from identify.friction.travels import travels_from_factors

    names = list(names)
    columns = {j: [names.index(f"{PRESLIDING_PREFIX}{j + 1}_{k}") for k in range(len(candidates))]
               for j in range(robot.n)
               if all(f"{PRESLIDING_PREFIX}{j + 1}_{k}" in names for k in range(len(candidates)))}
    choice, table = travels_from_factors(R, rows, names, columns, len(candidates))
    travels = tuple(float(candidates[choice[j]]) if j in choice else np.nan for j in range(robot.n))
    return PreslidingTravels(travels, tuple(float(c) for c in candidates),
                             tuple(tuple(table.get(j, [np.nan] * len(candidates))) for j in range(robot.n)))


def presliding_travels(robot: rx90sym.Robot, recordings: Sequence[Any], base: Any,
                       candidates: Sequence[float] = TRAVEL_CANDIDATES, **options: Any) -> PreslidingTravels:
    """The presliding travel per joint, separable like the velocity scales: FPj is linear, δ_j
    one of ``candidates`` [rad]. One observation matrix holds a column FPj_k per candidate (rest
    policy "presliding" in ``options``, the fit's other observation options); each joint's δ chosen by
    coordinate descent on the weighted cost from its per-joint factors
    (:func:`identify.friction.travels.travels_from_factors`, as block by block)."""
    from identify.estimation.incremental_qr import JointFactors

    obs = observation_matrix(robot, recordings, base=travel_columns(robot, base, candidates), **options)
    factors = JointFactors(robot.n, len(obs.names))
    for j in range(robot.n):
        rows = obs.joint == j
        factors.add(j, np.column_stack([obs.W[rows], obs.Y[rows]]))
    return travels_of(robot, factors.R, factors.rows, obs.names, candidates)
