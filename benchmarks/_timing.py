"""Timing helper shared by the benchmark scripts (medians of calibrated batches)."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable


def median_rate(
    fn: Callable[[], object],
    work: float,
    repeats: int,
    min_time: float,
    clock: Callable[[], float] = time.perf_counter,
) -> float:
    """Median of ``work / seconds`` over ``repeats`` timed batches of calls to ``fn``.

    ``fn`` is called once to warm up (JIT, caches); the batch size doubles until one batch
    takes at least ``min_time`` seconds. ``clock``: wall time by default;
    ``time.process_time`` (this process's CPU time) is steadier on a shared machine.
    """
    fn()
    n = 1
    while True:
        t0 = clock()
        for _ in range(n):
            fn()
        if clock() - t0 >= min_time:
            break
        n *= 2
    rates = []
    for _ in range(repeats):
        t0 = clock()
        for _ in range(n):
            fn()
        rates.append(work * n / (clock() - t0))
    return statistics.median(rates)


def print_breakdown(title: str, parts: dict[str, float], share_of: str = "share") -> None:
    """A markdown table of ``parts`` (microseconds; ``"total core.step"`` is 100 %)."""
    print(f"\n## {title} (microseconds per control step)\n")
    print(f"| part | us | {share_of} |\n|---|---|---|")
    total = parts["total core.step"]
    for k, v in parts.items():
        print(f"| {k} | {v:,.1f} | {100 * v / total:.0f} % |")
