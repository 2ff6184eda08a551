"""The friction columns of W beyond Coulomb + viscous: the smooth forms.

:class:`FrictionBase` wraps the base parameters (any object with ``names`` and ``regressor_batch``,
like :class:`identify.observation.spring_fit.BaseWithSpring`): with form "tanh" / "stribeck"
(:mod:`identify.friction.forms`) each own Coulomb column sign(v) becomes tanh(v/vs), or sign(v)·(1 − e)
with a column FSTj = sign(v)·e, e = exp(−(v/vs)²), for the joint's velocity scale vs [rad/s]; with form
"probe" (internal) the Coulomb columns hold the driver speed itself, so that one pass of rows gives the
scale search the (filtered, decimated) speed of every row. :func:`friction_base` makes the columns a fit
uses: the form's, and the presliding magnitudes of the rest policy "presliding"
(:class:`identify.observation.rest.PreslidingBase`) around them.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, Sequence

import numpy as np

import rx90sym

from identify.friction.forms import DEFAULT_FRICTION, FRICTION_FORMS, friction_columns
from identify.observation.processing import uniform
from identify.observation.rest import STRIBECK_PREFIX, CoulombTerm, PreslidingBase, coulomb_terms, own_terms

__all__ = ["FrictionBase", "form_columns", "friction_base", "friction_probe", "inner_columns"]


@dataclass(frozen=True, eq=False)
class FrictionBase:
    """Base parameters with the columns of a friction form (module docstring); usable as ``base`` everywhere.

    base: the wrapped columns; terms: (row, column, driver) of each Coulomb entry of ``base``
    driven by its own joint (:func:`identify.observation.rest.own_terms`); form: "coulomb" | "tanh" |
    "stribeck" | "probe", or one of the first three per joint (a tuple indexed by joint, 0-based:
    a Coulomb joint keeps its sign column, no scale);
    scales: velocity scale vs [rad/s] per joint (0-based index) for the smooth forms (nan or
    anything on a Coulomb joint).
    """

    base: Any
    terms: tuple[tuple[int, int, tuple[float, ...]], ...]
    form: str | tuple[str, ...] = DEFAULT_FRICTION
    scales: tuple[float, ...] | None = None

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
        return tuple(self.base.names) + tuple(f"{STRIBECK_PREFIX}{r + 1}" for r in self.rows
                                              if self.form_of(r) == "stribeck")

    @property
    def nb(self) -> int:
        return len(self.names)

    def regressor_batch(self, Q: Any, QD: Any, QDD: Any, out: np.ndarray | None = None) -> np.ndarray:
        """[Phi_b with the Coulomb columns of the form, FST columns]: (N, n, nb)."""
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
        if out is not None:
            out[...] = full
            return out
        return full


def inner_columns(base: Any) -> Any:
    """``base`` without its friction columns: inside a :class:`PreslidingBase` and a :class:`FrictionBase`."""
    base = base.base if isinstance(base, PreslidingBase) else base
    return base.base if isinstance(base, FrictionBase) else base


def form_columns(base: Any) -> FrictionBase | None:
    """The :class:`FrictionBase` of ``base`` (inside its presliding columns), None: Coulomb."""
    base = base.base if isinstance(base, PreslidingBase) else base
    return base if isinstance(base, FrictionBase) else None


def friction_base(base: Any, terms: Sequence[Any], form: str | Sequence[str] | None = None,
                  scales: Sequence[float] | None = None, presliding: bool = False,
                  travels: Sequence[float] | None = None) -> Any:
    """``base`` with the friction columns of ``form`` (one, or one per joint; None: keep the form of
    ``base``, else Coulomb) and, with ``presliding``, the FPj columns around them (travels [rad] per
    joint; None: those of ``base``, else :data:`identify.observation.rest.PRESLIDING_TRAVEL`); ``base``
    itself when nothing is added. terms: the Coulomb entries of ``base`` (CoulombTerm, or (row, column,
    driver))."""
    form = uniform(form if form is None or isinstance(form, str) else tuple(form))   # one spelling inside
    if isinstance(base, PreslidingBase):
        presliding, travels = True, base.travels if travels is None else travels
        base = base.base
    if isinstance(base, FrictionBase):
        form = base.form if form is None else form
        scales = base.scales if scales is None and form == base.form else scales
        base = base.base
    form = form or DEFAULT_FRICTION
    rows = tuple((t.row, t.column, tuple(t.driver)) if hasattr(t, "row") else tuple(t) for t in own_terms(terms))
    if form != DEFAULT_FRICTION:
        base = FrictionBase(base, rows, form, tuple(float(s) for s in scales) if scales is not None else None)
    if presliding:
        base = PreslidingBase(base, rows, tuple(float(d) for d in travels) if travels is not None else None)
    return base


def friction_probe(robot: rx90sym.Robot, base: Any) -> tuple[Any, "FrictionBase", tuple[CoulombTerm, ...], tuple[int, ...]]:
    """What a search over friction forms reads: (``base`` without its friction form, the probe
    columns (form "probe": each own-joint Coulomb column holds the filtered, decimated driver
    speed), those Coulomb terms, the joints (1-based) whose Coulomb is asymmetric (FS+, FS-), where
    a smooth form has no single magnitude)."""
    inner = inner_columns(base)
    terms = own_terms(coulomb_terms(robot, inner.names))
    asymmetric = tuple(sorted({t.row + 1 for t in terms
                               if rx90sym.parameters.split_name(t.name)[0] in ("FSP", "FSN")}))
    return inner, friction_base(inner, terms, "probe"), terms, asymmetric
