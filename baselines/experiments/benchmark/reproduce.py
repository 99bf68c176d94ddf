"""Reproduce Sec. VI-A of the paper: the ``paper`` suite of the benchmark CLI.

    python -m baselines.reproduce             # = python -m baselines.benchmark --suite paper
    python -m baselines.reproduce --check     #   --out results/reproduce; exit 1 if a check fails

Every option of ``python -m baselines.benchmark`` is accepted (``--n-uavs``, ``--seeds``,
``--policies``, ``--horizon``, ``--workers``, ``--no-figures``, ``--backend ray``, ...).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from baselines.experiments.benchmark.run import main as benchmark_main

__all__ = ["main"]


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m baselines.reproduce``: the benchmark with ``--suite paper --out
    results/reproduce`` first on the line; returns the exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    # the user's own --suite/--out (later on the line) win over these defaults
    return benchmark_main(
        ["--suite", "paper", "--out", "results/reproduce", *argv],
        prog="python -m baselines.reproduce",
    )
