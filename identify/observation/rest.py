"""A joint at rest: the rows each rest policy gives W, the Coulomb entries it acts on, the presliding state.

Below the rest threshold the sign of a joint's speed is the sign of noise, and its static friction
lies anywhere in [-FS, FS]. The rest policies (:data:`identify.observation.processing.REST_POLICIES`)
say what its Coulomb entries (:func:`coulomb_terms`) hold there: the rows are dropped ("drop"),
kept with Coulomb 0 ("zero-coulomb"), kept as they are ("none"), kept as they are through a short or
travelling pass and with Coulomb 0 over a longer, still rest ("crossing", :func:`crossing_passes`),
or kept with the presliding state of the position history ("presliding").

The presliding state: a real joint stopped after a motion keeps (part of) the friction of that motion
(the UR10e's joint 6 shows -2 N·m for seconds). The play operator

    z_k = clip(z_{k-1} + (q_k - q_{k-1}) / delta, -1, 1),

a Dahl model with a sharp knee, follows the direction of the last motion once the joint has travelled
``delta`` rad in it, holds it at rest, and swings through 0 over ``delta`` rad when the motion
reverses; it is driven by the positions only, never by the torque it is judged against. Its
magnitude FPj is a column of its own (:class:`PreslidingBase`), kept on the rest rows only, so the
moving rows keep their friction form.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any, Sequence

import numpy as np
from scipy.ndimage import maximum_filter1d, minimum_filter1d

import rx90sym

from identify.observation.processing import CROSSING_SECONDS, CROSSING_TRAVEL, has_policy

__all__ = ["PRESLIDING_PREFIX", "PRESLIDING_TRAVEL", "STRIBECK_PREFIX", "CoulombTerm", "PreslidingBase",
           "coulomb_terms", "crossing_passes", "defaulted_travels", "empty_presliding", "own_terms", "presliding_base",
           "presliding_state", "rest_rows", "without_empty_presliding"]

#: Column names: FPj the presliding magnitude [N·m] of joint j; FSTj the Stribeck (breakaway) level [N·m] of
#: a friction form (identify.friction.columns), which rests like FSj.
PRESLIDING_PREFIX = "FP"
STRIBECK_PREFIX = "FST"
#: Travel (rad) over which the presliding state goes from one sign to the other (docs/real-logs.md).
PRESLIDING_TRAVEL = 2e-3


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


def own_terms(terms: Sequence[Any]) -> tuple[Any, ...]:
    """The Coulomb entries driven by their own joint's speed (FSj in row j): the ones a smooth form,
    a Stribeck level or a presliding magnitude applies to; a motor's (the coupling's FSM) keeps sign(q̇)."""
    def driver(t: Any) -> tuple[int, tuple[float, ...]]:
        return (t.row, tuple(t.driver)) if hasattr(t, "row") else (t[0], tuple(t[2]))

    return tuple(t for t in terms
                 if driver(t)[1][driver(t)[0]] == 1 and sum(abs(x) for x in driver(t)[1]) == 1)


def presliding_state(q: np.ndarray, travel: float = PRESLIDING_TRAVEL) -> np.ndarray:
    """z (N,) of the play operator (module docstring) along the positions ``q`` (N,) [rad]; z_0 = 0."""
    if not travel > 0:
        raise ValueError(f"presliding travel must be a positive angle in rad, got {travel!r}")
    steps = np.diff(np.asarray(q, dtype=float)) / travel
    z = np.empty(steps.size + 1)
    z[0] = 0.0
    for k, s in enumerate(steps, start=1):
        z[k] = min(1.0, max(-1.0, z[k - 1] + s))
    return z


def defaulted_travels(travels: Sequence[float | None]) -> list[float]:
    """Travels [rad] with the default where none was chosen (the joint never rests: no FPj column)."""
    return [PRESLIDING_TRAVEL if v is None or not np.isfinite(v) else float(v) for v in travels]


def crossing_passes(mask: np.ndarray, q: np.ndarray, longest: float, travel: float) -> np.ndarray:
    """(S,) True where ``mask`` (below the rest threshold) is a motion, for the "crossing" rest
    policy: inside a run shorter than ``longest`` samples, or where the positions ``q`` [rad] span
    ``travel`` [rad] or more within ``longest`` samples around (a slow motion, or the moments
    after a stop)."""
    size = max(1, int(longest))
    span = maximum_filter1d(q, size, mode="nearest") - minimum_filter1d(q, size, mode="nearest")
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    starts, ends = edges[::2], edges[1::2]
    short = (ends - starts) < longest
    out = np.zeros(mask.size + 1, dtype=np.int32)
    np.add.at(out, starts[short], 1)
    np.add.at(out, ends[short], -1)
    return mask & ((np.cumsum(out[:-1]) > 0) | (span >= travel))


@dataclass(frozen=True, eq=False)
class PreslidingBase:
    """``base`` (any columns with ``names`` and ``regressor_batch``) with the presliding magnitudes: one
    column FPj per joint with an own Coulomb term, holding the presliding state of that joint's positions
    (kept on its rest rows only by :func:`rest_rows`); usable as ``base`` everywhere.

    terms: (row, column, driver) of the own Coulomb entries of ``base`` (:func:`own_terms`); travels:
    presliding travel δ [rad] per joint (None: :data:`PRESLIDING_TRAVEL`); candidates: travels [rad]
    tried for every joint, one column FPj_k each (the travel search, identify.friction.travels; None:
    one column FPj at ``travels``).
    """

    base: Any
    terms: tuple[tuple[int, int, tuple[float, ...]], ...]
    travels: tuple[float, ...] | None = None
    candidates: tuple[float, ...] | None = None

    @cached_property
    def rows(self) -> tuple[int, ...]:
        """Joints (0-based) with a Coulomb term, in order."""
        return tuple(sorted({row for row, _, _ in self.terms}))

    @cached_property
    def names(self) -> tuple[str, ...]:
        return tuple(self.base.names) + tuple(name for r in self.rows for name, _ in self.presliding_columns(r))

    @property
    def nb(self) -> int:
        return len(self.names)

    def travel(self, row: int) -> float:
        """Presliding travel δ [rad] of joint ``row`` (0-based)."""
        return float(self.travels[row]) if self.travels is not None else PRESLIDING_TRAVEL

    def presliding_columns(self, row: int) -> list[tuple[str, float]]:
        """(name, travel δ [rad]) of joint ``row``'s presliding column(s)."""
        if self.candidates is None:
            return [(f"{PRESLIDING_PREFIX}{row + 1}", self.travel(row))]
        return [(f"{PRESLIDING_PREFIX}{row + 1}_{k}", float(d)) for k, d in enumerate(self.candidates)]

    def regressor_batch(self, Q: Any, QD: Any, QDD: Any, out: np.ndarray | None = None) -> np.ndarray:
        """[the columns of ``base``, FP columns]: (N, n, nb); z on every sample of the position history
        (the rest policy keeps it at rest only)."""
        Phi_b = self.base.regressor_batch(Q, QD, QDD)
        full = np.zeros(Phi_b.shape[:2] + (self.nb,))
        full[:, :, :Phi_b.shape[2]] = Phi_b
        Q = np.asarray(Q, dtype=float)
        for row, _, driver in self.terms:
            position = Q @ np.asarray(driver)
            for name, travel in self.presliding_columns(row):
                full[:, row, self.names.index(name)] = presliding_state(position, travel)
        if out is not None:
            out[...] = full
            return out
        return full


def presliding_base(robot: rx90sym.Robot, base: Any = None, rest: Any = None) -> Any:
    """The columns a fit with rest policy ``rest`` (one, or one per joint) uses: ``base`` (default:
    the symbolic base parameters of ``robot``) and, where a joint is "presliding", one magnitude FPj
    per joint with a Coulomb term (the other joints' FPj are 0 and left out of W)."""
    base = base if base is not None else rx90sym.base_parameters(robot)
    if not has_policy(rest, "presliding") or isinstance(base, PreslidingBase):
        return base
    terms = own_terms(coulomb_terms(robot, base.names))
    return PreslidingBase(base, tuple((t.row, t.column, tuple(t.driver)) for t in terms))


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


def rest_rows(robot: rx90sym.Robot, names: Sequence[str] | None, speed: np.ndarray, q: np.ndarray,
              Phi: np.ndarray, min_velocity: float, policies: tuple[str, ...], rate: float,
              context: tuple[np.ndarray, np.ndarray, slice] | None = None) -> np.ndarray:
    """(S, n) rows kept: for a "drop" joint those whose Coulomb drivers all move, every row of the
    others; sets the Coulomb entries of ``Phi`` (in place) where their driver rests, after the
    policy of the row's joint: 0 ("zero-coulomb"), the presliding state of the filtered positions
    ``q`` ("presliding"; the position history, never the torque), 0 over rests longer than
    CROSSING_SECONDS at ``rate`` [Hz] ("crossing"; the runs measured on ``context``: (speed, q) of wider
    samples and the slice of these rows in them), unchanged ("none", "drop")."""
    usable = np.ones(speed.shape, dtype=bool)
    names = tuple(names if names is not None else robot.parameter_names)
    for term in coulomb_terms(robot, names):
        driver_moving = np.abs(speed @ np.asarray(term.driver)) >= min_velocity
        rest = policies[term.row]
        if rest == "drop":
            usable[:, term.row] &= driver_moving
            still = np.zeros_like(driver_moving)  # rows dropped; an FPj column (another joint's policy) is 0
        elif rest == "none":
            still = np.zeros_like(driver_moving)
        elif rest == "crossing":
            c_speed, c_q, inner = context if context is not None else (speed, q, slice(None))
            c_moving = np.abs(c_speed @ np.asarray(term.driver)) >= min_velocity
            passes = crossing_passes(~c_moving, c_q @ np.asarray(term.driver), CROSSING_SECONDS * rate, CROSSING_TRAVEL)
            still = ~driver_moving & ~passes[inner]
        else:
            still = ~driver_moving
        # The moving friction (Coulomb, smooth or Stribeck) says nothing at rest.
        # A form's columns at several scales (FSj_k, the friction choice's folds) rest like FSj.
        variants = [c for c in _named(names, "FS", term.row) if c != term.column] if own_terms([term]) else []
        for column in [term.column] + variants + _named(names, STRIBECK_PREFIX, term.row):
            Phi[still, term.row, column] = 0.0
        own = _named(names, PRESLIDING_PREFIX, term.row) if own_terms([term]) else []
        if own:
            # FPj holds z of the joint's own positions (PreslidingBase): kept at rest only, with this policy.
            for column in own:
                Phi[driver_moving if rest == "presliding" else slice(None), term.row, column] = 0.0
        elif rest == "presliding" and not _named(names, PRESLIDING_PREFIX, term.row):
            # Columns built by hand, without FPj: z in FS's column (shared magnitude). A motor's
            # Coulomb term (the coupling's FSM) beside an FPj adds nothing at rest.
            z = presliding_state(q @ np.asarray(term.driver))
            Phi[still, term.row, term.column] = z[still]
    return usable


def _named(names: Sequence[str], prefix: str, row: int) -> list[int]:
    """The column(s) of parameter ``prefix`` of joint ``row`` + 1 among ``names``: the name itself,
    or its candidates ``NAME_k`` ([] when absent)."""
    name = f"{prefix}{row + 1}"
    return [c for c, n in enumerate(names) if n == name or (n.startswith(name + "_") and n[len(name) + 1:].isdigit())]
