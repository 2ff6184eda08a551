"""BLAS on one thread inside the toolkit's calls, the caller's setting back after them.

The toolkit's linear algebra is tall and thin: least squares of tens of columns over thousands
of rows, many small QR factorisations. A second BLAS thread there spins and waits more than it
computes, and on a busy or many-core machine it costs far more than it gives (measured by
benchmarks/bench_library_vs_command.py, docs/reliability.md). So the public calls that do the work
(``identify.fit``, ``predict``, ``validate``, ``payload``, ``drive_gains``, ...) run inside
:func:`one_blas_thread`, and the ``rx90`` command applies the same rule to its whole process
(:func:`command_blas_threads`): one rule for the library and the command.

The rule, in order:

1. An environment variable naming the BLAS's thread count (:data:`BLAS_THREAD_VARIABLES`, e.g.
   ``OPENBLAS_NUM_THREADS=4`` or ``OMP_NUM_THREADS=4`` set before Python started) is the user's
   choice: the toolkit leaves the BLAS as it is.
2. Inside :func:`blas_threads` (the caller's own count) the toolkit's calls leave the BLAS as it is.
3. Otherwise the BLAS runs on one thread for the call (``threadpoolctl.threadpool_limits``); the
   count it had is back when the call returns or raises. A caller's own
   ``threadpoolctl.threadpool_limits(n)`` with n > 1 cannot be told from the BLAS's default and is
   replaced by one thread inside the call: use :func:`blas_threads` to keep it.

Nested calls (``fit`` inside ``payload``, ``predict`` inside ``validate``) limit once: an inner
call costs one context-variable read. Only the BLAS is limited: the compiled regressor's OpenMP
loop over samples (:mod:`rx90sym.compiled`) keeps its threads (dynamic blocks: a descheduled
thread holds back one block only). The limit is process-wide for OpenBLAS built with pthreads:
set by the first thread that limits it (threadpoolctl), so calls made from worker threads run
under the limit of the thread that set it. Dask workers started by a nanny get
``OPENBLAS_NUM_THREADS=1`` from Dask (rule 1).
"""
from __future__ import annotations

import contextlib
import contextvars
import os
import sys
from typing import Iterator

__all__ = ["BLAS_THREAD_VARIABLES", "blas_threads", "command_blas_threads", "explicit_blas_variable",
           "one_blas_thread"]

#: Environment variables a BLAS reads its thread count from (OpenBLAS, its GotoBLAS name, OpenMP
#: builds and OpenBLAS's fallback, MKL, BLIS): one set, not empty, is the user's choice.
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
                         "BLIS_NUM_THREADS")

#: What a command's own process sets to 1 before any BLAS loads (not OMP_NUM_THREADS: the compiled
#: regressor's OpenMP loop keeps its threads).
COMMAND_VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")

# True inside a limit already set (the toolkit's or the caller's blas_threads): calls leave the pool as it is.
_LIMITED = contextvars.ContextVar("rx90sym_blas_limited", default=False)


def explicit_blas_variable() -> str | None:
    """The first of :data:`BLAS_THREAD_VARIABLES` set in the environment (read at each call), or None."""
    return next((name for name in BLAS_THREAD_VARIABLES if os.environ.get(name, "").strip()), None)


@contextlib.contextmanager
def _limit(threads: int) -> Iterator[None]:
    # threadpoolctl acts on the libraries loaded when the limit is set: numpy's and scipy's BLAS
    # (two libraries) are loaded first, so that a module imported inside the call finds them limited.
    import numpy  # noqa: F401
    import scipy.linalg  # noqa: F401
    from threadpoolctl import threadpool_limits

    token = _LIMITED.set(True)
    try:
        with threadpool_limits(limits=threads, user_api="blas"):
            yield
    finally:
        _LIMITED.reset(token)


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """The toolkit's BLAS default for the block (or, as ``@one_blas_thread()``, the decorated
    call): one thread, unless an environment variable names the count or the caller chose it
    with :func:`blas_threads` (the rule in the module docstring); the caller's count back after it,
    also on an exception. Inside it, nested uses cost one context-variable read."""
    if _LIMITED.get() or explicit_blas_variable() is not None:
        yield
        return
    with _limit(1):
        yield


@contextlib.contextmanager
def blas_threads(threads: int) -> Iterator[None]:
    """Run numpy's and scipy's BLAS on ``threads`` threads inside the block, the toolkit's calls
    included (they keep this count instead of their one thread); the caller's count back after
    it, also on an exception. E.g. ``with rx90sym.blas_threads(8): identify.fit(...)``."""
    if int(threads) < 1:
        raise ValueError(f"blas_threads: threads must be >= 1, got {threads!r}")
    with _limit(int(threads)):
        yield


@contextlib.contextmanager
def command_blas_threads() -> Iterator[None]:
    """The same rule for a command's whole process (``rx90``). Before NumPy is loaded and with no
    variable naming the count, the process's own environment gets :data:`COMMAND_VARIABLES` = 1:
    every BLAS it loads afterwards starts on one thread (its child processes too), and nothing is
    imported for it (a threadpoolctl limit reaches only the libraries already loaded: it would load
    SciPy first, doubling the time of a light command such as ``rx90 model``). Once NumPy is loaded
    (the command run from Python): :func:`one_blas_thread` for the block."""
    if "numpy" in sys.modules or explicit_blas_variable() is not None:
        with one_blas_thread():
            yield
        return
    for name in COMMAND_VARIABLES:
        os.environ[name] = "1"
    yield
