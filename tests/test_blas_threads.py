"""The library's BLAS rule (rx90sym.threads): one thread inside the fit's hot paths, the caller's
count back after the call (also when it raises), an explicit choice kept, nested calls limited once.

Each test sets the caller's count to 2 with threadpoolctl (numpy's and scipy's OpenBLAS both) and
reads the counts threadpoolctl reports from inside an inner function the public call runs.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
import scipy.linalg  # noqa: F401  (scipy's own BLAS loaded, so that both libraries are checked)
from threadpoolctl import threadpool_info, threadpool_limits

import identify
import rx90sym
import rx90sym.threads as threads
from identify.fitting import passes, validation

CALLER = 2


def blas_counts() -> list[int]:
    """The thread count of every BLAS library threadpoolctl sees that can run threads."""
    return [d["num_threads"] for d in threadpool_info()
            if d["user_api"] == "blas" and d.get("threading_layer") != "disabled"]


@pytest.fixture(scope="module")
def short_run():
    """A 6 s UR10e twin run at 100 Hz, and the fit's processing fixed (no choice: a fast fit)."""
    from motions import multisine

    robot = rx90sym.load_robot("ur10e")
    rec = rx90sym.twin.simulate(robot, multisine(robot, 0, duration=6.0), duration=6.0, rate=100.0,
                                noise="quantised", seed=0)
    return robot, rec, identify.Processing(cutoff=8.0, estimate_delay=False, cross_validate=False)


@pytest.fixture
def no_thread_variables(monkeypatch):
    """A process as a user starts one: no environment variable names the BLAS's thread count."""
    for name in threads.BLAS_THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)


@pytest.fixture
def caller_pool(no_thread_variables):
    """The caller's BLAS count set to 2 with threadpoolctl for the test (its own back after it):
    the counts it reads before the call."""
    with threadpool_limits(limits=CALLER, user_api="blas"):
        before = blas_counts()
        if not before or set(before) != {CALLER}:
            pytest.skip(f"this machine's BLAS does not take {CALLER} threads (threadpoolctl reads {before})")
        yield before


def recorder(monkeypatch, module, name: str, seen: list, fail: bool = False) -> None:
    """Replace ``module.name`` by a wrapper appending the BLAS counts to ``seen`` (then raising when ``fail``)."""
    inner = getattr(module, name)

    def wrapped(*args, **kwargs):
        seen.append(blas_counts())
        if fail:
            raise RuntimeError("inner failure")
        return inner(*args, **kwargs)

    monkeypatch.setattr(module, name, wrapped)


def test_fit_and_predict_run_blas_on_one_thread_and_give_the_caller_its_count_back(
        short_run, caller_pool, monkeypatch):
    robot, rec, processing = short_run
    in_fit, in_predict = [], []
    recorder(monkeypatch, passes, "solve_joint_systems", in_fit)
    recorder(monkeypatch, validation, "column_regressor", in_predict)
    before = caller_pool
    fit = identify.fit(robot, [rec], processing)
    between = blas_counts()
    fit.predict(rec)
    after = blas_counts()
    assert in_fit and all(c == [1] * len(before) for c in in_fit), in_fit
    assert in_predict and all(c == [1] * len(before) for c in in_predict), in_predict
    assert between == before and after == before


def test_the_callers_count_is_back_when_the_call_raises(short_run, caller_pool, monkeypatch):
    robot, rec, processing = short_run
    seen = []
    recorder(monkeypatch, passes, "solve_joint_systems", seen, fail=True)
    before = caller_pool
    with pytest.raises(RuntimeError, match="inner failure"):
        identify.fit(robot, [rec], processing)
    assert blas_counts() == before
    assert seen == [[1] * len(before)]


@pytest.mark.parametrize("choice", ["environment", "blas_threads"])
def test_an_explicit_choice_is_kept_inside_the_call(caller_pool, monkeypatch, choice):
    """OPENBLAS_NUM_THREADS in the environment (as the command honours it) or the caller's own
    rx90sym.blas_threads: the toolkit's rule (what the calls above run in) keeps the caller's count."""
    with threads.one_blas_thread():
        assert set(blas_counts()) == {1}  # the rule without a choice, for contrast
    if choice == "environment":
        monkeypatch.setenv("OPENBLAS_NUM_THREADS", str(CALLER))
        with threads.one_blas_thread():
            inside = blas_counts()
    else:
        with threadpool_limits(limits=1, user_api="blas"):  # a caller's plain limit, then its own choice
            with rx90sym.blas_threads(CALLER), threads.one_blas_thread():
                inside = blas_counts()
    assert inside == caller_pool, inside


def test_nested_calls_limit_once(short_run, no_thread_variables, monkeypatch):
    """fit_fleet runs fit per robot: the pool is limited once, by the outer call."""
    robot, rec, processing = short_run
    import threadpoolctl

    made = []
    original = threadpoolctl.threadpool_limits

    def counting(*args, **kwargs):
        made.append(kwargs.get("limits", args[0] if args else None))
        return original(*args, **kwargs)

    monkeypatch.setattr(threadpoolctl, "threadpool_limits", counting)
    identify.fit_fleet({"a": (robot, [rec]), "b": (robot, [rec])}, processing)
    assert made == [1]


def test_the_command_runs_blas_on_one_thread(short_run, caller_pool, monkeypatch, tmp_path, capsys):
    """rx90 identify run from Python (NumPy loaded, no thread variable): one thread inside it too."""
    from identify.app import cli

    robot, rec, _ = short_run
    log = tmp_path / "run.csv"
    identify.write_recording(log, rec, robot)
    seen = []
    recorder(monkeypatch, passes, "solve_joint_systems", seen)
    # --min-velocity 0: the twin's Coulomb term follows sign(q̇) through every slow pass.
    assert cli.main(["identify", str(log), "--robot", "ur10e", "--cutoff", "8", "--delay", "0", "--min-velocity",
                     "0"]) == 0
    assert blas_counts() == caller_pool
    assert seen and all(c == [1] * len(caller_pool) for c in seen), seen


PROCESS = """
import json, os
from rx90sym.threads import command_blas_threads
with {manager}:
    import numpy, scipy.linalg
    from threadpoolctl import threadpool_info
    counts = [d["num_threads"] for d in threadpool_info()
              if d["user_api"] == "blas" and d.get("threading_layer") != "disabled"]
print(json.dumps([counts, os.environ.get("OPENBLAS_NUM_THREADS")]))
"""


def process_counts(manager: str, **variables: str) -> tuple[list[int], str | None]:
    """A fresh process that loads numpy and scipy inside ``manager``: its BLAS counts and its
    OPENBLAS_NUM_THREADS, with ``variables`` as the only thread variables of its environment."""
    env = {k: v for k, v in os.environ.items() if k not in threads.BLAS_THREAD_VARIABLES} | variables
    done = subprocess.run([sys.executable, "-c", PROCESS.format(manager=manager)], env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return tuple(json.loads(done.stdout.splitlines()[-1]))


def test_the_command_process_starts_every_blas_on_one_thread_unless_a_variable_names_the_count():
    """rx90's process (numpy not loaded yet): one thread for every BLAS it loads later; with
    OMP_NUM_THREADS given, what a plain process gets with it, and OPENBLAS_NUM_THREADS left unset."""
    counts, openblas = process_counts("command_blas_threads()")
    assert counts and set(counts) == {1} and openblas == "1"
    given = process_counts("command_blas_threads()", OMP_NUM_THREADS="2")
    assert given == process_counts("open(os.devnull)", OMP_NUM_THREADS="2") and given[1] is None


def test_blas_threads_refuses_a_count_below_one():
    with pytest.raises(ValueError, match="threads must be >= 1, got 0"):
        with rx90sym.blas_threads(0):
            pass
