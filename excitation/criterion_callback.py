"""The excitation criterion as a CasADi callback: compiled regressor samples and a BLAS Gram matrix.

IPOPT evaluates the criterion f(G(x)) and its gradient every iteration, where (objective.py)

    G = (1/N) sum_k Phi_k^T Phi_k,    Phi_k = diag(w) Phi_b,smooth(q_k, qd_k, qdd_k)   (eqs. 7-8, 15)

on the N grid samples, q_k = Bq_k C etc. linear in the decision vector x (C = rest Z, x =
Z.flatten("F")). In one CasADi graph the regressor runs in the VM and the product W^T W, a dense
(nb x nN) by (nN x nb) product, in CasADi's own loops: 5.5 ms for f and 19 ms for its gradient on
the UR5 (400 samples, 52 parameters), a third of each IPOPT iteration. Here the samples come from
compiled C (kernels.py), G from one BLAS product, and the gradient by the chain rule:

    Gbar = df/dG (CasADi, on the nb x nb matrix only),  Phibar_k = (1/N) Phi_k (Gbar + Gbar^T),
    (qbar_k, qdbar_k, qddbar_k) = the regressor's adjoint at sample k applied to Phibar_k (compiled),
    xbar = vec(rest^T (Bq^T Qbar + Bd^T Qdbar + Bdd^T Qddbar)).

Exact (no approximation): the same function and derivative as the graph, to rounding.
"""
from __future__ import annotations

import re
from typing import Any, Sequence

import casadi as ca
import numpy as np

from .kernels import SampleKernel, gram


class _Samples:
    """The regressor on the grid for one decision vector at a time (the last one is kept: IPOPT
    asks for f and its gradient at the same point)."""

    def __init__(self, regressor: ca.Function, bases: Sequence[np.ndarray], n: int, name: str,
                 compile: bool) -> None:
        self.bases = [np.ascontiguousarray(b, dtype=float) for b in bases]  # (N, m) each
        self.n, self.m = n, self.bases[0].shape[1]
        sym = regressor.sx_in()
        phi = regressor(*sym)
        self.nb = phi.shape[1]
        seed = ca.SX.sym("phibar_t", self.nb, n)  # Phibar^T: read as Phibar (N, n, nb)
        adjoint = ca.densify(ca.gradient(ca.sum1(ca.sum2(seed * phi.T)), ca.vertcat(*sym)))  # (3n,): q, qd, qdd
        n_samples = self.bases[0].shape[0]
        opts = {"cse": True}
        self.phi = SampleKernel(ca.Function(f"{name}_phi", list(sym), [ca.densify(phi.T)], opts), n_samples,
                                compile)
        self.adjoint = SampleKernel(ca.Function(f"{name}_adj", [*sym, seed], [adjoint], opts), n_samples, compile)
        self._x: bytes | None = None
        self._phi = self._gram = np.zeros(0)
        self._samples: list[np.ndarray] = []

    def at(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(Phi (N, n, nb), G (nb, nb)) at x."""
        key = x.tobytes()
        if key != self._x:
            z = x.reshape(self.m, self.n, order="F")
            self._samples = [b @ z for b in self.bases]  # (N, n) each
            self._phi = self.phi(*self._samples)  # (N, n, nb), overwritten at the next x
            self._gram = gram(self._phi.reshape(-1, self.nb)) / self._phi.shape[0]
            self._x = key
        return self._phi, self._gram

    def pullback(self, x: np.ndarray, gbar: np.ndarray) -> np.ndarray:
        """xbar (m n,) of the scalar whose derivative with respect to G is gbar (nb, nb)."""
        phi, _ = self.at(x)
        n_samples = phi.shape[0]
        phibar = phi @ ((gbar + gbar.T) / n_samples)  # (N, n, nb)
        adj = self.adjoint(*self._samples, phibar.reshape(n_samples, -1)).reshape(n_samples, len(self.bases), self.n)
        zbar = sum(b.T @ adj[:, i, :] for i, b in enumerate(self.bases))  # (m, n)
        return zbar.flatten(order="F")


class _OfX(ca.Callback):
    """A callback of the dense decision vector x (nx,) with one dense output (rows,)."""

    def __init__(self, name: str, nx: int, rows: int) -> None:
        ca.Callback.__init__(self)
        self.nx, self.rows = nx, rows
        self.construct(name, {})

    def get_n_in(self) -> int:
        return 1

    def get_n_out(self) -> int:
        return 1

    def get_sparsity_in(self, i: int) -> ca.Sparsity:
        return ca.Sparsity.dense(self.nx, 1)

    def get_sparsity_out(self, i: int) -> ca.Sparsity:
        return ca.Sparsity.dense(self.rows, 1)


class _Gradient(_OfX):
    """x -> df/dx (m n,) of one stage."""

    def __init__(self, name: str, stage: "CriterionCallback") -> None:
        self.stage = stage
        super().__init__(name, stage.nx, stage.nx)

    def eval(self, arg: Any) -> list[np.ndarray]:
        x = np.array(arg[0].nonzeros())  # dense: faster than np.asarray(DM)
        _, g_mean = self.stage.samples.at(x)
        try:
            gbar = np.asarray(self.stage.derivative(g_mean))
        except RuntimeError:  # G singular: an evaluation error for IPOPT, as in the one graph
            return [np.full(self.stage.nx, np.nan)]
        return [self.stage.samples.pullback(x, gbar)]


class CriterionCallback(_OfX):
    """x -> criterion of one stage (scalar), with an exact reverse derivative."""

    def __init__(self, name: str, samples: _Samples, value: ca.Function, derivative: ca.Function) -> None:
        self.samples, self.value, self.derivative = samples, value, derivative
        self._gradient: _Gradient | None = None
        self._reverse: ca.Function | None = None
        super().__init__(name, samples.m * samples.n, 1)

    def eval(self, arg: Any) -> list[Any]:
        _, g_mean = self.samples.at(np.array(arg[0].nonzeros()))
        try:
            return [self.value(g_mean)]
        except RuntimeError:  # G singular (a motionless trial point): IPOPT cuts its step back
            return [np.nan]

    def has_reverse(self, nadj: int) -> bool:
        return nadj == 1

    def get_reverse(self, nadj: int, name: str, inames: list[str], onames: list[str],
                    opts: dict) -> ca.Function:
        self._gradient = _Gradient(f"{name}_gradient", self)  # kept alive with the callback
        x, out, seed = ca.MX.sym("x", self.nx), ca.MX.sym("out", 1, 1), ca.MX.sym("seed", 1, 1)
        self._reverse = ca.Function(name, [x, out, seed], [seed * self._gradient(x)], inames, onames, opts)
        return self._reverse


def criterion_callbacks(regressor: ca.Function, objective: Any, stages: Sequence[int], bases: Sequence[np.ndarray],
                        n: int, duration: float, name: str, compile: bool = True) -> list[CriterionCallback]:
    """One callback per stage p of ``stages``: x -> objective.expression(G(x), p) (see the module
    docstring). regressor: the weighted, smoothed base regressor (SX-evaluable); bases: the
    (N, m) matrices mapping free coefficients to q, qd and qdd on the grid; duration [s]."""
    label = re.sub(r"\W", "_", name)
    samples = _Samples(regressor, bases, n, f"excitation_{label}", compile)
    g = ca.MX.sym("G", samples.nb, samples.nb)
    out = []
    for k, p in enumerate(stages):
        f = objective.expression(objective.information(g, duration), p)
        value = ca.Function(f"criterion_{k}", [g], [f])
        derivative = ca.Function(f"criterion_{k}_dG", [g], [ca.gradient(f, g)])
        out.append(CriterionCallback(f"criterion_{label}_{k}", samples, value, derivative))
    return out


def evaluable_on_sx(f: ca.Function) -> bool:
    """Whether f can be evaluated on SX symbols (needed to compile its samples)."""
    try:
        f.sx_in()
        return True
    except Exception:  # MX-only functions (e.g. with callbacks)
        return False
