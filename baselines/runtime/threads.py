"""One thread per process, set before numpy loads.

The parallelism of this project is across processes (jobs, seed blocks, routes); inside a
process numpy's BLAS, numba and torch run on one thread. On a small shared machine that is
faster (SB3 about 3x on 2 cores), and a job's numbers do not depend on the thread count.

The libraries read their thread counts when they load, so :func:`pin_threads` runs first: in
the launcher of every command (``python -m baselines.benchmark``, ``python -m train``, ...),
which pins and only then imports the command's module. This module imports nothing heavy::

    from baselines.runtime.threads import pin_threads
    pin_threads()
    import numpy as np
"""

from __future__ import annotations

import os
import sys

__all__ = ["THREAD_VARIABLES", "pin_threads"]

#: environment variables that size the thread pools of OpenMP, MKL, OpenBLAS and numba
THREAD_VARIABLES = (
    "OMP_NUM_THREADS",
    "MKL_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "NUMBA_NUM_THREADS",
)


def pin_threads() -> None:
    """One thread per process for OpenMP, MKL, OpenBLAS, numba and torch.

    Sets each of :data:`THREAD_VARIABLES` to 1 unless the user set it (child processes
    inherit them), and calls ``torch.set_num_threads(1)`` when torch is loaded already (so
    code that trains calls it again once torch is imported).
    """
    for var in THREAD_VARIABLES:
        os.environ.setdefault(var, "1")
    torch = sys.modules.get("torch")
    if torch is not None:
        torch.set_num_threads(1)
