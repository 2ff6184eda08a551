"""Compiled evaluation of CasADi functions over many samples, and C export.

CasADi generates the C of one sample; a small loop written here runs it over N samples reading
and writing NumPy buffers in place (no per-sample Python, no DM conversion). The shared library
is cached on disk by the hash of its source. Without a C compiler, evaluation falls back to
CasADi's virtual machine through ``Function.map`` (same numbers, slower).
"""
from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
import warnings
from dataclasses import fields
from pathlib import Path
from typing import Any, Iterator, Sequence

import casadi as ca
import numpy as np

_LOOP = r"""
#include <stdlib.h>
/* Runs {name} on N samples; samples are split between threads when built with OpenMP. */
int {name}_batch(long long N, const double** inputs, const long long* in_sizes,
                 double* out, long long out_size) {{
  int failed = 0;
  #pragma omp parallel reduction(|:failed)
  {{
    casadi_int sz_arg, sz_res, sz_iw, sz_w;
    {name}_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
    const casadi_real** arg = (const casadi_real**) malloc(sizeof(void*) * (sz_arg + 1));
    casadi_real** res = (casadi_real**) malloc(sizeof(void*) * (sz_res + 1));
    casadi_int* iw = (casadi_int*) malloc(sizeof(casadi_int) * (sz_iw + 1));
    casadi_real* w = (casadi_real*) malloc(sizeof(casadi_real) * (sz_w + 1));
    if (!arg || !res || !iw || !w) failed = 1;
    /* Dynamic blocks: on a loaded machine a descheduled thread holds back only its current
       block, not a fixed half of the samples (static halves ran 2x slower than one thread). */
    #pragma omp for schedule(dynamic, 128)
    for (long long i = 0; i < N; ++i) {{
      if (failed) continue;
      for (int k = 0; k < {n_in}; ++k) arg[k] = inputs[k] + i * in_sizes[k];
      res[0] = out + i * out_size;
      if ({name}(arg, res, iw, w, 0)) failed = 1;
    }}
    free(arg); free(res); free(iw); free(w);
  }}
  return failed;
}}
"""


def cache_dir() -> Path:
    """Where compiled libraries are kept: $RX90SYM_CACHE or ~/.cache/rx90sym."""
    root = os.environ.get("RX90SYM_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "rx90sym")
    path = Path(root)
    path.mkdir(parents=True, exist_ok=True)
    return path


def _c_compiler() -> str | None:
    return os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")


def shared_library(source: str, name: str, flags: Sequence[str] = ("-O2",)) -> Path:
    """Compile C source into a shared library in the cache (keyed by source, flags, compiler).

    Raises RuntimeError when there is no compiler or it fails."""
    cc = _c_compiler()
    if cc is None:
        raise RuntimeError("no C compiler found (set CC)")
    flags = ["-shared", "-fPIC", *flags]
    key = hashlib.sha256((source + " ".join(flags) + cc).encode()).hexdigest()[:20]
    lib_path = cache_dir() / f"{name}_{key}.so"
    if not lib_path.exists():
        with tempfile.TemporaryDirectory(dir=cache_dir()) as tmp:
            c_path = Path(tmp) / f"{name}.c"
            c_path.write_text(source)
            tmp_lib = Path(tmp) / "lib.so"
            proc = subprocess.run([cc, *flags, str(c_path), "-o", str(tmp_lib), "-lm"],
                                  capture_output=True, text=True, timeout=600)
            if proc.returncode != 0:
                raise RuntimeError(f"{cc} failed: {proc.stderr.strip()[:500]}")
            os.replace(tmp_lib, lib_path)  # atomic: concurrent builders never see half a file
    return lib_path


def compiled_function(f: ca.Function) -> ca.Function:
    """``f`` as generated C loaded with casadi.external (cached), or ``f`` itself with a warning
    when no C compiler can build it (CasADi's VM gives the same numbers, slower)."""
    cg = ca.CodeGenerator(f"{f.name()}.c", {"with_header": False})
    cg.add(f)
    try:
        return ca.external(f.name(), str(shared_library(cg.dump(), f.name())))
    except (OSError, RuntimeError, subprocess.SubprocessError) as exc:
        warnings.warn(f"{f.name()}: C compilation unavailable ({exc}); using CasADi's VM",
                      RuntimeWarning, stacklevel=2)
        return f


def map_samples(f: ca.Function, *inputs: np.ndarray) -> np.ndarray:
    """A one-output function on N samples through CasADi's VM (no compilation):
    inputs (N, size_k) -> (N, rows, cols). For repeated or large evaluations use BatchFunction."""
    N = np.shape(inputs[0])[0]
    out = f.map(N, "serial")(*[np.asarray(x, dtype=float).T for x in inputs]).full()
    # map() concatenates the samples' rows x cols blocks horizontally.
    return out.reshape(f.size1_out(0), N, f.size2_out(0)).transpose(1, 0, 2)


def _has_openmp(cc: str) -> bool:
    """Whether the compiler accepts -fopenmp (gcc does; plain clang on macOS may not): tried once
    per compiler, the answer kept in the cache beside the libraries (a compile costs ~50 ms)."""
    marker = cache_dir() / f"openmp_{hashlib.sha256(cc.encode()).hexdigest()[:20]}"
    if marker.exists():
        return marker.read_text().strip() == "1"
    with tempfile.TemporaryDirectory(dir=cache_dir()) as tmp:
        src = Path(tmp) / "omp.c"
        src.write_text("#include <omp.h>\nint f(void) { return omp_get_max_threads(); }\n")
        proc = subprocess.run([cc, "-fopenmp", "-shared", "-fPIC", str(src), "-o", str(Path(tmp) / "omp.so")],
                              capture_output=True, timeout=60)
        partial = Path(tmp) / "answer"
        partial.write_text("1" if proc.returncode == 0 else "0")
        os.replace(partial, marker)  # atomic: a concurrent run reads a whole answer or none
        return proc.returncode == 0


def _dense_row_major(f: ca.Function, name: str) -> ca.Function:
    """Same function with every input a dense column and the (only) output dense and transposed,
    so a sample's output lands in memory in row-major order."""
    if f.n_out() != 1:
        raise ValueError(f"{f.name()}: batch evaluation needs exactly one output")
    args = [ca.SX.sym(f.name_in(k), f.size1_in(k) * f.size2_in(k)) for k in range(f.n_in())]
    shaped = [ca.reshape(a, f.size1_in(k), f.size2_in(k)) for k, a in enumerate(args)]
    out = f.call(shaped)[0]
    # Common subexpression elimination: ~15 % fewer operations on the regressor.
    return ca.Function(name, args, [ca.cse(ca.densify(out.T))])


class PickledFields:
    """Mixin of a frozen dataclass holding cached CasADi functions (functools.cached_property):
    pickles its fields only, so the caches are rebuilt on first use (pickling for Dask workers)."""

    def __getstate__(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in fields(self)}  # type: ignore[arg-type]

    def __setstate__(self, state: dict[str, Any]) -> None:
        for key, value in state.items():
            object.__setattr__(self, key, value)


class BatchFunction:
    """Evaluate a one-output CasADi function on N samples: inputs (N, size_k) -> (N, rows, cols).

    ``compile=True`` generates C and builds a shared library with the system compiler (cached);
    if that is impossible, CasADi's VM is used and a warning says so.
    """

    def __init__(self, f: ca.Function, name: str | None = None, compile: bool = True) -> None:
        self.name = (name or f.name()).replace("-", "_")
        self.f = _dense_row_major(f, self.name)
        self.in_sizes = [self.f.size1_in(k) for k in range(self.f.n_in())]
        self.out_shape = (f.size1_out(0), f.size2_out(0))
        self._lib = None
        self.backend = "casadi-vm"
        if compile:
            try:
                self._lib = self._build()
                self.backend = "compiled-c"
            except (OSError, RuntimeError, subprocess.SubprocessError) as exc:
                warnings.warn(f"{self.name}: C compilation unavailable ({exc}); using CasADi's VM",
                              RuntimeWarning, stacklevel=2)

    def _build(self) -> ctypes.CDLL:
        cc = _c_compiler()
        if cc is None:
            raise RuntimeError("no C compiler found (set CC)")
        cg = ca.CodeGenerator(f"{self.name}.c", {"with_header": False, "casadi_int": "long long int"})
        cg.add(self.f)
        source = cg.dump() + _LOOP.format(name=self.name, n_in=self.f.n_in())
        flags = ["-O3"] + (["-fopenmp"] if _has_openmp(cc) else [])
        lib_path = shared_library(source, self.name, flags)
        lib = ctypes.CDLL(str(lib_path))
        fn = getattr(lib, f"{self.name}_batch")
        fn.restype = ctypes.c_int
        fn.argtypes = [ctypes.c_longlong, ctypes.POINTER(ctypes.c_void_p),
                       ctypes.POINTER(ctypes.c_longlong), ctypes.c_void_p, ctypes.c_longlong]
        return lib

    def __call__(self, *inputs: Any, out: np.ndarray | None = None) -> np.ndarray:
        """Evaluate on N samples; ``out`` (N, rows, cols) float64 C-contiguous is filled in place
        when given (saves the page faults of a fresh large array on repeated calls)."""
        if len(inputs) != len(self.in_sizes):
            raise ValueError(f"{self.name}: expected {len(self.in_sizes)} input arrays, got {len(inputs)}")
        arrays = []
        N = None
        for k, (x, size) in enumerate(zip(inputs, self.in_sizes)):
            a = np.ascontiguousarray(np.asarray(x, dtype=float).reshape(-1, size) if np.ndim(x) != 2
                                     else np.asarray(x, dtype=float))
            if a.ndim != 2 or a.shape[1] != size:
                raise ValueError(f"{self.name}: input {k} must have shape (N, {size}), got {np.shape(x)}")
            if N is None:
                N = a.shape[0]
            elif a.shape[0] != N:
                raise ValueError(f"{self.name}: inputs have different numbers of samples ({N} and {a.shape[0]})")
            arrays.append(a)
        rows, cols = self.out_shape
        if out is None:
            out = np.empty((N, rows, cols))
        elif out.shape != (N, rows, cols) or out.dtype != np.float64 or not out.flags.c_contiguous:
            raise ValueError(f"{self.name}: out must be a C-contiguous float64 array of shape "
                             f"{(N, rows, cols)}")
        if N == 0:
            return out
        if self._lib is None:
            mapped = self.f.map(N, "serial")
            res = mapped(*[a.T for a in arrays])
            out[...] = res.full().T.reshape(N, rows, cols)  # DM -> ndarray explicitly (casadi 3.8)
            return out
        ptrs = (ctypes.c_void_p * len(arrays))(*[a.ctypes.data for a in arrays])
        sizes = (ctypes.c_longlong * len(arrays))(*self.in_sizes)
        flag = getattr(self._lib, f"{self.name}_batch")(N, ptrs, sizes, out.ctypes.data, rows * cols)
        if flag != 0:
            raise RuntimeError(f"{self.name}: compiled evaluation failed (code {flag})")
        return out


class BatchWorkspace:
    """A reused output buffer for a :class:`BatchFunction`, as Pinocchio's ``Data`` for its model.

    A fresh (N, rows, cols) array per call costs its page faults (a 40 MB regressor batch: about
    as long as the evaluation itself on two cores); a workspace pays them once and then reuses
    the memory. ``evaluate`` returns a view valid until the next call on the same workspace;
    ``chunks`` streams the samples through a small block of ``chunk`` samples that stays in
    cache. One workspace per thread: it is not shared safely between threads.
    """

    def __init__(self, batch: BatchFunction, chunk: int = 2048) -> None:
        if chunk < 1:
            raise ValueError(f"chunk must be >= 1, got {chunk}")
        self.batch = batch
        self.chunk = int(chunk)
        self._buffer = np.empty((0,) + batch.out_shape)

    def _view(self, N: int) -> np.ndarray:
        if self._buffer.shape[0] < N:
            self._buffer = np.empty((N,) + self.batch.out_shape)
        return self._buffer[:N]

    def evaluate(self, *inputs: Any) -> np.ndarray:
        """All N samples into the reused buffer: a (N, rows, cols) view, overwritten by the next call."""
        N = np.shape(inputs[0])[0]
        return self.batch(*inputs, out=self._view(N))

    def chunks(self, *inputs: Any) -> Iterator[tuple[int, np.ndarray]]:
        """Blocks of at most ``chunk`` samples: yields (first sample index, (m, rows, cols) view);
        each view is overwritten by the next block."""
        N = np.shape(inputs[0])[0]
        arrays = [np.asarray(x, dtype=float) for x in inputs]
        for start in range(0, N, self.chunk):
            stop = min(start + self.chunk, N)
            yield start, self.batch(*[a[start:stop] for a in arrays], out=self._view(stop - start))


def export_c(functions: Sequence[ca.Function], directory: str, prefix: str = "robot") -> list[str]:
    """Write the C source (and header) of CasADi functions into ``directory``; returns the paths.

    The code is self-contained (no CasADi runtime needed) and uses the CasADi calling
    convention documented in the header: ``f(arg, res, iw, w, mem)`` with ``f_work`` sizes.
    """
    out_dir = Path(directory)
    out_dir.mkdir(parents=True, exist_ok=True)
    cg = ca.CodeGenerator(f"{prefix}_model.c", {"with_header": True})
    for f in functions:
        cg.add(f)
    with tempfile.TemporaryDirectory(dir=out_dir) as tmp:
        cwd = os.getcwd()
        try:
            os.chdir(tmp)
            cg.generate()
        finally:
            os.chdir(cwd)
        paths = []
        for fname in sorted(os.listdir(tmp)):
            os.replace(os.path.join(tmp, fname), out_dir / fname)
            paths.append(str(out_dir / fname))
    return paths
