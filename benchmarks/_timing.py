"""Timing helper shared by the benchmark scripts (medians of calibrated batches)."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable


def median_rate(fn: Callable[[], object], work: float, repeats: int, min_time: float) -> float:
    """Median of ``work / seconds`` over ``repeats`` timed batches of calls to ``fn``.

    ``fn`` is called once to warm up (JIT, caches); the batch size doubles until one batch
    takes at least ``min_time`` seconds.
    """
    fn()
    n = 1
    while True:
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        if time.perf_counter() - t0 >= min_time:
            break
        n *= 2
    rates = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        rates.append(work * n / (time.perf_counter() - t0))
    return statistics.median(rates)
