"""The one process pool of the experiments, training and the benchmark scripts."""

from __future__ import annotations

import multiprocessing as mp
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any

__all__ = ["imap_unordered"]


def imap_unordered(
    fn: Callable[..., Any], tasks: Sequence[tuple[Any, ...]], workers: int
) -> Iterator[tuple[int, Any]]:
    """Yield ``(i, fn(*tasks[i]))`` for every task, in the order they finish.

    With ``workers <= 1`` or a single task everything runs here, in order; otherwise in a pool
    of ``min(workers, len(tasks))`` fresh processes (``fn`` must be a top-level function and
    the arguments picklable). If a task raises, or the caller stops early (Ctrl-C), the tasks
    not yet started are cancelled.
    """
    if workers <= 1 or len(tasks) <= 1:
        for i, args in enumerate(tasks):
            yield i, fn(*args)
        return
    # fresh worker processes rather than forks of this one: a fork of a process whose torch /
    # OpenMP thread pools are running (the driver may have loaded a learned policy) can hang
    methods = mp.get_all_start_methods()
    ctx = mp.get_context("forkserver" if "forkserver" in methods else "spawn")
    with ProcessPoolExecutor(max_workers=min(workers, len(tasks)), mp_context=ctx) as pool:
        futures = {pool.submit(fn, *args): i for i, args in enumerate(tasks)}
        try:
            for f in as_completed(futures):
                yield futures[f], f.result()
        except BaseException:
            for f in futures:
                f.cancel()
            raise
