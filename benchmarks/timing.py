"""Timing helper shared by the benchmark scripts (run them as ``python benchmarks/NAME.py``)."""
from __future__ import annotations

import time
from typing import Callable


def time_it(fn: Callable[[], object], repeat: int = 5, warmup: bool = True) -> float:
    """Best wall time (s) of ``repeat`` calls of ``fn()``, after one untimed call if ``warmup``."""
    if warmup:
        fn()
    best = float("inf")
    for _ in range(max(1, repeat)):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best
