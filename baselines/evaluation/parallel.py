"""One thread per process and one process pool, for the experiments, training and the
benchmark scripts.

The parallelism of this project is across processes (jobs, seed blocks, routes); inside a
process numpy's BLAS, numba and torch run on one thread. On a small shared machine that is
faster (SB3 about 3x on 2 cores), and a job's numbers do not depend on the thread count.

This module imports nothing heavy, so that :func:`pin_threads` can run before numpy loads::

    from baselines.evaluation.parallel import pin_threads
    pin_threads()
    import numpy as np
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Iterator, Sequence
from typing import Any

__all__ = ["THREAD_VARIABLES", "imap_unordered", "pin_threads"]

#: environment variables that size the thread pools of OpenMP, MKL, OpenBLAS and numba
THREAD_VARIABLES = (
    "OMP_NUM_THREADS",
    "MKL_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "NUMBA_NUM_THREADS",
)


def pin_threads(load_torch: bool = False) -> None:
    """One thread per process for OpenMP, MKL, OpenBLAS, numba and torch.

    Sets each of :data:`THREAD_VARIABLES` to 1 unless the user set it (the libraries read
    them when they load, so call this first; child processes inherit them), and calls
    ``torch.set_num_threads(1)`` when torch is loaded, or with ``load_torch=True`` after
    importing it (training).
    """
    for var in THREAD_VARIABLES:
        os.environ.setdefault(var, "1")
    if load_torch or "torch" in sys.modules:
        import torch

        torch.set_num_threads(1)


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
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed

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
