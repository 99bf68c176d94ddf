"""Compare a controller with the safety filter off and on, run by run (paired by seed).

    python -m baselines.safety_compare runs/safety_suite
    python -m baselines.safety_compare runs/off --against runs/variant --policy smc

Each folder is an ``--out`` of ``python -m baselines.benchmark`` whose runs carry the safety
columns (e.g. ``--suite safety``); the rows of all folders on one side are pooled. The
filter-off runs (``safety_filter=none``) of the first folders pair with the filter-on runs
(``safety_filter=cbf``) of ``--against`` (default: the same folders) on every setting both
share (controller, N, start, ...) and on (seed, pair); a setting only ``--against`` varies
(e.g. ``--set safety_other_accel=40,100``) gives one line per value. For each metric it prints
the median and worst run of each side and their change, the change of the 90th percentile
and the median per-run ratio on/off (each with a seeded bootstrap 95 % CI: ``--seed``), and
the runs that got more than 10 % worse, more than 10 % better, or stayed identical;
``--figure PNG`` draws every paired run, off against on.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from baselines.experiments.paired import add_bootstrap_options, run_paired
from baselines.experiments.safety.paired import (
    PAIRED_METRICS,
    compare_filter,
    paired_figure,
    paired_filter_lines,
)
from baselines.runtime.cli import ArgumentParser

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The command line of ``python -m baselines.safety_compare``."""
    ap = ArgumentParser(
        prog="python -m baselines.safety_compare",
        description=__doc__.split("\n\n")[0],
        epilog=__doc__.split("\n\n", 2)[2],
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    ap.add_argument("runs", nargs="+", help="benchmark output folders with the filter-off runs")
    ap.add_argument(
        "--against",
        nargs="+",
        default=None,
        metavar="FOLDER",
        help="folders with the filter-on runs (default: the same folders)",
    )
    ap.add_argument(
        "-p", "--policy", nargs="+", default=None, help="controllers to compare (default: all)"
    )
    ap.add_argument(
        "--metrics", nargs="+", default=list(PAIRED_METRICS), help="per-run result columns"
    )
    ap.add_argument(
        "--filters",
        nargs=2,
        default=["none", "cbf"],
        choices=["none", "cbf"],
        metavar=("A", "B"),
        help="safety_filter of each side; 'none none' with --against compares two "
        "filter-off runs (e.g. one with --set disturbance_std=1 as a placebo)",
    )
    ap.add_argument(
        "--figure",
        type=Path,
        default=None,
        metavar="PNG",
        help="also draw every paired run, off against on, one panel per controller and metric",
    )
    add_bootstrap_options(ap, 2000)
    return ap


def main(argv: Sequence[str] | None = None) -> int:
    """Compare the runs and print the tables; returns the exit status."""

    def compare(args, rows_a, rows_b, rng):
        res = compare_filter(
            rows_a,
            rows_b,
            metrics=args.metrics,
            policies=args.policy,
            filters=tuple(args.filters),
            rng=rng,
            n_boot=args.bootstrap,
        )
        lines = paired_filter_lines(res)
        if args.figure is not None:
            lines.append(f"\nwrote {paired_figure(res, args.figure)}")
        return lines

    return run_paired(build_parser(), argv, compare)
