"""Velocity scales of smooth friction from per-joint factors tabulated on grids of scales.

The smooth Coulomb FS·tanh(q̇/vs) and Stribeck (FS + (FST − FS)·exp(−(q̇/vs)²))·sign(q̇)
(identify.friction.forms) are linear in every parameter but each joint's velocity scale vs
[rad/s]. Their columns, evaluated on the filtered, decimated driver speed v of every row at a list
of scales per joint, are tabulated as extra columns of the per-joint triangular factors
(:class:`identify.friction.scale_table.ScaleTable`, block after block). Any choice of one tabulated
scale per joint then gives the projected cost F(s) = ½‖D(Y − W(s)·β̂(s))‖² (variable projection,
Golub & Pereyra; D eq. 11's weights of a first fit at a middle scale) from the factors' Gram matrices
alone: nothing of the rows is kept, so the search reads a log of any length block by block and its
result does not depend on the block. A joint's costs at all its scales come from one Cholesky factor
of the columns that do not change with it (a Schur complement per scale).

The search (:func:`find_scales`): on a log grid of 1/8 decade (:data:`COARSE_GRID`) over
:data:`SCALE_BOUNDS`, each joint starts at the scale its own rows prefer (a common scale), then
coordinate descent (two sweeps); a parabola in log s through the best point and its neighbours
gives each joint the centre of a fine grid of 1/48 decade reaching a coarse step either side
(:func:`fine_grids`, a second table); coordinate descent on it and a parabola again. The scale is then rounded to a lattice of 1/4096
decade (0.06 %), far below its σ: two tables equal to rounding (another block size) give the same
scale. σ of the scales: the Gauss-Newton covariance σ²(JᵀJ)⁻¹ of the weighted residual in (β, ln s)
at the fine grid's best point, the columns' derivatives in ln s tabulated beside them,
σ² = 2F / (rows − parameters).

Lower bound of each joint's scale: half the :data:`LOW_SPEED_SHARE` quantile of its moving speeds
(below it a column fits a handful of rows; :func:`identify.friction.scale_table.lower_bounds`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from identify.estimation.compression import _from_augmented_rows
from identify.friction.scale_table import LOW_SPEED_SHARE, SCALE_BOUNDS, ScaleTable, lower_bounds

__all__ = ["COARSE_GRID", "LOW_SPEED_SHARE", "SCALE_BOUNDS", "ScaleSearch", "coarse_search", "find_scales",
           "fine_grids", "fine_search"]

#: The first table's scales [rad/s]: 1/8 decade apart from the lower bound, and the upper bound.
COARSE_GRID = np.r_[10.0 ** (-4 + np.arange(35) / 8), SCALE_BOUNDS[1]]
#: The scale of the first fit, whose residuals give eq. 11's weights [rad/s].
MIDDLE_SCALE = 10.0 ** -1.5
#: Fine grid: points and spacing [decades]; the lattice the scales are rounded to [decades].
FINE_POINTS, FINE_STEP, LATTICE = 13, 1.0 / 48, 1.0 / 4096


@dataclass(frozen=True)
class ScaleSearch:
    """The scales found: per searched joint (``joints``, 0-based) the scale [rad/s], its σ [rad/s], whether
    it stopped on a bound; cost: the weighted cost F at them; weights (n,): eq. 11's of the first fit;
    lo: ln lower bound per searched joint."""

    joints: tuple[int, ...]
    scales: np.ndarray
    std: np.ndarray
    at_bound: tuple[bool, ...]
    cost: float
    weights: np.ndarray
    lo: np.ndarray


#: Rank tolerance on a column-scaled Gram matrix (its eigenvalues are the squared singular values of the
#: column-scaled rows: 1e-14 is a singular value of 1e-7, as fine as rounding in the Gram allows).
GRAM_RCOND = 1e-14


class _Gram:
    """The weighted projected cost of any choice of tabulated scale per joint, from the factors' Gram matrices."""

    def __init__(self, table: ScaleTable, R: dict[int, np.ndarray], rows: dict[int, int], weights: np.ndarray) -> None:
        self.table, self.rows = table, rows
        self.G = {j: (weights[j] ** 2) * (Rj.T @ Rj) for j, Rj in R.items()}
        stribeck = sorted(j for j, f in table.forms.items() if f == "stribeck")
        self.fst = {j: table.c + i for i, j in enumerate(stribeck)}
        self.C = table.c + len(stribeck)

    def indices(self, j: int, k: int | None) -> tuple[np.ndarray, np.ndarray]:
        """(columns of joint j's table rows, their place among the C + 1 global columns) at its scale index k."""
        t, c = self.table, self.table.c
        src, dst = list(range(c)), list(range(c))
        if k is not None and j in t.forms:
            src[t.own[j]] = c + k * t.m
            if t.forms[j] == "stribeck":
                src.append(c + k * t.m + 1)
                dst.append(self.fst[j])
        return np.array(src + [t.width - 1]), np.array(dst + [self.C])

    def part(self, j: int, k: int | None) -> np.ndarray:
        src, dst = self.indices(j, k)
        out = np.zeros((self.C + 1, self.C + 1))
        out[np.ix_(dst, dst)] = self.G[j][np.ix_(src, src)]
        return out

    def cost(self, parts: dict[int, np.ndarray]) -> float:
        """½ of the weighted residual's squared norm of the system summed from ``parts``."""
        A = sum(parts.values())
        C = self.C
        live = np.flatnonzero(np.diag(A)[:C] > 0)
        G, g = A[np.ix_(live, live)], A[live, C]
        try:
            L = np.linalg.cholesky(G)
            z = np.linalg.solve(L, g)
        except np.linalg.LinAlgError:   # rank deficient at this scale: the least-norm solution
            x = np.linalg.lstsq(G, g, rcond=None)[0]
            return 0.5 * float(A[C, C] - g @ x)
        return 0.5 * float(A[C, C] - z @ z)


    def profile(self, j: int, parts: dict[int, np.ndarray], ks: np.ndarray) -> np.ndarray:
        """The cost at each of joint j's tabulated scales ``ks``, the other joints' parts as in ``parts``:
        the columns that do not change with j's scale (X) factored once, each scale's column(s) f_k
        (FSj, and FSTj for Stribeck; 0 in the other joints' rows) projected on them, cost =
        ½(‖y − P_X y‖² − nᵀ D⁻¹ n), n = f_kᵀ(y − P_X y), D = f_kᵀ(I − P_X)f_k."""
        t, C = self.table, self.C
        varying = [t.own[j]] + ([self.fst[j]] if j in self.fst else [])
        A = sum(parts.values())   # joint j's X-X block does not depend on its scale
        X = np.array([x for x in range(C) if x not in varying and A[x, x] > 0])
        white = _whitening(A[np.ix_(X, X)])
        zy = white(A[X, C])
        rest = A[C, C] - zy @ zy
        # Joint j's table columns behind the global X columns (an FSTi of another joint is 0 in its rows).
        src, dst = self.indices(j, None)
        where = dict(zip(dst[:-1].tolist(), src[:-1].tolist()))
        rows = [i for i, x in enumerate(X) if x in where]
        srcX = [where[X[i]] for i in rows]
        m = 2 if t.forms[j] == "stribeck" else 1
        tab = (t.c + np.asarray(ks)[:, None] * t.m + np.arange(m)).ravel()     # the columns of every scale, in order
        Gj = self.G[j]
        GXf = np.zeros((X.size, tab.size))
        GXf[rows] = Gj[np.ix_(srcX, tab)]
        Zf = white(GXf).reshape(-1, len(ks), m)
        yc = t.width - 1
        num = Gj[tab, yc].reshape(len(ks), m) - np.einsum("xkm,x->km", Zf, zy)
        den = Gj[np.ix_(tab, tab)].reshape(len(ks), m, len(ks), m)[np.arange(len(ks)), :, np.arange(len(ks)), :] \
            - np.einsum("xkm,xkn->kmn", Zf, Zf)
        if m == 1:   # nᵀD⁻¹n of one column (0 where the column is 0: nothing gained)
            d = den[:, 0, 0]
            gain = np.where(d > 0, num[:, 0] ** 2 / np.where(d > 0, d, 1.0), 0.0)
        else:
            gain = np.array([n @ np.linalg.lstsq(d, n, rcond=None)[0] for n, d in zip(num, den)])
        return 0.5 * (rest - gain)


def _weights(table: ScaleTable, R: dict[int, np.ndarray], rows: dict[int, int], middle: dict[int, int]) -> np.ndarray:
    """eq. 11's weights (1/σ_j of each joint's own residual) of the fit at the tabulated scale ``middle[j]``."""
    from identify.estimation.least_squares import joint_weights

    gram = _Gram(table, R, rows, np.ones(table.n))
    blocks = {}
    for j in sorted(R):  # the joints with rows (one whose torque is left out has none: weight 0)
        src, dst = gram.indices(j, middle.get(j))
        M = np.zeros((R[j].shape[0], gram.C + 1))
        M[:, dst] = R[j][:, src]
        blocks[j] = M
    live = np.flatnonzero(np.any(np.vstack(list(blocks.values()))[:, :gram.C] != 0.0, axis=0))  # e.g. an FPj never resting
    weights = np.zeros(table.n)
    weights[sorted(blocks)] = joint_weights([_from_augmented_rows(M[:, list(live) + [gram.C]], rows[j])
                                             for j, M in blocks.items()])
    return weights


def _whitening(G: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """``x -> L⁻¹x`` with G = LLᵀ (Cholesky), or, where G is singular (columns the rows cannot separate,
    e.g. a one-way joint's Coulomb column and its offset), ``Λ⁻½VᵀDx`` over the eigenvectors of the
    column-scaled Gram DGD above :data:`GRAM_RCOND` x its largest eigenvalue: the same projections
    (``zᵀz = xᵀG⁺x``) on the columns' span."""
    try:
        L = np.linalg.cholesky(G)
        return lambda x: np.linalg.solve(L, x)
    except np.linalg.LinAlgError:
        d = np.sqrt(np.diag(G))
        D = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
        lam, V = np.linalg.eigh(G * np.outer(D, D))
        keep = lam > GRAM_RCOND * max(lam.max(), 0.0)
        M = (V[:, keep].T * D[None, :]) / np.sqrt(lam[keep])[:, None]
        return lambda x: M @ x


def _parabola(u: np.ndarray, f: np.ndarray, k: int) -> float:
    """The vertex of the parabola through points k-1, k, k+1 (equally spaced in u), within a step of u[k];
    u[k] at an end or where not convex."""
    if k == 0 or k == len(u) - 1:
        return float(u[k])
    h = u[k + 1] - u[k]
    den = f[k - 1] - 2 * f[k] + f[k + 1]
    if not (den > 0 and h > 0):
        return float(u[k])
    return float(u[k] + np.clip(0.5 * h * (f[k - 1] - f[k + 1]) / den, -h, h))


def _descend(gram: _Gram, joints: Sequence[int], allowed: dict[int, np.ndarray],
             start: dict[int, int]) -> tuple[dict[int, int], dict[int, np.ndarray]]:
    """Coordinate descent over each joint's allowed scale indices (two sweeps): (choice, per joint the
    costs along its allowed indices at the others' final choice)."""
    pick = dict(start)
    parts = {j: gram.part(j, pick.get(j)) for j in gram.G}
    profile = {}
    for _ in range(2):
        for j in joints:
            profile[j] = gram.profile(j, parts, allowed[j])
            pick[j] = int(allowed[j][int(np.argmin(profile[j]))])
            parts[j] = gram.part(j, pick[j])
    return pick, profile


def coarse_search(table: ScaleTable, folds: Sequence[int] | None = None,
                  weights: np.ndarray | None = None) -> ScaleSearch:
    """The first stage on the rows of ``folds`` (None: every fold) of a table of :data:`COARSE_GRID`:
    scales the parabolas' vertices (the centres of the fine grids), σ not computed; weights: eq. 11's
    (None: of the first fit at :data:`MIDDLE_SCALE`)."""
    folds = list(range(table.folds)) if folds is None else list(folds)
    R, rows, counts = table.merged(folds)
    joints = tuple(j for j in sorted(table.forms) if j in R)  # a joint without rows (its torque left out): Coulomb
    if not joints:
        raise ValueError("velocity-scale search: no joint of a smooth form has rows")
    lo = lower_bounds(counts, joints)
    if weights is None:
        middle = {j: int(np.argmin(np.abs(np.log(table.scales[j] / MIDDLE_SCALE)))) for j in joints}
        weights = _weights(table, R, rows, middle)
    gram = _Gram(table, R, rows, weights)
    allowed = _allowed(table, joints, lo, np.arange(table.K))
    pick, profile = _descend(gram, joints, allowed, _common_start(gram, joints, allowed))
    centre = [_parabola(np.log(table.scales[j][allowed[j]]), profile[j],
                        int(np.flatnonzero(allowed[j] == pick[j])[0])) for j in joints]
    return ScaleSearch(joints, np.exp(centre), np.full(len(joints), np.nan), tuple(False for _ in joints),
                       gram.cost({j: gram.part(j, pick.get(j)) for j in gram.G}), weights, lo)


def _allowed(table: ScaleTable, joints: Sequence[int], lo: np.ndarray, indices: np.ndarray) -> dict[int, np.ndarray]:
    """Per joint the table's scale ``indices`` within its bounds."""
    hi = np.log(SCALE_BOUNDS[1])
    out = {}
    for i, j in enumerate(joints):
        u = np.log(table.scales[j][indices])
        out[j] = indices[(u >= lo[i] - 1e-12) & (u <= hi + 1e-12)]
    return out


def fine_search(table: ScaleTable, first: ScaleSearch, folds: Sequence[int] | None = None,
                group: int = 0) -> ScaleSearch:
    """The second stage on the rows of ``folds`` of a table whose scales ``group`` (the group-th run of
    :data:`FINE_POINTS` per joint) are :func:`fine_grids` of the ``first`` stage: coordinate descent from
    the points nearest its centres, parabolas, the scales rounded to the :data:`LATTICE`, σ."""
    folds = list(range(table.folds)) if folds is None else list(folds)
    joints, lo, hi = first.joints, first.lo, np.log(SCALE_BOUNDS[1])
    R, rows, _ = table.merged(folds)
    gram = _Gram(table, R, rows, first.weights)
    allowed = _allowed(table, joints, lo, np.arange(group * FINE_POINTS, (group + 1) * FINE_POINTS))
    start = {j: int(allowed[j][np.argmin(np.abs(np.log(table.scales[j][allowed[j]] / first.scales[i])))])
             for i, j in enumerate(joints)}
    pick, profile = _descend(gram, joints, allowed, start)
    step = LATTICE * np.log(10.0)
    out_u = []
    for i, j in enumerate(joints):
        v = _parabola(np.log(table.scales[j][allowed[j]]), profile[j], int(np.flatnonzero(allowed[j] == pick[j])[0]))
        out_u.append(float(np.clip(np.round(v / step) * step, lo[i], hi)))
    f = gram.cost({j: gram.part(j, pick.get(j)) for j in gram.G})
    sigma2 = 2.0 * f / max(1, sum(rows.values()) - gram.C - len(joints))
    u = np.array(out_u)
    std = np.exp(u) * _gauss_newton_std(gram, joints, pick, sigma2) if table.derivatives else np.full(u.size, np.nan)
    bound = tuple(bool(min(x - a, hi - x) < 1e-3) for x, a in zip(u, lo))
    return ScaleSearch(joints, np.exp(u), std, bound, f, first.weights, lo)


def _gauss_newton_std(gram: _Gram, joints: Sequence[int], pick: dict[int, int], sigma2: float) -> np.ndarray:
    """σ of each joint's ln s: σ²(JᵀJ)⁻¹ of the weighted residual in (β, ln s) at the scales ``pick`` (the
    scales together: their columns share the other parameters), J's column of joint j's ln s the
    derivative of its friction columns times their coefficients β̂ (in joint j's rows only)."""
    t, C = gram.table, gram.C
    parts = {j: gram.part(j, pick.get(j)) for j in gram.G}
    A = sum(parts.values())
    live = np.flatnonzero(np.diag(A)[:C] > 0)
    beta = np.zeros(C)
    beta[live] = np.linalg.lstsq(A[np.ix_(live, live)], A[live, C], rcond=None)[0]
    J = len(joints)
    N = np.zeros((C + J, C + J))
    d0 = t.c + t.K * t.m
    for j, Gj in gram.G.items():
        src, dst = gram.indices(j, pick.get(j))
        P = np.zeros((t.width, C + J))
        P[src[:-1], dst[:-1]] = 1.0
        if j in joints:   # ∂(β_FS f + β_FST f_ST)/∂ln s_j
            k = pick[j]
            P[d0 + k * t.m, C + joints.index(j)] = beta[t.own[j]]
            if j in gram.fst:
                P[d0 + k * t.m + 1, C + joints.index(j)] = beta[gram.fst[j]]
        N += P.T @ Gj @ P
    keep = np.r_[live, C + np.arange(J)]
    cov = sigma2 * np.linalg.pinv(N[np.ix_(keep, keep)])
    return np.sqrt(np.maximum(np.diag(cov)[-J:], 0.0))


def find_scales(feed: Callable[[ScaleTable], None], n: int, c: int, own: dict[int, int], forms: dict[int, str],
                fold_sets: Sequence[Sequence[int] | None] = (None,), folds: int = 1, std: bool = True) -> list[ScaleSearch]:
    """The scales of the joints ``forms`` on each set of folds of ``fold_sets`` (None: all), from two passes
    over the rows: ``feed(table)`` adds every probe row to the table (``ScaleTable.add``, rows of ``c``
    columns, ``own`` the own Coulomb column of each joint, ``folds`` time blocks). The coarse table,
    then one fine table holding every set's fine grid (with the columns' derivatives when ``std``: the
    scales' σ; without, σ is NaN)."""
    coarse = ScaleTable(n, c, own, forms, {j: COARSE_GRID for j in forms}, folds)
    feed(coarse)
    first = [coarse_search(coarse, fs) for fs in fold_sets]
    grids = [fine_grids(x) for x in first]
    forms = {j: forms[j] for j in sorted({j for x in first for j in x.joints})}  # the joints with rows
    fine = ScaleTable(n, c, own, forms, {j: np.concatenate([g.get(j, np.full(FINE_POINTS, MIDDLE_SCALE)) for g in grids])
                                         for j in forms}, folds, std)
    feed(fine)
    return [fine_search(fine, x, fs, i) for i, (x, fs) in enumerate(zip(first, fold_sets))]


def _common_start(gram: _Gram, joints: Sequence[int], allowed: dict[int, np.ndarray]) -> dict[int, int]:
    """Each joint's index of lowest own residual when every smooth joint takes the same tabulated scale."""
    import scipy.linalg
    K = gram.table.K
    best = {}
    own = np.full((K, len(joints)), np.inf)
    for k in range(K):
        parts = {j: gram.part(j, k if j in joints else None) for j in gram.G}
        A = sum(parts.values())
        C = gram.C
        live = np.flatnonzero(np.diag(A)[:C] > 0)
        beta = np.zeros(C)
        try:
            beta[live] = scipy.linalg.cho_solve(scipy.linalg.cho_factor(A[np.ix_(live, live)]), A[live, C])
        except np.linalg.LinAlgError:   # rank deficient at this scale: the least-norm solution
            beta[live] = np.linalg.lstsq(A[np.ix_(live, live)], A[live, C], rcond=None)[0]
        x = np.r_[beta, -1.0]
        for i, j in enumerate(joints):
            own[k, i] = float(x @ parts[j] @ x)    # the joint's own weighted residual
    for i, j in enumerate(joints):
        ok = allowed[j]
        best[j] = int(ok[np.argmin(own[ok, i])]) if ok.size else int(np.argmin(own[:, i]))
    return best


def fine_grids(coarse: ScaleSearch) -> dict[int, np.ndarray]:
    """Per searched joint the fine table's scales [rad/s]: :data:`FINE_POINTS` points :data:`FINE_STEP`
    decades apart centred on the coarse result, shifted inside the bounds, the lower bound itself the
    first point when it is reached."""
    step = FINE_STEP * np.log(10.0)
    half = (FINE_POINTS - 1) // 2
    out = {}
    for i, j in enumerate(coarse.joints):
        c = float(np.log(coarse.scales[i]))
        a = max(coarse.lo[i], c - half * step)
        b = min(np.log(SCALE_BOUNDS[1]), a + 2 * half * step)
        a = b - 2 * half * step if b - 2 * half * step >= coarse.lo[i] else a
        out[j] = np.exp(np.linspace(a, b, FINE_POINTS)) if b > a else np.exp(np.full(FINE_POINTS, a))
    return out
