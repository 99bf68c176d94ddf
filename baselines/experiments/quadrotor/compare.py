"""Compare two sets of quadrotor-experiment runs seed by seed (per-run criteria).

    python -m baselines.quadrotor_compare runs/qoff/* --against runs/qsafe/*

Each folder is an ``--out`` of ``python -m baselines.quadrotor_experiment``; the rows of all
folders on one side are pooled. For the seeds both sides share, it prints how many quadrotor
runs miss each Sec. VI-B criterion on each side, the runs that miss it on one side only (an
exact McNemar test), and the median paired change of each criterion's metric with a bootstrap
95 % CI (seeded: ``--seed``). Where run B had the safety filter on (its ``results.csv`` has
``turn_peak_since_filter``), it also splits the seeds by whether B's filter acted within
1.5 s before B's turn peak, with the turn-peak misses and medians of both runs per group.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from baselines.experiments.paired import add_bootstrap_options, run_paired
from baselines.experiments.quadrotor.paired import compare_runs, paired_lines
from baselines.runtime.cli import ArgumentParser

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The command line of ``python -m baselines.quadrotor_compare``."""
    ap = ArgumentParser(
        prog="python -m baselines.quadrotor_compare",
        description=__doc__.split("\n\n")[0],
        epilog=__doc__.split("\n\n", 2)[2],
    )
    ap.add_argument("runs", nargs="+", help="output folders of run A (pooled)")
    ap.add_argument(
        "--against", nargs="+", required=True, metavar="FOLDER", help="output folders of run B"
    )
    ap.add_argument("--policy", default="smc", help="controller in run A (default smc)")
    ap.add_argument(
        "--against-policy", default=None, help="controller in run B (default: --policy)"
    )
    ap.add_argument("--label", default="A", help="name of run A in the tables")
    ap.add_argument("--against-label", default="B", help="name of run B in the tables")
    add_bootstrap_options(ap, 4000)
    return ap


def main(argv: Sequence[str] | None = None) -> int:
    """Compare the runs and print the tables; returns the exit status."""

    def compare(args, rows_a, rows_b, rng):
        res = compare_runs(
            rows_a, rows_b, args.policy, args.against_policy, rng=rng, n_boot=args.bootstrap
        )
        return paired_lines(res, args.label, args.against_label)

    return run_paired(build_parser(), argv, compare)
