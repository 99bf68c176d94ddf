"""What the two paired-comparison commands share (``quadrotor_compare``, ``safety_compare``):
the bootstrap options, and a main that loads both sides' folders, compares them and prints
the lines; bad input (a folder without results, nothing to pair, a bad metric) ends in the
one error line of :mod:`baselines.runtime.cli`."""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from baselines.runtime.cli import at_least, user_errors
from baselines.runtime.folders import load_results

__all__ = ["add_bootstrap_options", "run_paired"]

#: compare(args, rows of run A, rows of run B or None, bootstrap generator) -> lines
Compare = Callable[[argparse.Namespace, list, "list | None", np.random.Generator], list[str]]


def add_bootstrap_options(ap: argparse.ArgumentParser, resamples: int) -> None:
    """``--bootstrap`` (resamples, default ``resamples``) and ``--seed`` (its generator)."""
    ap.add_argument("--bootstrap", type=int, default=resamples, help="bootstrap resamples")
    ap.add_argument("--seed", type=at_least(0), default=0, help="seed of the bootstrap's generator")


def run_paired(ap: argparse.ArgumentParser, argv: Sequence[str] | None, compare: Compare) -> Any:
    """Parse ``argv`` with ``ap`` (positional ``runs``, ``--against``), load the folders and
    print ``compare``'s lines; 0 on success."""
    args = ap.parse_args(argv)
    if args.bootstrap < 1:
        ap.error(f"--bootstrap {args.bootstrap} is invalid: must be >= 1")
    with user_errors(ap):
        rows_a = load_results(args.runs, "runs")
        rows_b = None if args.against is None else load_results(args.against, "--against")
        lines = compare(args, rows_a, rows_b, np.random.default_rng(args.seed))
    print("\n".join(lines))
    return 0
