"""Separable least squares for friction nonlinear in a velocity scale (variable projection).

The smooth Coulomb FS·tanh(q̇/vs) and Stribeck (FS + (FST − FS)·exp(−(q̇/vs)²))·sign(q̇)
(identify.friction.forms) are linear in every parameter but the joint's velocity scale vs
[rad/s]. For given scales the linear parameters β are the least-squares solution (eq. 10); the
scales minimise the projected cost F(s) = ½‖D(Y − W(s)·β̂(s))‖² (Golub & Pereyra): the
gradient needs only ∂W/∂s at β̂ (β̂ optimal), CasADi's derivative of the form
(identify.friction.forms.friction_columns; tanh's evaluated in NumPy). D holds the paper's per-joint weights (eq. 11) of a first fit.

Procedure (:func:`velocity_scales`): one observation matrix whose Coulomb columns hold the
filtered, decimated driver speed v of every row (``FrictionBase`` form "probe"); the scales searched
on grids of scales tabulated as extra columns of per-joint triangular factors
(:mod:`identify.friction.scale_search`: the same code reads a log block by block), bounded to
:data:`SCALE_BOUNDS` (the lower bound raised to half the 2nd percentile of the joint's speeds: below
it a column fits a handful of rows). The columns are evaluated on the decimated speed (f(Dv) for the
parallel-filtered D·f(v): equal where the speed changes slowly over the decimation filter, i.e. for
vs above the speed change in a few decimated periods); the fit itself then uses the exact
parallel-filtered columns.

The presliding travel δ per joint is separable the same way (:mod:`identify.friction.travels`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

import rx90sym
from identify.friction.scale_search import ScaleSearch, find_scales
from identify.friction.scale_table import LOW_SPEED_SHARE, SCALE_BOUNDS
from identify.friction.columns import FrictionBase, friction_probe
from identify.observation.matrix import Observation, observation_matrix

__all__ = ["LOW_SPEED_SHARE", "SCALE_BOUNDS", "VelocityScales", "smooth_probe", "scales_from_observation", "smooth_joints",
           "velocity_scales"]


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
