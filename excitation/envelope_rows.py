"""The safety envelope's nonlinear rows for IPOPT, with a Jacobian through the joint samples.

Per constraint sample t_k the envelope gives a few smooth rows of (q_k, qd_k) (:func:`sample_rows`):
the lowest point's height (a soft minimum over the points), the capsule clearances (one soft
minimum over every capsule pair and box, or one row per pair) and the fastest point's squared
Cartesian speed (a soft maximum). The joint samples are linear in the decision vector x (the free
coefficients Z): q_k = S_k Z, qd_k = S'_k Z. Left to CasADi's algorithmic differentiation, the
Jacobian of N such rows with respect to the n * m entries of x costs n * m directional derivatives
of every row (each row depends on every coefficient); by the chain rule it is

    d rows_k / d z_j = (d rows_k / d q_kj) S_k + (d rows_k / d qd_kj) S'_k,

n directional derivatives per sample and a product with the constant S_k, S'_k: m times fewer
(m = 9 for 5 harmonics). :func:`through_samples` gives CasADi that Jacobian (exact, its own AD
per sample) as the function's custom Jacobian; nothing else changes in what IPOPT sees. The
motor torques' rows (constraints.torque_rows, functions of q_k, qd_k and qdd_k) go the same way.
The per-sample functions and their Jacobians run as compiled C (kernels.py).

Soft extremes are conservative: the soft minimum is never above the true minimum and the soft
maximum never below the true maximum (at most temperature x log(count) away).
"""
from __future__ import annotations

from typing import Sequence

import casadi as ca
import numpy as np

from .kernels import compiled_kernel, symbols_like
from .model import ExcitationModel

HEIGHT_SOFTNESS = 0.002  # [m]: the lowest point's soft minimum is at most 2 mm x log(count) low
SPEED_SOFTNESS = 0.005   # [m^2/s^2]: the fastest point's soft maximum of squared speeds
SPEED_MARGIN = 0.05      # fraction of the Cartesian speed limit kept on the constraint grid
CLEARANCE_SOFTNESS = 0.002  # [m]: soft minimum over the capsule pairs (collision.SOFT_MIN's scale)


def smooth_extreme(f: ca.Function, k: float) -> ca.Function:
    """One smooth row instead of one per point: k log sum exp(v / k) of f's outputs, never below
    their maximum (k > 0) or, k < 0, never above their minimum: conservative, and IPOPT's linear
    algebra no longer grows with the number of points (20 height rows per sample made a 10 s UR5
    start 9x slower)."""
    sym = [ca.SX.sym(f.name_in(i), f.size1_in(i)) for i in range(f.n_in())]
    v = f(*sym)
    if v.shape[0] == 1:
        return f
    return ca.Function(f"{f.name()}_extreme", sym, [k * ca.logsumexp(v / k)], f.name_in(), ["extreme"])


def sample_rows(model: ExcitationModel, velocity_margin: float, height_margin: float,
                clearance_margin: float, pairs_per_row: bool = False
                ) -> tuple[ca.Function, np.ndarray, np.ndarray] | None:
    """(f, lo, hi): the envelope's rows at one sample, f(q [rad], qd [rad/s]) -> (r,), with their
    bounds: lowest height >= z_min + height_margin [m]; clearance >= clearance_margin [m] (one
    soft minimum over the pairs and boxes, or one row each with ``pairs_per_row``); squared
    speed of the fastest point <= ((1 - max(velocity_margin, SPEED_MARGIN)) speed_max)^2. None
    when the model has no envelope."""
    q, qd = ca.SX.sym("q", model.n), ca.SX.sym("qd", model.n)
    rows, lo, hi = [], [], []
    if model.heights is not None and model.z_min is not None:
        rows.append(smooth_extreme(model.heights, -HEIGHT_SOFTNESS)(q))
        lo.append([model.z_min + height_margin])
        hi.append([np.inf])
    clearance = None if model.collision is None else model.collision.clearance
    if clearance is not None:
        c = clearance(q) if pairs_per_row else smooth_extreme(clearance, -CLEARANCE_SOFTNESS)(q)
        rows.append(c)
        lo.append(np.full(c.shape[0], clearance_margin))
        hi.append(np.full(c.shape[0], np.inf))
    if model.speeds is not None:
        # Cartesian speeds are not band-limited like the joint motion (the Bernstein bound of
        # constraints.kinematic_grid_rate does not cover them): 5 % kept on the grid (2 % let the
        # TX40's tool reach 1.0024 m/s between grid points on the 1 kHz check).
        rows.append(smooth_extreme(model.speeds, SPEED_SOFTNESS)(q, qd))
        keep = max(velocity_margin, SPEED_MARGIN)
        lo.append([-np.inf])
        hi.append([((1.0 - keep) * model.speed_max) ** 2])
    if not rows:
        return None
    f = ca.Function("envelope_sample", [q, qd], [ca.vertcat(*rows)], ["q", "qd"], ["rows"])
    return f, np.concatenate(lo).astype(float), np.concatenate(hi).astype(float)


def through_samples(f: ca.Function, bases: Sequence[np.ndarray], n: int, compile: bool = False) -> ca.Function:
    """x -> rows (r N,): f at every sample, sample-major (sample k's r rows together), for x =
    Z.flatten(order="F"), Z (m, n), input i of f at sample k = bases[i][k] @ Z (bases: one (N, m)
    matrix per input of f, e.g. q and qd, or q, qd and qdd for the torques). Its Jacobian is the
    chain rule of the module docstring (f's own exact AD per sample). compile: f and its
    per-sample Jacobian as compiled C (kernels.py; the same numbers to rounding)."""
    bases = [np.asarray(b, float) for b in bases]
    if len(bases) != f.n_in():
        raise ValueError(f"{f.name()}: {len(bases)} sample bases for {f.n_in()} inputs")
    n_samples, m = bases[0].shape
    r = f.size1_out(0)
    x = ca.MX.sym("x", m * n)
    z = ca.reshape(x, m, n)
    inputs = [ca.mtimes(ca.DM(b), z).T for b in bases]  # (n, N) each
    sym = symbols_like(f)
    out = f(*sym)
    # cse: the common subexpressions of the ball distances' derivatives (12 % fewer instructions)
    rows = compiled_kernel(ca.Function(f"{f.name()}_rows", sym, [out], {"cse": True}), compile)
    df = compiled_kernel(ca.Function(f"{f.name()}_jac", sym, [ca.jacobian(out, s) for s in sym],
                                     {"cse": True}), compile)
    g = ca.vec(rows.map(n_samples, "serial")(*inputs))
    jacs = df.map(n_samples, "serial")(*inputs)  # (r, n N) each: sample k's block in columns k n ...
    reps = [ca.DM(np.repeat(b, r, axis=0)) for b in bases]  # (r N, m)
    blocks = []
    for j in range(n):
        block = [ca.repmat(ca.vec(jac[:, j::n]), 1, m) * rep for jac, rep in zip(jacs, reps)]  # d rows / d z_j
        blocks.append(block[0] if len(block) == 1 else sum(block[1:], block[0]))
    name = f"{f.name()}_samples"
    jac = ca.Function(f"jac_{name}", [x, ca.MX.sym("out_rows", g.shape[0])], [ca.horzcat(*blocks)],
                      ["x", "out_rows"], ["jac_rows_x"])
    return ca.Function(name, [x], [g], ["x"], ["rows"],
                       {"custom_jacobian": jac, "jac_penalty": 0})
