"""Evaluate a trained pair policy next to the analytic controllers, with the reproduction's
rollout and metrics (``baselines.evaluation.rollout``), on held-out seeds.

    python -m train.evaluate models/pair_n20_a50.zip                 # N = 20, 10 seeds
    python -m train.evaluate models/pair_n20_a50.zip --n-uavs 20 50 100 --init corners random
    python -m train.evaluate pair_n20_a50        # a packaged policy by name, from any folder

The task is the one the model was evaluated on during training (stored in the model file:
preset and overrides, e.g. ``pair_accel_limit=50``, the preset's 50 s episode), with ``n_uavs``
and ``init`` varied as asked and ``--set`` overrides on top. Baselines are names for
``baselines.make_pair_policy``, with gains as in the benchmark (``braking:detour=80``);
``name@LIMIT`` runs it with ``pair_accel_limit=LIMIT`` (e.g. ``smc@1000``: sliding mode with
the paper's unconstrained acceleration). Writes
``results.csv`` (one row per run), ``summary.md`` (median [min-max] over seeds per setting
and policy, and the learned policy's targets,
:data:`baselines.reporting.criteria.LEARNED`) and ``run.json``.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tqdm import tqdm

from baselines import POLICIES, make_pair_policy
from baselines.controllers.sb3 import read_metadata
from baselines.controllers.zoo import resolve_model
from baselines.evaluation.recording import (
    RecordOptions,
    add_record_options,
    check_run_names,
    record_options,
    recorded_rollout,
    report_line,
    run_name,
    written,
)
from baselines.evaluation.rollout import trace_metrics
from baselines.evaluation.specs import parse_assignment, parse_policy
from baselines.reporting.criteria import (
    GENERALIST,
    all_passed,
    check_learned,
    check_learned_all,
    criteria_lines,
    criteria_table,
)
from baselines.reporting.tables import summary_table as markdown_table
from baselines.runtime.cli import ArgumentParser, at_least, user_errors
from baselines.runtime.files import atomic_write_text, write_csv, write_json
from baselines.runtime.folders import result_folder
from baselines.runtime.pool import imap_unordered
from baselines.runtime.record import run_record
from baselines.runtime.threads import pin_threads
from pairflock_env import make_config
from train.settings import RunSettings

__all__ = ["COLUMNS", "build_parser", "main", "run_job", "summary_table"]

#: (metric, column title, format) of the summary table
COLUMNS = (
    ("band_time", "in 0.5 m band for good (s)", "{:.2f}"),
    ("ss_mean_error", "steady mean err (m)", "{:.3f}"),
    ("ss_max_error", "steady max err (m)", "{:.3f}"),
    ("min_pair_separation", "min pair-other dist (m)", "{:.2f}"),
    ("peak_accel", "peak pair accel (m/s^2)", "{:.0f}"),
    ("s_settle_time", "s settle (s)", "{:.2f}"),
)


def _task_overrides(model_path: Path) -> tuple[str, dict[str, Any]]:
    meta = read_metadata(model_path)
    settings = meta.get("settings")
    if settings is None:
        raise ValueError(f"{str(model_path)!r} has no training settings in its metadata")

    s = RunSettings.from_dict(settings)
    return s.preset, s.eval_overrides()


def split_limit(policy: str) -> tuple[str, str | None]:
    """``NAME[:GAINS][@LIMIT]`` as (``NAME[:GAINS]``, ``LIMIT`` text or None)."""
    head, at, limit = policy.rpartition("@")
    return (head, limit) if at else (policy, None)


def run_job(
    model_path: str,
    policy: str,
    n_uavs: int,
    init: str,
    seeds: list[int],
    extra: dict[str, Any],
    recording: RecordOptions | None = None,
) -> list[dict[str, Any]]:
    """Metrics per seed of one (policy, N, init) combination; ``recording`` writes its
    recordings (:mod:`baselines.evaluation.recording`)."""
    pin_threads()

    preset, over = _task_overrides(Path(model_path))
    over = {**over, "n_uavs": n_uavs, "init": init, **extra}
    name, limit = split_limit(policy)
    if limit is not None:
        over["pair_accel_limit"] = float(limit)
    cfg = make_config(preset, **over)
    if name == "learned":
        pol = make_pair_policy(f"sb3:{model_path}", cfg)
    else:
        spec = parse_policy(name)
        pol = make_pair_policy(spec.name, cfg, **dict(spec.gains))
    t0 = time.perf_counter()
    rows = trace_metrics(recorded_rollout(recording, cfg, pol, seeds))
    wall = time.perf_counter() - t0
    return [
        {
            "n_uavs": n_uavs,
            "init": init,
            "policy": policy,
            "pair_accel_limit": cfg.pair_accel_limit,
            "wall_s": round(wall, 2),
            **r,
        }
        for r in rows
    ]


def summary_table(rows: list[dict[str, Any]], policies: list[str]) -> str:
    """Markdown: median [min-max] over seeds per (N, init, policy); corners first."""
    rank = {p: i for i, p in enumerate(policies)}
    return markdown_table(
        [r for r in rows if r["policy"] in rank],
        COLUMNS,
        lead=(
            ("N", "n_uavs"),
            ("init", "init"),
            ("policy", "policy"),
            ("limit (m/s^2)", lambda r: f"{r['pair_accel_limit']:.0f}"),
        ),
        group=lambda r: (r["n_uavs"], r["init"], r["policy"]),
        sort=lambda g: (g[1] != "corners", g[0], rank[g[2]]),
    )


def build_parser() -> argparse.ArgumentParser:
    """The evaluation's argument parser."""
    p = ArgumentParser(
        prog="python -m train.evaluate",
        description=__doc__.split("\n\n")[0],
        epilog=__doc__.split("\n\n", 2)[2],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "model",
        type=Path,
        help="model zip written by python -m train, or a packaged policy's name "
        "(e.g. pair_n20_a50; baselines.controllers.zoo)",
    )
    p.add_argument("--n-uavs", type=int, nargs="+", default=[20], help="swarm sizes (default 20)")
    p.add_argument(
        "--init",
        nargs="+",
        default=["corners"],
        choices=("corners", "random"),
        help="pair start: the paper's corners and/or random (default corners)",
    )
    p.add_argument("--seeds", type=at_least(1), default=10, help="seeds per setting (default 10)")
    p.add_argument(
        "--first-seed",
        type=at_least(0),
        default=10_000,
        help="held-out seeds are first-seed, first-seed+1, ... (default 10000; "
        "training evaluates on 1000-1009 and trains on SeedSequence children)",
    )
    p.add_argument(
        "--baselines",
        nargs="*",
        default=["smc", "smc@1000", "proportional"],
        help="analytic controllers for comparison, NAME[:GAIN=V,...][@LIMIT] "
        "(default: smc smc@1000 proportional)",
    )
    p.add_argument(
        "--set",
        dest="sets",
        action="append",
        default=[],
        metavar="FIELD=VALUE",
        help="extra PairFlockConfig override for every run",
    )
    p.add_argument(
        "--out", type=Path, default=None, help="output folder (default results/eval_<model name>)"
    )
    p.add_argument(
        "--workers",
        type=at_least(1),
        default=min(2, os.cpu_count() or 1),
        help="worker processes (default 2; 1 runs here)",
    )
    _add_check_options(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_record_options(p)
    return p


def _add_check_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--check",
        action="store_true",
        help="exit status 1 unless the learned policy meets its targets (--targets)",
    )
    p.add_argument(
        "--targets",
        choices=["learned", "generalist"],
        default="learned",
        help="learned (default): baselines.reporting.criteria.LEARNED at N=20, corners; "
        "generalist: criteria.GENERALIST on every evaluated N and start",
    )


def _check_args(args: argparse.Namespace, parser: argparse.ArgumentParser) -> dict[str, Any]:
    """Validate the options before anything runs (bad input ends in ``parser.error``, one
    line naming it); returns the ``--set`` overrides."""
    with user_errors(parser):
        args.model = resolve_model(args.model)
        for n in args.n_uavs:
            if n < 2:
                raise ValueError(f"--n-uavs {n} is invalid: must be >= 2")
        for b in args.baselines:
            _check_baseline(b)
        extra = dict(parse_assignment(s, "--set") for s in args.sets)
        preset, over = _task_overrides(args.model)
        for n in args.n_uavs:  # every evaluated task builds, --set overrides included
            for init in args.init:
                _task_config(preset, {**over, "n_uavs": n, "init": init}, extra)
    return extra


def _task_config(preset: str, task: dict[str, Any], extra: dict[str, Any]) -> Any:
    """The config of one evaluated task; an error names ``--set`` when it has overrides."""
    try:
        return make_config(preset, **task, **extra)
    except (TypeError, ValueError) as e:
        sets = ", ".join(f"{k}={v!r}" for k, v in extra.items())
        raise type(e)(f"--set {sets}: {e}" if extra else str(e)) from None


def _check_baseline(b: str) -> None:
    """``--baselines`` entry ``NAME[:GAINS][@LIMIT]``: a registered analytic controller, gains
    it accepts and a positive limit; ``ValueError`` naming the entry otherwise."""
    head, limit = split_limit(b)
    name = head.split(":", 1)[0]
    if name not in POLICIES or name.endswith(":"):
        raise ValueError(
            f"--baselines {b!r} is invalid: analytic controllers are "
            f"{', '.join(k for k in POLICIES if not k.endswith(':'))}"
        )
    if limit is not None:
        try:
            if float(limit) <= 0:
                raise ValueError
        except ValueError:
            raise ValueError(
                f"--baselines {b!r} is invalid: LIMIT after @ must be a number > 0"
            ) from None
    try:
        spec = parse_policy(head)
        make_pair_policy(spec.name, make_config("paper"), **dict(spec.gains))
    except (TypeError, ValueError) as e:
        raise ValueError(f"--baselines {b!r} is invalid: {e}") from None


def _recordings(args, record: RecordOptions | None, policies: list[str]) -> dict[tuple, Any]:
    """The recording options of every (N, init, policy) run (None without --record);
    ``ValueError`` when two runs would share a folder."""
    runs = [(n, init, pol) for n in args.n_uavs for init in args.init for pol in policies]
    if record is None:
        return dict.fromkeys(runs)
    recordings = {
        (n, init, pol): record.run(
            run_name(f"n{n}", init, pol),
            f"sb3:{args.model.stem}" if pol == "learned" else pol,
            n_uavs=n,
            init=init,
            policy=pol,
            model=str(args.model),
        )
        for n, init, pol in runs
    }
    check_run_names(recordings.values())
    return recordings


def _run(args, policies: list[str], seeds: list[int], extra, recordings) -> list[dict[str, Any]]:
    jobs = [
        (str(args.model), pol, n, init, seeds, extra, recordings[n, init, pol])
        for n in sorted(args.n_uavs, reverse=True)
        for init in args.init
        for pol in policies
    ]
    rows: list[dict[str, Any]] = []
    with tqdm(total=len(jobs), desc="evaluate", unit="job", disable=args.quiet) as bar:
        for _, job_rows in imap_unordered(run_job, jobs, args.workers):
            rows += job_rows
            bar.update()
    order = {p: i for i, p in enumerate(policies)}
    rows.sort(key=lambda r: (r["init"] != "corners", r["n_uavs"], order[r["policy"]], r["seed"]))
    return rows


def _checks(rows: list[dict[str, Any]], targets: str) -> list:
    """The learned policy's checks: LEARNED at N = 20, corners, or GENERALIST everywhere."""
    return check_learned(rows) if targets == "learned" else check_learned_all(rows, GENERALIST)


def _summary(model: Path, seeds: list[int], table: str, checks, targets: str) -> str:
    md = [
        f"# Evaluation of `{model}`",
        "",
        f"Held-out seeds {seeds[0]}-{seeds[-1]}; full episodes; median [min-max] over seeds; "
        "metrics of `pairflock_env.task.metrics` via `baselines.evaluation.rollout`.",
        "",
        table,
        "",
    ]
    if checks:
        title = "learned policy, N = 20, corners" if targets == "learned" else "generalist"
        md += [f"## Targets ({title})", "", *criteria_table(checks)]
    return "\n".join(md) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m train.evaluate`` / ``pairflock-evaluate``; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    extra = _check_args(args, parser)
    out = args.out or Path("results") / f"eval_{args.model.stem}"
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    policies = ["learned", *args.baselines]
    with user_errors(parser):
        recordings = _recordings(args, record_options(args, out, seeds), policies)
    t0 = time.perf_counter()
    rows = _run(args, policies, seeds, extra, recordings)
    table = summary_table(rows, policies)
    checks = _checks(rows, args.targets)
    recorded = written(recordings.values(), seeds, out)
    with result_folder(out) as folder:  # complete and consistent, or marked INCOMPLETE
        write_csv(folder / "results.csv", rows)
        atomic_write_text(
            folder / "summary.md", _summary(args.model, seeds, table, checks, args.targets)
        )
        record = run_record(
            model=str(args.model),
            seeds=seeds,
            n_uavs=args.n_uavs,
            init=args.init,
            policies=policies,
            extra_overrides=extra,
            wall_s=round(time.perf_counter() - t0, 1),
            outputs=["results.csv", "summary.md"],
            recordings=recorded,
        )
        write_json(folder / "run.json", record)
    print(table)
    for line in criteria_lines(checks):
        print(line)
    print(f"wrote {out / 'summary.md'}")
    if recorded:
        print(report_line(recorded, out))
    return 1 if args.check and not all_passed(checks) else 0
