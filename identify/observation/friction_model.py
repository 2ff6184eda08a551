"""The friction columns of W beyond Coulomb + viscous: smooth forms and the presliding magnitude.

:class:`FrictionBase` wraps the base parameters (any object with ``names`` and
``regressor_batch``, like :class:`identify.observation.spring_fit.BaseWithSpring`):

- form "tanh" / "stribeck" (:data:`identify.observation.friction.FRICTION_FORMS`): each Coulomb
  column sign(v) becomes tanh(v/vs), or sign(v)·(1 − e) with a column FSTj = sign(v)·e,
  e = exp(−(v/vs)²), for the joint's velocity scale vs [rad/s];
- ``presliding``: one column FPj per joint with a Coulomb term holding the presliding state z of
  the joint's positions (identify.observation.friction, travel ``travels[j]``), kept on the rest
  rows only (identify.observation.matrix, ``rest="presliding"``), so the rest torque is z·FPj with
  its own magnitude and the moving rows keep the Coulomb model; with ``candidates``, one column
  FPj_k per candidate travel k instead (the travel search, identify.friction.scales);
- form "probe" (internal): the Coulomb columns hold the driver speed itself, so that one
  observation matrix gives separable least squares the (filtered, decimated) speed of every row.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.observation.friction import (DEFAULT_FRICTION, FRICTION_FORMS, PRESLIDING_TRAVEL, friction_columns,
                                          presliding_state)
from identify.observation.processing import uniform

__all__ = ["CoulombTerm", "FrictionBase", "PRESLIDING_PREFIX", "STRIBECK_PREFIX", "coulomb_terms", "friction_base",
           "friction_probe", "own_terms", "presliding_base", "empty_presliding", "without_empty_presliding"]

#: Column names: FPj the presliding magnitude [N·m] of joint j, FSTj its Stribeck (breakaway) level [N·m].
PRESLIDING_PREFIX = "FP"
STRIBECK_PREFIX = "FST"


@dataclass(frozen=True, eq=False)
class FrictionBase:
    """Base parameters with friction columns (module docstring); usable as ``base`` everywhere.

    base: the wrapped columns; terms: (row, column, driver) of each Coulomb entry of ``base``
    driven by its own joint (:func:`coulomb_terms`, :func:`own_terms`); form: "coulomb" | "tanh" |
    "stribeck" | "probe", or one of the first three per joint (a tuple indexed by joint, 0-based:
    a Coulomb joint keeps its sign column, no scale);
    scales: velocity scale vs [rad/s] per joint (0-based index) for the smooth forms (nan or
    anything on a Coulomb joint);
    presliding: add the FPj columns; travels: presliding travel δ [rad] per joint (None:
    PRESLIDING_TRAVEL); candidates: travels [rad] tried for every joint, one column FPj_k each
    (the search; None: one column FPj at ``travels``).
    """

    base: Any
    terms: tuple[tuple[int, int, tuple[float, ...]], ...]
    form: str | tuple[str, ...] = DEFAULT_FRICTION
    scales: tuple[float, ...] | None = None
    presliding: bool = False
    travels: tuple[float, ...] | None = None
    candidates: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        per_joint = isinstance(self.form, tuple)
        if (self.form not in FRICTION_FORMS + ("probe",) if not per_joint
                else not all(f in FRICTION_FORMS for f in self.form)):
            raise ValueError(f"friction form must be one of {FRICTION_FORMS} or one of them per joint, got {self.form!r}")
        if per_joint and any(row >= len(self.form) for row, _, _ in self.terms):
            raise ValueError(f"friction form: {len(self.form)} forms given, the Coulomb terms reach joint "
                             f"{max(row for row, _, _ in self.terms) + 1}")
        rows = sorted({row for row, _, _ in self.terms if self.form_of(row) in ("tanh", "stribeck")})
        if rows and (self.scales is None or any(not (row < len(self.scales) and self.scales[row] > 0) for row in rows)):
            raise ValueError(f"friction form {self.form!r} needs a positive velocity scale [rad/s] for "
                             f"joints {', '.join(str(r + 1) for r in rows)}, got {self.scales!r}")

    def form_of(self, row: int) -> str:
        """The friction form of joint ``row`` (0-based)."""
        return self.form[row] if isinstance(self.form, tuple) else self.form

    @cached_property
    def rows(self) -> tuple[int, ...]:
        """Joints (0-based) with a Coulomb term, in order."""
        return tuple(sorted({row for row, _, _ in self.terms}))

    @cached_property
    def names(self) -> tuple[str, ...]:
        extra = [f"{STRIBECK_PREFIX}{r + 1}" for r in self.rows if self.form_of(r) == "stribeck"]
        if self.presliding:
            extra += [name for r in self.rows for name, _ in self.presliding_columns(r)]
        return tuple(self.base.names) + tuple(extra)

    def travel(self, row: int) -> float:
        """Presliding travel δ [rad] of joint ``row`` (0-based)."""
        return float(self.travels[row]) if self.travels is not None else PRESLIDING_TRAVEL

    def presliding_columns(self, row: int) -> list[tuple[str, float]]:
        """(name, travel δ [rad]) of joint ``row``'s presliding column(s)."""
        if self.candidates is None:
            return [(f"{PRESLIDING_PREFIX}{row + 1}", self.travel(row))]
        return [(f"{PRESLIDING_PREFIX}{row + 1}_{k}", float(d)) for k, d in enumerate(self.candidates)]

    @property
    def nb(self) -> int:
        return len(self.names)

    def regressor_batch(self, Q: Any, QD: Any, QDD: Any, out: np.ndarray | None = None) -> np.ndarray:
        """[Phi_b with the Coulomb columns of the form, FST columns, FP columns (0)]: (N, n, nb)."""
        Phi_b = self.base.regressor_batch(Q, QD, QDD)
        full = np.zeros(Phi_b.shape[:2] + (self.nb,))
        c = Phi_b.shape[2]
        full[:, :, :c] = Phi_b
        QD = np.asarray(QD, dtype=float)
        for row, column, driver in self.terms:
            v = QD @ np.asarray(driver)
            form = self.form_of(row)
            if form == "probe":
                full[:, row, column] = v
            elif form in ("tanh", "stribeck"):
                cols, _ = friction_columns(form, v, self.scales[row])
                full[:, row, column] = cols[:, 0]
                if form == "stribeck":
                    full[:, row, self.names.index(f"{STRIBECK_PREFIX}{row + 1}")] = cols[:, 1]
            if self.presliding:
                # z on every sample of the position history; the rest mask keeps it at rest only.
                position = np.asarray(Q, dtype=float) @ np.asarray(driver)
                for name, travel in self.presliding_columns(row):
                    full[:, row, self.names.index(name)] = presliding_state(position, travel)
        if out is not None:
            out[...] = full
            return out
        return full


def own_terms(terms: Sequence[Any]) -> tuple[Any, ...]:
    """The Coulomb entries driven by their own joint's speed (FSj in row j): the ones a smooth form,
    a Stribeck level or a presliding magnitude applies to; a motor's (the coupling's FSM) keeps sign(q̇)."""
    def driver(t: Any) -> tuple[int, tuple[float, ...]]:
        return (t.row, tuple(t.driver)) if hasattr(t, "row") else (t[0], tuple(t[2]))

    return tuple(t for t in terms
                 if driver(t)[1][driver(t)[0]] == 1 and sum(abs(x) for x in driver(t)[1]) == 1)


def friction_base(base: Any, terms: Sequence[Any], form: str | Sequence[str] | None = None,
                  scales: Sequence[float] | None = None, presliding: bool = False,
                  travels: Sequence[float] | None = None) -> Any:
    """``base`` with the friction columns of ``form`` (one, or one per joint; None: keep the form of
    a FrictionBase, else Coulomb) and, with ``presliding``, the FPj columns (travels [rad] per
    joint; None: those of a FrictionBase, else PRESLIDING_TRAVEL); ``base`` itself when nothing is
    added. terms: the Coulomb entries of ``base`` (CoulombTerm, or (row, column, driver))."""
    form = uniform(form if form is None or isinstance(form, str) else tuple(form))   # one spelling inside
    if isinstance(base, FrictionBase):
        form = base.form if form is None else form
        scales = base.scales if scales is None and form == base.form else scales
        presliding = presliding or base.presliding
        travels = base.travels if travels is None else travels
        base = base.base
    form = form or DEFAULT_FRICTION
    if form == DEFAULT_FRICTION and not presliding:
        return base
    rows = tuple((t.row, t.column, tuple(t.driver)) if hasattr(t, "row") else tuple(t) for t in own_terms(terms))
    return FrictionBase(base, rows, form, tuple(float(s) for s in scales) if scales is not None else None, presliding,
                        tuple(float(d) for d in travels) if travels is not None else None)


@dataclass(frozen=True)
class CoulombTerm:
    """One Coulomb entry of the regressor: parameter ``name`` (column ``column``) in joint ``row``'s
    equation, whose sign is that of the speed ``driver @ qd`` (a joint, or a motor for FSM terms)."""

    name: str
    column: int
    row: int
    driver: tuple[float, ...]


def coulomb_terms(robot: rx90sym.Robot, names: Sequence[str]) -> tuple[CoulombTerm, ...]:
    """The Coulomb entries among the parameter columns ``names`` (standard or base names).

    FSj (and FSPj, FSNj of an asymmetric joint) acts on row j with the sign of q̇j; the coupling's FSMb acts on rows a and b with the sign
    of the motor speed q̇a + q̇b (``coulomb_sign = "motor"``) or of q̇b in row a and q̇a in row b
    (``"paper"``, eqs. 17-18).
    """
    n = robot.n
    unit = np.eye(n)
    out = []
    for c, name in enumerate(names):
        try:
            kind, j = rx90sym.parameters.split_name(name)
        except ValueError:
            continue
        if kind in ("FS", "FSP", "FSN") and 1 <= j <= n:
            out.append(CoulombTerm(name, c, j - 1, tuple(unit[j - 1])))
        elif kind == "FSM" and robot.coupling is not None and j == robot.coupling.joints[1] + 1:
            a, b = robot.coupling.joints
            if robot.coupling.coulomb_sign == "motor":
                drivers = {a: unit[a] + unit[b], b: unit[a] + unit[b]}
            else:
                drivers = {a: unit[b], b: unit[a]}
            out += [CoulombTerm(name, c, row, tuple(w)) for row, w in drivers.items()]
    return tuple(out)


def friction_probe(robot: rx90sym.Robot, base: Any) -> tuple[Any, "FrictionBase", tuple[CoulombTerm, ...], tuple[int, ...]]:
    """What a search over friction forms reads: (``base`` without its friction form, the probe
    columns (form "probe": each own-joint Coulomb column holds the filtered, decimated driver
    speed), those Coulomb terms, the joints (1-based) whose Coulomb is asymmetric (FS+, FS-), where
    a smooth form has no single magnitude)."""
    inner = base.base if isinstance(base, FrictionBase) else base
    terms = own_terms(coulomb_terms(robot, inner.names))
    asymmetric = tuple(sorted({t.row + 1 for t in terms
                               if rx90sym.parameters.split_name(t.name)[0] in ("FSP", "FSN")}))
    return inner, friction_base(inner, terms, "probe"), terms, asymmetric


def presliding_base(robot: rx90sym.Robot, base: Any = None, rest: Any = None) -> Any:
    """The columns a fit with rest policy ``rest`` (one, or one per joint) uses: ``base`` (default:
    the symbolic base parameters of ``robot``) and, where a joint is "presliding", one magnitude FPj
    per joint with a Coulomb term (the other joints' FPj are 0 and left out of W)."""
    from identify.observation.processing import has_policy

    base = base if base is not None else rx90sym.base_parameters(robot)
    if not has_policy(rest, "presliding") or getattr(base, "presliding", False):
        return base
    return friction_base(base, coulomb_terms(robot, base.names), presliding=True)


def empty_presliding(nonzero: Sequence[bool], names: Sequence[str]) -> tuple[list[int] | None, tuple[str, ...]]:
    """(the columns kept, None when all are; a note naming those left out): the presliding columns FPj
    that are 0 on every row (``nonzero`` False: joint j never rests after a motion in these recordings,
    nothing identifies its magnitude, a prediction counts it as 0)."""
    empty = [c for c, name in enumerate(names)
             if name.startswith(PRESLIDING_PREFIX) and name[len(PRESLIDING_PREFIX):].replace("_", "").isdigit()
             and not nonzero[c]]
    if not empty:
        return None, ()
    note = (f"presliding magnitude(s) {', '.join(names[c] for c in empty)} left out: the joint never rests "
            f"after a motion in these recordings")
    return [c for c in range(len(names)) if c not in empty], (note,)


def without_empty_presliding(W: np.ndarray, names: Sequence[str]) -> tuple[np.ndarray, tuple[str, ...], tuple[str, ...]]:
    """W and names without the presliding columns FPj that are 0 on every row (:func:`empty_presliding`),
    and a note naming them."""
    keep, note = empty_presliding(np.any(W != 0.0, axis=0), names)
    if keep is None:
        return W, tuple(names), ()
    return W[:, keep], tuple(names[c] for c in keep), note
