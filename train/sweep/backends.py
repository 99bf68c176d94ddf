"""The two backends of a sweep by name: ``local`` (worker processes, :mod:`train.sweep.local`)
and ``ray`` (Ray Tune, :mod:`train.sweep.ray`).

The one module of :mod:`train` that imports inside a function: Ray is optional
(``pip install 'pairflock-env[sweep]'``), so the Ray backend is imported only when a sweep
asks for it.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from train.sweep.local import Outcome, Progress, run_local

__all__ = ["BACKENDS", "run_backend"]

BACKENDS = ("local", "ray")


def run_backend(
    name: str,
    plan: Any,
    pending: list[Any],
    out: Path,
    progress: Progress,
    *,
    address: str | None = None,
    num_cpus: int | None = None,
    cpus_per_trial: float = 1.0,
    max_concurrent: int | None = None,
) -> Outcome:
    """Run the ``pending`` trials of ``plan`` (every draw, for a search) on backend ``name``."""
    if name not in BACKENDS:
        raise ValueError(f"backend={name!r} is invalid: must be one of {', '.join(BACKENDS)}")
    if name == "local":
        return run_local(pending, out, max_concurrent or os.cpu_count() or 1, progress)
    try:
        from train.sweep.ray import run_ray
    except ImportError:
        raise ImportError(
            "--backend ray needs Ray Tune: pip install 'pairflock-env[sweep]'"
        ) from None
    return run_ray(
        plan,
        pending,
        out,
        progress,
        address=address,
        num_cpus=num_cpus,
        cpus_per_trial=cpus_per_trial,
        max_concurrent=max_concurrent,
    )
