"""Multi-start optimisation: starts run serially or through Dask, the best verified start wins.

Each start draws its initial point from its own generator (optimiser.start_rng(seed, index)), so a
start gives the same result whichever process or machine runs it and in whatever order; the winner
is the feasible start of smallest criterion value, ties broken by the smaller start number. The
run stops on the count of starts (and IPOPT's iteration limits); a wall-clock ``time_budget`` is
optional, off by default, and every start it skips is reported.

Dask: pass a ``dask.distributed.Client`` (a LocalCluster's or an existing scheduler's, see
:func:`dask_client`); the starts are sent in chunks, each chunk builds the NLP once on its worker.
"""
from __future__ import annotations

import contextlib
import sys
import time
from typing import Any, Iterator, TextIO

import numpy as np

from rx90sym.threads import one_blas_thread

from .model import ExcitationModel
from .optimiser import StartResult, run_starts
from .options import OptimiserOptions, check_request
from .trajectory import Form, SolveInfo, Trajectory


@one_blas_thread()
def optimise_model(model: ExcitationModel, form: Form, *, seed: int = 0, starts: int = 4,
                   time_budget: float | None = None, options: OptimiserOptions | None = None,
                   progress: bool | TextIO = True, client: Any = None) -> Trajectory:
    """Optimal excitation trajectory for a generic model; the best verified start is returned.

    seed (>= 0) and starts fix the result (same seed, same result, serial or through Dask).
    time_budget [s]: optional wall-clock budget over all starts (solves stop at the deadline,
    later starts are skipped and reported; the result then depends on the machine's speed).
    progress: True for a line per start on stderr, False for silence, or a text stream.
    client: a dask.distributed.Client to run the starts on its workers (None: in this process).
    Raises ValueError for requests that cannot be met (see optimiser.check_request) and when no
    start holds every limit on the fine grid and excites every base parameter.
    BLAS on one thread inside the call, the caller's count back after it (rx90sym.threads).
    """
    options = options or OptimiserOptions()
    if starts < 1:
        raise ValueError(f"starts must be >= 1, got {starts}")
    if int(seed) < 0:
        raise ValueError(f"seed must be >= 0, got {seed}")
    if time_budget is not None and not time_budget > 0.0:
        raise ValueError(f"time_budget must be > 0 s, got {time_budget:g}")
    check_request(model, form, options)
    stream = sys.stderr if progress is True else (progress or None)
    t_start = time.perf_counter()
    deadline = None if time_budget is None else time.time() + float(time_budget)
    indices = list(range(1, starts + 1))
    if client is None:
        results = run_starts(model, form, options, seed, indices, deadline,
                             on_result=lambda r: _print(stream, r, starts))
    else:
        results = _run_dask(client, model, form, options, seed, indices, deadline, stream, starts)
    return _best(model, form, options, seed, results, time.perf_counter() - t_start)


def _run_dask(client: Any, model: ExcitationModel, form: Form, options: OptimiserOptions, seed: int,
              indices: list[int], deadline: float | None, stream: TextIO | None,
              starts: int) -> list[StartResult]:
    from dask.distributed import as_completed

    workers = max(1, len(client.scheduler_info().get("workers", {})))
    size = max(1, int(np.ceil(len(indices) / (2 * workers))))  # two chunks per worker: balance
    chunks = [indices[i:i + size] for i in range(0, len(indices), size)]
    model_f, form_f, options_f = client.scatter([model, form, options], broadcast=True)
    futures = [client.submit(run_starts, model_f, form_f, options_f, seed, chunk, deadline, pure=False)
               for chunk in chunks]
    results: list[StartResult] = []
    for future in as_completed(futures):
        for result in future.result():
            results.append(result)
            _print(stream, result, starts)
    return sorted(results, key=lambda r: r.index)


def _print(stream: TextIO | None, r: StartResult, starts: int) -> None:
    if stream is None:
        return
    if r.skipped:
        print(f"[excitation] start {r.index}/{starts}: skipped ({r.skipped})", file=stream, flush=True)
        return
    print(f"[excitation] start {r.index}/{starts}: {r.iterations:4d} iterations, cond {r.cond:9.3f}, "
          f"score {r.score:9.4g}, feasible {'yes' if r.report.feasible else 'no '}, "
          f"{r.time_s:6.1f} s, {r.status}", file=stream, flush=True)


def _best(model: ExcitationModel, form: Form, options: OptimiserOptions, seed: int,
          results: list[StartResult], elapsed: float) -> Trajectory:
    ran = [r for r in results if not r.skipped]
    good = [r for r in ran if r.report.feasible and np.isfinite(r.score)]
    if not good:
        failures = [r.failure for r in ran if r.failure]
        raise ValueError(f"excitation: no start out of {len(ran)} holds every limit on the "
                         f"{options.verify_rate:g} Hz check and excites every base parameter "
                         f"({failures[-1] if failures else 'no start ran'}); the limits may be "
                         f"impossible to meet (e.g. torque limits below the static load or friction)")
    best = min(good, key=lambda r: (r.score, r.index))  # deterministic tie-break
    skipped = tuple(r.index for r in results if r.skipped)
    info = SolveInfo("ipopt multi-start", int(seed), len(ran), sum(r.report.feasible for r in ran),
                     best.iterations, sum(r.iterations for r in ran), elapsed, best.status,
                     best.surrogate_cond, options.grid_rate, best.index, skipped,
                     best.score)
    return Trajectory(form, best.coefficients, best.cond, options.criterion.name,
                      model.controller_offsets, best.report, info, options.cond_rate, model.names)


@contextlib.contextmanager
def dask_client(workers: int | None = None, scheduler: str | None = None,
                processes: bool = True) -> Iterator[Any]:
    """A dask.distributed Client: connected to ``scheduler`` (an address such as
    tcp://host:8786) or to a LocalCluster of ``workers`` single-threaded workers (processes, or
    threads with processes=False); closed on exit."""
    from dask.distributed import Client, LocalCluster

    if scheduler is not None:
        if workers is not None:
            raise ValueError("give either a scheduler address or a number of local workers, not both")
        try:
            client = Client(scheduler)
        except OSError as exc:  # refused, unreachable, timed out (Dask's connect timeout, 30 s by default)
            raise ValueError(f"Dask scheduler {scheduler}: cannot connect ({str(exc).splitlines()[0]}); start one "
                             f"there (`dask scheduler`, with workers) or give 'local' for workers on this "
                             f"machine") from None
        with client:
            yield client
        return
    if workers is None or workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    with LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=processes,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        yield client
