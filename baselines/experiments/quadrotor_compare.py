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
import sys
from collections.abc import Sequence

import numpy as np

from baselines.evaluation.io import load_results

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The command line of ``python -m baselines.quadrotor_compare``."""
    ap = argparse.ArgumentParser(
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
    ap.add_argument("--bootstrap", type=int, default=4000, help="bootstrap resamples")
    ap.add_argument("--seed", type=int, default=0, help="seed of the bootstrap's generator")
    return ap


def main(argv: Sequence[str] | None = None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    from baselines.reporting.quadrotor_paired import compare_runs, paired_lines

    if args.bootstrap < 1:
        ap.error(f"--bootstrap {args.bootstrap} is invalid: must be >= 1")
    rows_a = load_results(args.runs, "runs")
    rows_b = load_results(args.against, "--against")
    try:
        res = compare_runs(
            rows_a,
            rows_b,
            args.policy,
            args.against_policy,
            rng=np.random.default_rng(args.seed),
            n_boot=args.bootstrap,
        )
    except ValueError as exc:
        raise SystemExit(str(exc)) from None
    print("\n".join(paired_lines(res, args.label, args.against_label)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
