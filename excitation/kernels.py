"""The excitation NLP's per-sample functions compiled to C, cached on disk.

IPOPT's iterations evaluate a few small functions at every grid sample: the weighted regressor
and its adjoint (the criterion), the envelope's rows and their Jacobian, the motor torques and
their Jacobian. In CasADi's virtual machine they dominate each iteration; compiled they run 3-10x
faster. The shared libraries are cached by the hash of their source
(rx90sym.compiled.shared_library), so a robot's kernels are compiled once per machine (and per
noise, friction smoothing and envelope settings, which are constants in them). Without a C
compiler the same functions run in CasADi's VM (same numbers, slower), with one warning.
"""
from __future__ import annotations

import subprocess
import warnings
from typing import Any

import casadi as ca

import numpy as np

#: gcc -Og: as fast as -O1 or -O2 on these straight-line functions (the UR5 envelope Jacobian,
#: 19k instructions: 1.25 ms for 111 samples against 12 ms in the VM) at a fraction of the
#: compile time (4 s of CPU against 6.5 s at -O1 and 10 s at -O2).
FLAGS = ("-Og",)


def compiled_kernel(f: ca.Function, compile: bool = True) -> ca.Function:
    """``f`` as C loaded with casadi.external (same inputs and outputs, no derivatives: callers
    give their own Jacobian), or ``f`` itself when ``compile`` is False or no compiler builds it
    (with a RuntimeWarning)."""
    if not compile:
        return f
    from rx90sym.compiled import shared_library  # the project's compile cache

    cg = ca.CodeGenerator(f"{f.name()}.c", {"with_header": False})
    cg.add(f)
    try:
        return ca.external(f.name(), str(shared_library(cg.dump(), f"excitation_{f.name()}", FLAGS)))
    except (OSError, RuntimeError, subprocess.SubprocessError) as exc:
        warnings.warn(f"{f.name()}: C compilation unavailable ({exc}); using CasADi's VM (slower)",
                      RuntimeWarning, stacklevel=2)
        return f


def symbols_like(f: ca.Function) -> list[Any]:
    """SX input symbols when f can be evaluated on SX (fast virtual machine), else MX."""
    try:
        return f.sx_in()
    except Exception:  # MX-only functions (e.g. with callbacks)
        return f.mx_in()


def dense(f: ca.Function) -> ca.Function:
    """``f`` (its first output) with a dense output, as a SampleKernel needs."""
    if f.sparsity_out(0).is_dense():
        return f
    sym = symbols_like(f)
    return ca.Function(f"{f.name()}_dense", sym, [ca.densify(f(*sym)[0] if f.n_out() > 1 else f(*sym))])


def evaluate_samples(f: ca.Function, *inputs: np.ndarray) -> np.ndarray:
    """f's first output on N samples, inputs (N, size_k) -> (N, rows, cols), in CasADi's VM
    without the DM -> numpy conversion (0.6 us per number: most of the time of a 1 kHz check)."""
    n_samples = np.shape(inputs[0])[0]
    if n_samples == 0:
        return np.zeros((0, f.size1_out(0), f.size2_out(0)))
    return SampleKernel(dense(f), n_samples, compile=False)(*inputs).transpose(0, 2, 1)


#: OpenBLAS runs a product on several threads when m n k >= 4 x 65536 (GEMM_MULTITHREAD_THRESHOLD x
#: SMP_THRESHOLD_MIN); for the information matrix those threads cost 35x the CPU time and 20x the
#: wall time of one thread on a loaded 2-core machine (spin-waits: 13 ms against 0.38 ms CPU for a
#: 2400 x 52 block), so :func:`gram` stays below it.
_ONE_THREAD = 4 * 65536


def gram(rows: np.ndarray) -> np.ndarray:
    """rows^T rows (k, k) for rows (N, k), summed in blocks small enough for BLAS to use one
    thread (an optimisation runs on one core; Dask spreads the starts)."""
    k = rows.shape[1]
    block = max(1, _ONE_THREAD // max(k * k, 1) - 1)
    out = np.zeros((k, k))
    for i in range(0, rows.shape[0], block):
        part = rows[i:i + block]
        out += part.T @ part
    return out


class SampleKernel:
    """A one-output function on N samples held in numpy arrays, without copies
    (casadi.Function.buffer): inputs (N, size_k) -> output (N, cols, rows) (sample k's output
    matrix in CasADi's column-major order, so an output Phi^T (nb x n) reads as Phi (N, n, nb)).
    The C is compiled without OpenMP: IPOPT calls it every iteration on a few hundred samples,
    where rx90sym's OpenMP batches spent 5x the CPU time in thread start and spin-waits on a
    loaded 2-core machine. The output array is reused: each call overwrites the last result."""

    def __init__(self, f: ca.Function, n_samples: int, compile: bool = True) -> None:
        if not all(f.sparsity_in(k).is_dense() for k in range(f.n_in())) or not f.sparsity_out(0).is_dense():
            raise ValueError(f"{f.name()}: a sample kernel needs dense inputs and output (ca.densify)")
        self.sizes = [f.size1_in(k) * f.size2_in(k) for k in range(f.n_in())]
        self.out = np.zeros((n_samples, f.size2_out(0), f.size1_out(0)))
        self.mapped = compiled_kernel(f, compile).map(n_samples, "serial")
        self._buffer, self._evaluate = self.mapped.buffer()
        self._buffer.set_res(0, memoryview(self.out))

    def __call__(self, *inputs: np.ndarray) -> np.ndarray:
        arrays = [np.ascontiguousarray(a, dtype=float) for a in inputs]
        for k, (a, size) in enumerate(zip(arrays, self.sizes)):
            if a.shape != (self.out.shape[0], size):
                raise ValueError(f"{self.mapped.name()}: input {k} must be {(self.out.shape[0], size)}, "
                                 f"got {a.shape}")
            self._buffer.set_arg(k, memoryview(a))
        self._evaluate()
        return self.out
