"""Tests of identify.estimation.consistency: pseudo-inertia, consistency report, consistent least squares.

Independent truths used here (none of them goes through the code under test):

* rigid bodies built from their mass distribution (solid box, cylinder, point clouds), whose
  pseudo-inertia is by definition ∫ [r; 1][r; 1]ᵀ dm;
* the classical consistency test (m > 0, inertia about the CoM PSD, principal moments obeying
  the triangle inequalities) written from the parallel-axis theorem;
* a genuine base-parameter map K for a 3-joint RX90-like arm (Table 1, axes 1–3), obtained from
  a small numpy Newton–Euler regressor written here (inertia about the frame origin, first
  moments, eq. 2) and QR with column pivoting (Gautier 1991): W = W_b K exactly;
* parameters that K identifies *directly* (a row of K that is a unit vector) and that every
  consistent body has ≥ 0 (IA, FV, FS and the diagonal moments XX, YY, ZZ about the origin):
  a negative OLS value there proves OLS inconsistent without solving anything.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

cp = pytest.importorskip("cvxpy")

from identify.estimation.consistency import (  # noqa: E402
    ConsistencyError,
    build_consistent_problem,
    consistency_margin,
    consistency_report,
    consistent_least_squares,
    pseudo_inertia,
)

FIELDS13 = ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M", "IA", "FS", "FV")
# Table 1, joints 1–3 (alpha, d, r); theta = q.
RX90_FIRST_THREE = ((0.0, 0.0, 0.0), (-np.pi / 2, 0.0, 0.0), (0.0, 0.45, 0.0))


# ------------------------------------------------------------------------------------------
# Independent helpers
# ------------------------------------------------------------------------------------------


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def _p10(inertia_origin: np.ndarray, h: np.ndarray, m: float) -> np.ndarray:
    i = inertia_origin
    return np.array([i[0, 0], i[0, 1], i[0, 2], i[1, 1], i[1, 2], i[2, 2], *h, m])


def _body_from_com(m: float, com: np.ndarray, inertia_com: np.ndarray) -> np.ndarray:
    """Ten parameters about the frame origin from mass, CoM (m) and inertia about the CoM."""
    shift = m * (com @ com * np.eye(3) - np.outer(com, com))  # parallel-axis theorem
    return _p10(inertia_com + shift, m * com, m)


def _classically_consistent(p: np.ndarray, tol: float = 1e-9) -> tuple[bool, float]:
    """(consistent within ``tol``?, distance to the boundary) from m, I_CoM and the triangle
    inequalities. A body with m ≤ 0 passes only as the all-zero (massless) limit."""
    m = p[9]
    if m <= 0:
        return bool(np.abs(p).max() <= tol), abs(m)
    i_origin = np.array([[p[0], p[1], p[2]], [p[1], p[3], p[4]], [p[2], p[4], p[5]]])
    com = p[6:9] / m
    i_com = i_origin - m * (com @ com * np.eye(3) - np.outer(com, com))
    lam = np.linalg.eigvalsh(i_com)
    margins = [lam[0], lam[1] + lam[2] - lam[0], lam[0] + lam[2] - lam[1], lam[0] + lam[1] - lam[2]]
    return bool(min(margins) >= -tol), abs(min(margins))


def _point_cloud_body(rng: np.random.Generator, mass: float, size: float, points: int = 8) -> np.ndarray:
    pts = rng.normal(size=(points, 3)) * size + rng.normal(size=3) * size
    w = rng.uniform(0.5, 1.5, points)
    w *= mass / w.sum()
    inertia = sum(wk * (p @ p * np.eye(3) - np.outer(p, p)) for wk, p in zip(w, pts))
    return _p10(inertia, (w[:, None] * pts).sum(axis=0), mass)


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def _regressor(table, q, qd, qdd, g: float = 9.81) -> np.ndarray:
    """Φ (n × 13n) of Γ = Φ χ for a revolute Khalil–Kleinfinger chain (eqs. 1–5)."""
    n = len(q)
    z = np.array([0.0, 0.0, 1.0])
    w, wd, vd = np.zeros(3), np.zeros(3), np.array([0.0, 0.0, g])  # gravity as base acceleration
    r0, p0 = np.eye(3), np.zeros(3)
    wrench_maps, frames = [], []
    for j in range(n):
        alpha, d, r = table[j]
        ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(q[j]), np.sin(q[j])
        rot = np.array([[ct, -st, 0], [ca * st, ca * ct, -sa], [sa * st, sa * ct, ca]])
        pos = np.array([d, -r * sa, r * ca])
        vd = rot.T @ (vd + np.cross(wd, pos) + np.cross(w, np.cross(w, pos)))
        w_prev = rot.T @ w
        w = w_prev + qd[j] * z
        wd = rot.T @ wd + qdd[j] * z + np.cross(w_prev, qd[j] * z)
        a = np.zeros((6, 10))  # [F; M about origin j] = a @ (XX..M)
        a[0:3, 9] = vd
        a[0:3, 6:9] = _skew(wd) + _skew(w) @ _skew(w)
        for k, (u, v) in enumerate(((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))):
            e = np.zeros((3, 3))
            e[u, v] = e[v, u] = 1.0
            a[3:6, k] = e @ wd + _skew(w) @ e @ w
        a[3:6, 6:9] = -_skew(vd)
        wrench_maps.append(a)
        p0 = p0 + r0 @ pos
        r0 = r0 @ rot
        frames.append((r0.copy(), p0.copy()))
    phi = np.zeros((n, 13 * n))
    for i in range(n):
        ri, pi = frames[i]
        for j in range(i, n):
            rj, pj = frames[j]
            a = wrench_maps[j]
            phi[i, 13 * j : 13 * j + 10] = ri[:, 2] @ (rj @ a[3:6] + _skew(pj - pi) @ rj @ a[0:3])
        phi[i, 13 * i + 10 : 13 * i + 13] = (qdd[i], np.sign(qd[i]), qd[i])
    return phi


class Arm:
    """3-joint arm with a genuine numeric base map and consistent true parameters."""

    def __init__(self, seed: int = 0) -> None:
        self.table = RX90_FIRST_THREE
        n = len(self.table)
        self.names = tuple(f"{f}{j}" for j in range(1, n + 1) for f in FIELDS13)
        rng = np.random.default_rng(seed)
        w = np.vstack([_regressor(self.table, *rng.uniform(-3, 3, (3, n))) for _ in range(30)])
        _, r, piv = sla.qr(w, mode="economic", pivoting=True)
        c = int(np.sum(np.abs(np.diag(r)) > abs(r[0, 0]) * 1e-9))
        self.K = np.zeros((c, w.shape[1]))
        self.K[:, piv[:c]] = np.eye(c)
        self.K[:, piv[c:]] = sla.solve_triangular(r[:c, :c], r[:c, c:])
        self.base_columns = piv[:c]
        chi = []
        for mass, size in ((10.0, 0.2), (8.0, 0.2), (4.0, 0.1)):
            body = _point_cloud_body(rng, mass, size)
            ia, fs, fv = rng.uniform(0.2, 1.0), rng.uniform(0.5, 2), rng.uniform(0.5, 2)
            chi += [*body, ia, fs, fv]
        self.chi = np.array(chi)
        self.beta = self.K @ self.chi

    def data(self, samples: int, noise: float, seed: int):
        """Base observation matrix, torques, and the compressed system (R, z, rss_outside).

        ``samples`` random states (q, q̇, q̈ uniform in ±2 rad, rad/s, rad/s²), 3 equations each,
        Gaussian torque noise of std ``noise`` N·m; (R, z) from the QR of [W_b | y].
        """
        rng = np.random.default_rng(seed)
        n = len(self.table)
        states = (rng.uniform(-2, 2, (3, n)) for _ in range(samples))
        wb = np.vstack([_regressor(self.table, *s)[:, self.base_columns] for s in states])
        y = wb @ self.beta + noise * rng.normal(size=wb.shape[0])
        r_aug = np.linalg.qr(np.column_stack([wb, y]), mode="r")
        return wb, y, r_aug[:-1, :-1], r_aug[:-1, -1], float(r_aug[-1, -1] ** 2)

    def certificate(self, beta: np.ndarray) -> list[str]:
        """Names of directly identified must-be-non-negative parameters that are negative."""
        out = []
        for i, row in enumerate(self.K):
            nz = np.flatnonzero(np.abs(row) > 1e-12)
            name = self.names[nz[0]]
            direct = nz.size == 1 and abs(row[nz[0]] - 1.0) < 1e-12
            if direct and name.startswith(("IA", "FV", "FS", "XX", "YY", "ZZ")) and beta[i] < 0:
                out.append(name)
        return out


@pytest.fixture(scope="module")
def arm() -> Arm:
    return Arm()


def _all_bodies_consistent(chi: np.ndarray, names) -> bool:
    for j in range(len(names) // 13):
        if not _classically_consistent(chi[13 * j : 13 * j + 10])[0]:
            return False
    return all(v >= -1e-9 for n, v in zip(names, chi) if n.startswith(("IA", "FV", "FS")))


# ------------------------------------------------------------------------------------------
# pseudo_inertia
# ------------------------------------------------------------------------------------------


def test_solid_box_pseudo_inertia_is_its_second_moment_matrix_and_positive_definite() -> None:
    rng = np.random.default_rng(1)
    m, dims, com, rot = 3.2, np.array([0.3, 0.1, 0.05]), np.array([0.1, -0.2, 0.4]), _rotation(rng)
    inertia_com = rot @ np.diag(m / 12 * (dims @ dims - dims**2)) @ rot.T  # m(b²+c²)/12 ...
    j = pseudo_inertia(_body_from_com(m, com, inertia_com))
    # ∫ r rᵀ dm for the box: m·(c cᵀ + R diag(a², b², c²)/12 Rᵀ).
    second = m * (np.outer(com, com) + rot @ np.diag(dims**2 / 12) @ rot.T)
    expected = np.block([[second, m * com[:, None]], [m * com[None, :], np.array([[m]])]])
    np.testing.assert_allclose(j, expected, atol=1e-12)
    assert np.linalg.eigvalsh(j)[0] > 0


def test_solid_cylinder_is_positive_definite() -> None:
    m, radius, height = 5.0, 0.06, 0.4
    inertia_com = np.diag([m * (3 * radius**2 + height**2) / 12] * 2 + [m * radius**2 / 2])
    j = pseudo_inertia(_body_from_com(m, np.array([0.0, 0.05, -0.2]), inertia_com))
    assert np.linalg.eigvalsh(j)[0] > 0
    assert consistency_report(_body_from_com(m, np.zeros(3), inertia_com), [f"{f}1" for f in FIELDS13[:10]]).ok


def test_triangle_inequality_violation_is_not_psd_although_inertia_is() -> None:
    inertia_com = np.diag([3.0, 1.0, 1.0])  # PSD, but Ixx > Iyy + Izz: no mass distribution has it
    assert np.linalg.eigvalsh(inertia_com)[0] > 0
    j = pseudo_inertia(_body_from_com(2.0, np.array([0.1, 0.0, 0.3]), inertia_com))
    assert np.linalg.eigvalsh(j)[0] < -0.1


def test_negative_mass_is_not_psd() -> None:
    p = _body_from_com(1.0, np.array([0.1, 0.2, 0.0]), np.diag([0.1, 0.1, 0.1]))
    p[9] = -1.0
    assert np.linalg.eigvalsh(pseudo_inertia(p))[0] < 0


def test_psd_agrees_with_classical_check_on_random_bodies() -> None:
    rng = np.random.default_rng(7)
    checked = both = 0
    for _ in range(400):
        m = rng.uniform(-0.5, 5.0)
        lam = rng.uniform(0.0, 1.0, 3)  # principal moments, triangle inequality sometimes broken
        rot = _rotation(rng)
        p = _body_from_com(m, rng.normal(size=3) * 0.3, rot @ np.diag(lam) @ rot.T)
        consistent, distance = _classically_consistent(p)
        if distance < 1e-6:
            continue  # too close to the boundary to call either way
        checked += 1
        both += consistent
        assert (np.linalg.eigvalsh(pseudo_inertia(p))[0] >= 0) == consistent
    assert checked > 300 and 50 < both < checked - 50  # both outcomes really exercised


def test_pseudo_inertia_cvxpy_expression_equals_numpy() -> None:
    p = np.arange(1.0, 11.0)
    x = cp.Variable(10)
    x.value = p
    np.testing.assert_allclose(pseudo_inertia(x).value, pseudo_inertia(p))
    np.testing.assert_allclose(pseudo_inertia(p), pseudo_inertia(p).T)
    with pytest.raises(ValueError, match="10"):
        pseudo_inertia(np.zeros(9))


# ------------------------------------------------------------------------------------------
# consistency_report
# ------------------------------------------------------------------------------------------


def test_report_covers_links_payload_and_prefix_rule() -> None:
    rng = np.random.default_rng(2)
    names = [f"{f}1" for f in FIELDS13] + ["FVM6", "FSM6", "OFF1"] + [f"{f}c" for f in FIELDS13[:10]]
    link = _point_cloud_body(rng, 3.0, 0.1)
    payload = _point_cloud_body(rng, 4.275, 0.05)
    chi = np.concatenate([link, [0.1, 1.0, 2.0], [0.5, 0.3, -7.0], payload])
    report = consistency_report(chi, names)
    assert report.ok and [b.body for b in report.bodies] == ["1", "c"]
    assert report.bodies[1].mass == pytest.approx(4.275)
    np.testing.assert_allclose(report.bodies[1].com, payload[6:9] / payload[9])
    assert [n for n, _, _ in report.nonnegative] == ["IA1", "FS1", "FV1", "FVM6", "FSM6"]  # OFF1 free

    bad = chi.copy()
    bad[names.index("FSM6")] = -1e-3
    assert not consistency_report(bad, names).ok
    assert any("FSM6" in v for v in consistency_report(bad, names).violations())
    assert consistency_report(dict(zip(names, chi)), names).ok
    with pytest.raises(ValueError, match="MZ1"):
        consistency_report(np.delete(chi, 8), [n for n in names if n != "MZ1"])


# ------------------------------------------------------------------------------------------
# consistent_least_squares
# ------------------------------------------------------------------------------------------


def test_test_arm_base_map_is_genuine(arm: Arm) -> None:
    # 3 joints of the RX90: ZZ1R; 7 for link 2; 7 for link 3; IA3; 6 friction terms (Table 2 rules).
    assert arm.K.shape == (22, 39)
    wb, _, _, _, _ = arm.data(5, 0.0, seed=9)
    rng = np.random.default_rng(9)
    w = np.vstack([_regressor(arm.table, *rng.uniform(-2, 2, (3, 3))) for _ in range(5)])
    np.testing.assert_allclose(w, wb @ arm.K, atol=1e-10)
    assert consistency_report(arm.chi, arm.names).ok


def test_equals_ols_when_ols_is_consistent(arm: Arm) -> None:
    wb, y, r, z, rss = arm.data(samples=400, noise=0.1, seed=0)
    beta_ols = np.linalg.solve(r, z)
    # Witness that OLS is consistent: truth moved along K's row space onto β_ols.
    witness = arm.chi + np.linalg.pinv(arm.K) @ (beta_ols - arm.beta)
    assert _all_bodies_consistent(witness, arm.names)

    sol = consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss, rows=wb.shape[0])
    assert sol.status == "optimal" and sol.report.ok and sol.rows == 1200
    assert _all_bodies_consistent(sol.chi, arm.names)
    assert sol.cost == pytest.approx(np.sum((wb @ sol.beta - y) ** 2), rel=1e-9)
    # OLS is the unconstrained minimum and here feasible, so the optimum equals it; what is left
    # is the null-space tie-break and solver tolerance (measured 2e-10) — far inside "a few %".
    assert rss <= sol.cost <= rss * (1 + 1e-4)
    np.testing.assert_allclose(sol.beta, beta_ols, atol=1e-3 * np.abs(beta_ols).max())
    assert sol.standard["M3"] == sol.chi[arm.names.index("M3")]


def test_poor_data_ols_inconsistent_but_constrained_consistent(arm: Arm) -> None:
    wb, y, r, z, rss = arm.data(samples=15, noise=5.0, seed=0)
    beta_ols = np.linalg.solve(r, z)
    assert arm.certificate(beta_ols), "OLS must be provably inconsistent for this seed"
    assert not arm.certificate(arm.beta)

    sol = consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss)
    assert sol.report.ok and _all_bodies_consistent(sol.chi, arm.names)
    assert not arm.certificate(sol.beta)
    true_cost = float(np.sum((wb @ arm.beta - y) ** 2))
    assert rss < sol.cost <= true_cost  # the truth is feasible, so the optimum can only be better
    assert sol.cost == pytest.approx(np.sum((wb @ sol.beta - y) ** 2), rel=1e-9)
    assert np.abs(sol.chi).max() < 100  # the null-space tie-break keeps unseen directions bounded


@pytest.mark.parametrize(
    "bounds",
    [
        dict(mass_bounds={2: (-2.0, -1.0)}),  # J ⪰ 0 implies M ≥ 0
        dict(total_mass=(30.0, 20.0)),  # lo > hi
        dict(mass_bounds={1: (20.0, None), "2": (15.0, None)}, total_mass=(None, 30.0)),
        # empty y-interval: M·0.2 ≤ MY ≤ M·0.1 forces M ≤ 0, against M ≥ 1
        dict(com_boxes={3: ([0.1, 0.2, 0.0], [0.2, 0.1, 0.1])}, mass_bounds={3: (1.0, None)}),
    ],
)
def test_infeasible_bounds_raise_with_status(arm: Arm, bounds: dict) -> None:
    _, _, r, z, rss = arm.data(samples=40, noise=0.5, seed=3)
    with pytest.raises(ConsistencyError, match="infeasible") as info:
        consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss, **bounds)
    assert info.value.status == "infeasible" and info.value.solver == "CLARABEL"
    assert "CLARABEL" in str(info.value)


def test_bounds_are_honoured_when_active(arm: Arm) -> None:
    _, _, r, z, rss = arm.data(samples=40, noise=0.5, seed=4)
    free = consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss)
    # Link 3's true CoM is (-0.10, 0.04, -0.02) m and it is seen (MX3, MY3 direct): the box
    # below excludes it, so the fit must pay for it.
    box = (np.array([-0.05, -0.05, -0.05]), np.array([0.02, 0.02, 0.02]))
    sol = consistent_least_squares(
        r, z, arm.K, arm.names, rss_outside=rss,
        mass_bounds={2: (9.0, 12.0), "3": (3.0, None)}, total_mass=(None, 25.0),
        com_boxes={3: box}, epsilon=1e-6,
    )
    tol = 1e-7
    assert 9.0 - tol <= sol.standard["M2"] <= 12.0 + tol and sol.standard["M3"] >= 3.0 - tol
    assert sum(sol.standard[f"M{j}"] for j in (1, 2, 3)) <= 25.0 + tol
    com3 = np.array(sol.report.bodies[2].com)
    assert np.all(com3 >= box[0] - tol) and np.all(com3 <= box[1] + tol)
    assert sol.report.min_eigenvalue >= 1e-6 - tol  # epsilon margin
    assert sol.cost > free.cost * 1.01  # the box was really active


def test_prior_decides_what_the_data_do_not_see(arm: Arm) -> None:
    _, _, r, z, rss = arm.data(samples=40, noise=0.5, seed=4)
    prior = {f"{f}1": v for f, v in zip(FIELDS13[:10], arm.chi[:10])}
    plain = consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss)
    sol = consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss, prior=prior, prior_weight=1.0)
    for name in ("XX1", "XY1", "XZ1", "YY1", "YZ1", "MX1", "MY1", "MZ1", "M1"):  # not in K at all
        assert np.all(arm.K[:, arm.names.index(name)] == 0)
        assert sol.standard[name] == pytest.approx(prior[name], abs=1e-4)
    assert abs(plain.standard["M1"] - prior["M1"]) > 1.0  # without the prior they go elsewhere
    # sol minimises fit + prior, so it can be no worse than plain on that sum; the slack covers
    # the two problems' different null-space tie-breaks (≤ δ·‖ν‖² ≈ 1e-6 · O(100) of rss).
    plain_prior_cost = sum((plain.standard[n] - v) ** 2 for n, v in prior.items())
    assert sol.cost + sol.prior_cost <= plain.cost + plain_prior_cost + 1e-3 * rss
    assert sol.prior_cost < 1e-2 * plain_prior_cost


def test_consistency_margin_answers_was_ols_consistent(arm: Arm) -> None:
    # Truth and good-data OLS have consistent representations (independent witness above);
    # poor-data OLS has a provably negative directly identified parameter.
    t_true, witness = consistency_margin(arm.beta, arm.K, arm.names)
    assert t_true > 0 and consistency_report(witness, arm.names).ok
    np.testing.assert_allclose(arm.K @ witness, arm.beta, atol=1e-8 * np.abs(arm.beta).max())
    assert consistency_report(witness, arm.names, margin=t_true / 2 * 0.99).ok  # margin t*/2 kept

    _, _, r, z, rss = arm.data(samples=400, noise=0.1, seed=0)
    assert consistency_margin(np.linalg.solve(r, z), arm.K, arm.names)[0] > 0
    _, _, r, z, rss = arm.data(samples=15, noise=5.0, seed=0)
    beta_ols = np.linalg.solve(r, z)
    assert arm.certificate(beta_ols)
    t_bad, _ = consistency_margin(beta_ols, arm.K, arm.names)
    assert t_bad < -1e-3
    # ... and then the consistent fit must pay for it.
    assert consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss).cost > rss * (1 + 1e-3)


def test_problem_size_does_not_depend_on_rows(arm: Arm) -> None:
    sizes = []
    for rows in (1_000, 100_000):
        rng = np.random.default_rng(rows)
        wb = rng.normal(size=(rows, arm.K.shape[0]))
        y = wb @ arm.beta + rng.normal(size=rows)
        r_aug = np.linalg.qr(np.column_stack([wb, y]), mode="r")
        built = build_consistent_problem(r_aug[:-1, :-1], r_aug[:-1, -1], arm.K, arm.names)
        m = built.problem.size_metrics
        sizes.append((
            m.num_scalar_variables, m.num_scalar_eq_constr, m.num_scalar_leq_constr, m.max_data_dimension,
            tuple(c.shape for c in built.problem.constraints), built.problem.objective.args[0].shape,
        ))
    assert sizes[0] == sizes[1]


@pytest.mark.parametrize("case", [(15, 5.0, 0), (400, 0.1, 0)], ids=["active", "inactive"])
def test_clarabel_and_scs_agree(arm: Arm, case: tuple[int, float, int]) -> None:
    wb, _, r, z, rss = arm.data(*case)
    a = consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss, solver="CLARABEL")
    b = consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss, solver="SCS")
    assert a.report.ok and b.report.ok and (a.solver, b.solver) == ("CLARABEL", "SCS")
    # β* is unique (R non-singular), so the two must estimate the same thing. A difference is
    # irrelevant when far below the statistical uncertainty of β itself: with noise variance
    # σ² = rss/(r − c) the estimate's spread is ‖R(β̂ − β)‖ ≈ σ·√c. We ask for 1 % of that
    # (measured: 3e-6 and 1.5e-5 of it, SCS at 1e-7 plus its margin retry of ~1e-6).
    rows, c = wb.shape
    spread = np.sqrt(rss / (rows - c) * c)
    assert np.linalg.norm(r @ (a.beta - b.beta)) < 0.01 * spread
    assert abs(a.cost - b.cost) < 1e-4 * a.cost


def test_failed_solve_is_an_error_never_a_result(arm: Arm) -> None:
    _, _, r, z, rss = arm.data(samples=15, noise=5.0, seed=0)
    with pytest.raises(ConsistencyError) as info:
        consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss, solver_options={"max_iter": 2})
    assert info.value.status != "optimal" and info.value.solver == "CLARABEL"
    assert info.value.status in str(info.value)


def _flaky_solve(monkeypatch: pytest.MonkeyPatch, index: int, bad_calls: int) -> list[float]:
    """Make the first ``bad_calls`` solves come back 1e-7 outside the cone on χ[index]."""
    import identify.estimation.consistency.fit as module

    real, margins = module.solve_problem, []

    def flaky(built, solver, options):
        chi, seconds, iterations = real(built, solver, options)
        margins.append(built.epsilon)
        if len(margins) <= bad_calls:
            chi = chi.copy()
            chi[index] = -1e-7  # what an interior-point solve stopped just outside looks like
        return chi, seconds, iterations

    monkeypatch.setattr(module, "solve_problem", flaky)
    return margins


def test_external_check_failure_is_resolved_with_a_margin(arm: Arm, monkeypatch: pytest.MonkeyPatch) -> None:
    _, _, r, z, rss = arm.data(samples=15, noise=5.0, seed=0)
    margins = _flaky_solve(monkeypatch, arm.names.index("IA3"), bad_calls=1)
    sol = consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss)
    # Solved at ten times the default margin 1e-8, checked at 1e-8: IA3 = -1e-7 falls short by 1.1e-7.
    assert margins[0] == pytest.approx(1e-7) and margins[1] == pytest.approx(1e-7 + 10 * (1e-7 + 1e-8))
    assert sol.retried and sol.epsilon == margins[1] and sol.report.ok and sol.report.margin == 1e-8
    assert sol.standard["IA3"] >= margins[1] * (1 - 1e-6)


def test_persistent_external_check_failure_raises(arm: Arm, monkeypatch: pytest.MonkeyPatch) -> None:
    _, _, r, z, rss = arm.data(samples=15, noise=5.0, seed=0)
    margins = _flaky_solve(monkeypatch, arm.names.index("FV2"), bad_calls=99)
    with pytest.raises(ConsistencyError, match="FV2") as info:
        consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss)
    assert info.value.status == "external_check_failed" and len(margins) == 3


def test_loose_scs_never_returns_an_inconsistent_result(arm: Arm) -> None:
    # SCS at 1e-6 leaves the cones by ~1e-5 here: the external check must catch it every time.
    _, _, r, z, rss = arm.data(samples=15, noise=5.0, seed=0)
    options = {"eps_abs": 1e-6, "eps_rel": 1e-6}
    try:
        sol = consistent_least_squares(r, z, arm.K, arm.names, rss_outside=rss, solver="SCS", solver_options=options)
    except ConsistencyError as exc:
        assert exc.solver == "SCS" and exc.status != "optimal"
    else:
        assert sol.report.ok and sol.report.min_eigenvalue >= -1e-9 and sol.retried


def test_bad_input_is_refused(arm: Arm) -> None:
    _, _, r, z, _ = arm.data(samples=30, noise=0.5, seed=5)
    with pytest.raises(ValueError, match="K"):
        consistent_least_squares(r, z, arm.K[:, :-1], arm.names)
    with pytest.raises(ValueError, match="prior"):
        consistent_least_squares(r, z, arm.K, arm.names, prior={"XX9": 1.0}, prior_weight=1.0)
    with pytest.raises(ValueError, match="mass_bounds"):
        consistent_least_squares(r, z, arm.K, arm.names, mass_bounds={7: (0.0, 1.0)})
    with pytest.raises(ValueError, match="solver"):
        consistent_least_squares(r, z, arm.K, arm.names, solver="MOSEK")
