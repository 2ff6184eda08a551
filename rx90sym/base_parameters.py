"""Base parameters (paper section II-D), two ways that must agree.

- symbolic: the general grouping rules (regrouping.py) with the lengths as CasADi symbols, then
  the particular eliminations near the base (parameters with no effect, rotor inertias that act
  exactly like a link inertia) found from the grouped regressor and checked to hold for any
  lengths; gives names, closed-form expressions (Table 2, eq. 19) and K(geometry).
- numeric: QR of the regressor stacked on random samples (Gautier 1991, ref. [14]).

Both choose, among the standard parameters in their eq. 4 order, the first ones whose columns
are independent of the preceding columns, so both give the same names and the same K.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from functools import cached_property
from typing import TYPE_CHECKING, Any, Callable, Iterator

import casadi as ca
import numpy as np
import scipy.linalg as sla

from .compiled import BatchFunction, BatchWorkspace, PickledFields, map_samples
from .parameters import LINK_PARAMETERS, split_name
from .regrouping import general_grouping

if TYPE_CHECKING:  # for annotations only
    from .description import Robot

# Columns are normalised before the rank decisions; a column whose distance to the span of the
# preceding ones is below this fraction of its norm is dependent. Random samples make genuine
# dependencies exact to ~1e-15 and independent columns stay above ~1e-4.
RANK_TOL = 1e-9


class Expressions(Mapping):
    """name -> closed form of each base parameter in the standard parameters, worked out on first
    use: the symbolic forms cost a tenth of a second of CasADi on a 6-joint arm, which a fit never
    reads (a table and ``rx90 model --base`` do). Pickled as the worked-out strings."""

    def __init__(self, make: Callable[[], dict[str, str]]) -> None:
        self._make: Callable[[], dict[str, str]] | None = make
        self._done: dict[str, str] | None = None

    def _forms(self) -> dict[str, str]:
        if self._done is None:
            self._done, self._make = self._make(), None
        return self._done

    def __getitem__(self, name: str) -> str:
        return self._forms()[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._forms())

    def __len__(self) -> int:
        return len(self._forms())

    def __repr__(self) -> str:
        return repr(self._forms())

    def __getstate__(self) -> dict[str, Any]:
        return {"_make": None, "_done": self._forms()}


@dataclass(frozen=True, eq=False)
class BaseParameters(PickledFields):
    """Base parameters of a robot: beta = K chi, Phi chi = Phi_b beta (eq. 2 on the base set)."""

    robot: Robot
    method: str
    names: tuple[str, ...]
    K: np.ndarray                        # (nb, n_params), numeric for the robot's geometry
    independent: tuple[int, ...]         # columns of the standard regressor kept as base columns
    expressions: Mapping[str, str]       # name -> closed form in the standard parameters (Expressions)
    K_symbolic: ca.Function | None = None  # geometry symbols -> K (symbolic method)
    geometry_names: tuple[str, ...] = ()
    geometry_values: tuple[float, ...] = ()

    @property
    def nb(self) -> int:
        """Number of base parameters."""
        return len(self.names)

    def beta(self, chi: Any) -> np.ndarray:
        """Base parameter values of a standard parameter vector (beta = K chi)."""
        return self.K @ np.asarray(chi, dtype=float)

    @cached_property
    def regressor(self) -> ca.Function:
        """casadi.Function (q, qd, qdd) -> Phi_b (n x nb), with Phi chi = Phi_b (K chi)."""
        f = self.robot.regressor
        q, qd, qdd = (ca.SX.sym(s, self.robot.n) for s in ("q", "qd", "qdd"))
        phi = f(q, qd, qdd)
        return ca.Function("base_regressor", [q, qd, qdd], [phi[:, list(self.independent)]],
                           ["q", "qd", "qdd"], ["Phi_b"])

    @cached_property
    def _batch(self) -> BatchFunction:
        return BatchFunction(self.regressor, name=f"{self.robot.name}_base_regressor")

    def regressor_batch(self, Q: Any, QD: Any, QDD: Any, out: np.ndarray | None = None) -> np.ndarray:
        """Phi_b on N samples, compiled: arrays (N, n) -> (N, n, nb); ``out`` filled in place if given."""
        return self._batch(Q, QD, QDD, out=out)

    def regressor_workspace(self, chunk: int = 2048) -> BatchWorkspace:
        """A reused buffer for Phi_b on many samples (see :class:`rx90sym.compiled.BatchWorkspace`)."""
        return BatchWorkspace(self._batch, chunk)

    def table(self) -> str:
        """Table 2 and eq. 19 of the paper, for this robot."""
        return format_table(self)


def base_parameters(robot: Robot, method: str = "symbolic", samples: int = 60, seed: int = 0) -> BaseParameters:
    """Base parameters of ``robot`` by ``method`` "symbolic" (regrouping rules) or "numeric" (QR).

    samples/seed: random states for the numeric rank decisions (both methods use them: the
    symbolic one only to find which grouped parameters still have no effect).
    """
    if method == "symbolic":
        return _symbolic(robot, samples, seed)
    if method == "numeric":
        return _numeric(robot, samples, seed)
    raise ValueError(f"base_parameters: method must be 'symbolic' or 'numeric', got {method!r}")


# --------------------------------------------------------------------------- shared numerics
def random_states(n: int, samples: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Random (q, qd, qdd) on which columns are compared (uniform angles, normal rates)."""
    rng = np.random.default_rng(seed)
    return (rng.uniform(-np.pi, np.pi, (samples, n)), rng.normal(0, 1.5, (samples, n)),
            rng.normal(0, 3.0, (samples, n)))


def stacked_regressor(robot: Robot, samples: int, seed: int) -> np.ndarray:
    """Phi stacked over random samples: (samples * n, n_params)."""
    blocks = map_samples(robot.regressor, *random_states(robot.n, samples, seed))
    return blocks.reshape(samples * robot.n, -1)


def _column_norms(W: np.ndarray, tol: float) -> np.ndarray:
    """Column norms with round-off-only columns (no effect on the model) set to exactly 0."""
    norms = np.linalg.norm(W, axis=0)
    norms[norms <= tol * norms.max(initial=0.0)] = 0.0
    return norms


def first_independent(W: np.ndarray, tol: float = RANK_TOL) -> list[int]:
    """Columns independent of all preceding columns, in order (QR without pivoting, ref. [14])."""
    norms = _column_norms(W, tol)
    scale = np.where(norms > 0, norms, 1.0)
    R = np.linalg.qr(np.where(norms > 0, W, 0.0) / scale, mode="r")
    diag = np.abs(np.diag(R))
    return [i for i in range(W.shape[1]) if norms[i] > 0 and diag[i] > tol]


def numeric_rank(W: np.ndarray, tol: float = RANK_TOL) -> int:
    """Rank from QR with column pivoting of the column-normalised matrix."""
    norms = _column_norms(W, tol)
    Wn = W[:, norms > 0] / norms[norms > 0]
    if Wn.shape[1] == 0:
        return 0
    _, R, _ = sla.qr(Wn, mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    return int(np.sum(d > tol * d[0]))


def grouping_matrix(W: np.ndarray, base: list[int]) -> np.ndarray:
    """K_d with W[:, others] = W[:, base] K_d (R1^-1 R2 of the QR of [W1 W2])."""
    others = [i for i in range(W.shape[1]) if i not in set(base)]
    Q, R = np.linalg.qr(np.hstack([W[:, base], W[:, others]]))
    nb = len(base)
    return sla.solve_triangular(R[:nb, :nb], R[:nb, nb:]), others


# --------------------------------------------------------------------------- numeric method
def _numeric(robot: Robot, samples: int, seed: int) -> BaseParameters:
    W = stacked_regressor(robot, samples, seed)
    rank = numeric_rank(W)
    base = first_independent(W)
    if len(base) != rank:
        raise RuntimeError(f"{robot.name}: ordered selection found {len(base)} independent columns "
                           f"but the pivoted QR rank is {rank}; increase samples")
    Kd, others = grouping_matrix(W, base)
    Kd[np.abs(Kd) < 1e-10] = 0.0
    names_std = robot.parameter_names
    K = np.zeros((len(base), len(names_std)))
    K[np.arange(len(base)), base] = 1.0
    K[:, others] = Kd
    names = tuple(_base_name(names_std[b], K[i], b) for i, b in enumerate(base))
    expressions = {nm: _numeric_expression(K[i], names_std) for i, nm in enumerate(names)}
    return BaseParameters(robot, "numeric", names, K, tuple(base), expressions)


def _numeric_expression(row: np.ndarray, names: tuple[str, ...]) -> str:
    terms = [(names[i], row[i]) for i in np.flatnonzero(row)]
    return _join([(_coef_str(c), p) for p, c in terms])


# --------------------------------------------------------------------------- symbolic method
def _symbolic(robot: Robot, samples: int, seed: int) -> BaseParameters:
    g = general_grouping(robot)
    names_std = robot.parameter_names
    kept = [i for i, v in enumerate(g.values) if not ca.SX(v).is_zero()]
    # Particular eliminations: dependencies left among the grouped columns. They must not depend
    # on the lengths (they come from the axes' directions), so they are found at the robot's
    # geometry and checked at a second, random one with the same zero pattern.
    W = stacked_regressor(robot, samples, seed)[:, kept]
    local = first_independent(W)
    Kd, local_dep = grouping_matrix(W, local)
    other = _perturbed_geometry(robot, seed)
    W2 = stacked_regressor(other, samples, seed + 1)[:, kept]
    if first_independent(W2) != local:
        raise NotImplementedError(f"{robot.name}: the eliminations near the base depend on the "
                                  f"lengths for this geometry; use method='numeric'")
    Kd2, _ = grouping_matrix(W2, local)
    if not np.allclose(Kd, Kd2, atol=1e-7):
        raise NotImplementedError(f"{robot.name}: a particular grouping has a length-dependent "
                                  f"coefficient; use method='numeric'")
    Kd = np.where(np.abs(Kd - np.round(Kd)) < 1e-9, np.round(Kd), Kd)
    base = [kept[i] for i in local]
    dep = [kept[i] for i in local_dep]
    beta = []
    for a, b in enumerate(base):
        expr = g.values[b]
        for c, k in enumerate(dep):
            if Kd[a, c] != 0.0:
                expr = expr + float(Kd[a, c]) * g.values[k]
        beta.append(ca.simplify(expr))
    K_sx = ca.jacobian(ca.vertcat(*beta), g.chi)
    K_fun = ca.Function("K", [g.geometry], [K_sx], ["geometry"], ["K"])
    K = K_fun(np.array(g.geometry_values)).full() if g.geometry.numel() else ca.DM(K_sx).full()
    K[np.abs(K) < 1e-14] = 0.0
    geo_names = tuple(g.geometry[i].name() for i in range(g.geometry.numel()))
    names = tuple(_base_name(names_std[b], K[i], b) for i, b in enumerate(base))
    expressions = Expressions(lambda: {nm: _symbolic_expression(K_sx[i, :], g, names_std) for i, nm in enumerate(names)})
    return BaseParameters(robot, "symbolic", names, K, tuple(base), expressions, K_fun, geo_names,
                          g.geometry_values)


def _perturbed_geometry(robot: Robot, seed: int) -> Any:
    rng = np.random.default_rng(seed + 12345)
    d = tuple(0.0 if x == 0 else float(rng.uniform(0.1, 1.0)) for x in robot.d)
    r = tuple(0.0 if x == 0 else float(rng.uniform(0.1, 1.0)) for x in robot.r)
    return replace(robot, d=d, r=r)


def _base_name(name: str, row: np.ndarray, own: int) -> str:
    """'R' suffix when other parameters were grouped into this one (paper's naming)."""
    others = np.flatnonzero(row)
    return name + "R" if any(i != own for i in others) else name


# --------------------------------------------------------------------------- formatting
def _coef_str(c: float) -> str:
    if float(c).is_integer():
        return str(int(c))
    return f"{c:.6g}"


def _poly_terms(coef: ca.SX, geometry: ca.SX, names: list[str]) -> list[tuple[float, str]]:
    """Monomials of a coefficient that is a polynomial of degree <= 2 in the lengths (units:
    a base parameter mixes kg m^2, kg m and kg, so no higher power can appear)."""
    if geometry.numel() == 0:
        return [(float(ca.DM(coef)), "")]
    x = geometry
    zero = np.zeros(x.numel())
    f = ca.Function("c", [x], [coef, ca.gradient(coef, x), ca.hessian(coef, x)[0]])
    c0, g, H = (np.array(v, dtype=float) for v in f(zero))
    terms = []
    if abs(c0.item()) > 1e-12:
        terms.append((c0.item(), ""))
    for i in range(len(names)):
        if abs(g[i, 0]) > 1e-12:
            terms.append((g[i, 0], names[i]))
    for i in range(len(names)):
        for k in range(i, len(names)):
            v = H[i, k] if i != k else H[i, i] / 2
            if abs(v) > 1e-12:
                terms.append((v, f"{names[i]}**2" if i == k else f"{names[i]}*{names[k]}"))
    return terms


def _symbolic_expression(row: ca.SX, g, names_std: tuple[str, ...]) -> str:
    geo = [g.geometry[i].name() for i in range(g.geometry.numel())]
    groups: dict[tuple, list[str]] = {}
    for i in range(len(names_std)):
        coef = row[0, i]
        if coef.is_zero():
            continue
        key = tuple((round(c, 12), m) for c, m in _poly_terms(coef, g.geometry, geo))
        if key:
            groups.setdefault(key, []).append(names_std[i])
    parts = []
    for key, params in groups.items():
        poly = _join([(_coef_str(c), m) for c, m in key]) if key else "0"
        monomial_only = len(key) == 1
        if len(key) == 1 and key[0][1] == "":
            c = key[0][0]
            parts.extend((_coef_str(c), p) for p in params)
            continue
        factor = poly if monomial_only else f"({poly})"
        inner = params[0] if len(params) == 1 else "(" + " + ".join(params) + ")"
        parts.append(("1", f"{factor}*{inner}"))
    return _join(parts)


def _join(terms: list[tuple[str, str]]) -> str:
    """'a*b + c - d' from (coefficient string, symbol) pairs."""
    out = ""
    for coef, sym in terms:
        neg = coef.startswith("-")
        mag = coef[1:] if neg else coef
        body = sym if mag == "1" and sym else (mag if not sym else f"{mag}*{sym}")
        if sym and sym.startswith("-"):
            body, neg = body[1:], not neg
        if not out:
            out = ("-" if neg else "") + body
        else:
            out += (" - " if neg else " + ") + body
    return out or "0"


def format_table(bp: BaseParameters) -> str:
    """Table 2 (base inertial parameters per link, '0' where eliminated) and the eq. 19 list."""
    robot = bp.robot
    kinds = LINK_PARAMETERS[:11]
    width = max(6, max(len(nm) for nm in bp.names) + 1)
    lines = [f"Base parameters of {robot.name} ({bp.method}): {bp.nb}",
             "j".ljust(3) + "".join(k.ljust(width) for k in kinds)]
    by_std = {robot.parameter_names[b]: nm for b, nm in zip(bp.independent, bp.names)}
    for j in range(1, robot.n + 1):
        lines.append(str(j).ljust(3) + "".join(by_std.get(f"{k}{j}", "0").ljust(width) for k in kinds))
    rest = [nm for nm in bp.names if split_name(nm.rstrip("R"))[0] not in kinds]
    lines.append("friction and other: " + " ".join(rest))
    lines.append("")
    lines.append("Grouping relations (eq. 19):")
    for nm in bp.names:
        if nm.endswith("R") and nm[:-1] in robot.parameter_names:
            lines.append(f"  {nm} = {bp.expressions[nm]}")
    return "\n".join(lines)
