"""``python -m train.sweep`` / ``pairflock-sweep``: training runs over seeds and settings.

A sweep trains one ``python -m train`` run per (setting, seed), on local worker processes
(``--backend local``) or on Ray Tune (``--backend ray``, one machine or a cluster), and
reports per setting the interquartile mean over seeds with stratified-bootstrap confidence
intervals (rliable). Both backends run the same trials through the same code, so they give
the same per-trial numbers. See ``docs/sweeps.md``.

Files written to ``--out``:

* ``sweep.json``: the sweep's definition, its trials and a record of each session;
* ``trials/<setting>/seed_<n>/``: one ordinary run directory per trial (resumable with
  ``python -m train --resume``), plus ``sweep_trial.json`` (its result) and
  ``sweep_eval_final.csv`` (the final model on every evaluation seed);
* ``sweep.csv``: one row per trial (setting, seed, final and best evaluation, aims met;
  wall times in the ``wall_*`` columns); ``summary.md``: IQM [95 % CI] per setting and the
  seeds meeting each aim; ``curves.png``: evaluation curves with CI bands;
* ``logs/`` (local backend: each worker's output) and ``ray/`` (Ray Tune's experiment).
"""

from __future__ import annotations

import argparse
import shutil
import sys
import textwrap
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from baselines.runtime.cli import ArgumentParser, at_least, int_like, user_errors
from baselines.runtime.files import atomic_write_text, write_csv, write_json
from baselines.runtime.record import run_record
from train.callbacks import SUMMARY
from train.settings import load_yaml
from train.sweep.backends import BACKENDS, run_backend
from train.sweep.local import Outcome, Progress
from train.sweep.plan import SWEEP_FILE, SweepPlan, load_sweep, parse_domain, parse_grid, same_plan
from train.sweep.report import csv_rows, curves_figure, summary_markdown
from train.sweep.trial import finished_result

__all__ = ["build_parser", "main"]

EPILOG = textwrap.dedent(
    """\
    keys of --grid and --set (dotted, onto the run settings of python -m train):
      env.FIELD             PairFlockConfig override, e.g. env.n_uavs=20,50
      eval_env.FIELD        evaluation-only override, e.g. eval_env.horizon=20
      hp.NAME[.SUB]         SB3 hyperparameter, e.g. hp.learning_rate=3e-4,1e-4 or
                            hp.policy_kwargs.net_arch=[64,64],[128,128]
      interface.NAME        learning-interface parameter, e.g. interface.w_band=0.1,0.2
      FIELD                 top-level setting, e.g. num_swarms=16,32 or eval_every=500000
    --search optuna draws settings instead: KEY=a,b,c (choice), KEY=uniform:LO:HI,
    KEY=loguniform:LO:HI, KEY=int:LO:HI; each draw is trained on every seed.

    resuming: run the same command again (or --resume DIR): finished trials are kept,
    unfinished ones continue from their newest checkpoint (Ray: Tuner.restore). Ctrl-C
    stops cleanly (running trials write a checkpoint; exit status 130).

    examples:
      python -m train.sweep --config train/configs/pair_n20_a50.yaml --seeds 0 1 2 3 4 \\
          --out runs/sweep_pair_n20_a50
      python -m train.sweep --config train/configs/pair_n20_a50.yaml --seeds 0 1 2 \\
          --grid hp.learning_rate=3e-4,1e-4 --grid env.n_uavs=20,50 --total-steps 2e6 \\
          --backend ray --out runs/sweep_lr_n
      ray start --head --num-cpus 16       # then, from any node of the cluster:
      python -m train.sweep --config CFG --seeds 0 1 2 3 4 --backend ray \\
          --address HEAD_IP:6379 --cpus-per-trial 1 --out /shared/sweep
      python -m train.sweep --config CFG --seeds 0 1 2 --search optuna --samples 8 \\
          --grid hp.learning_rate=loguniform:1e-5:1e-3 --metric final_score --mode min \\
          --backend ray --out runs/optuna
      python -m train.sweep --resume runs/sweep_lr_n
    """
)

#: flags that define the sweep (a resumed sweep keeps them as stored)
_PLAN_FLAGS = (
    "config",
    "seeds",
    "total_steps",
    "grid",
    "sets",
    "search",
    "samples",
    "metric",
    "mode",
)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``python -m train.sweep``."""
    p = ArgumentParser(
        prog="python -m train.sweep",
        description=__doc__.split("\n\n")[1].replace("\n", " "),
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _plan_options(p.add_argument_group("what to train"))
    _backend_options(p.add_argument_group("where to run"))
    g = p.add_argument_group("output")
    g.add_argument("--out", type=Path, help="sweep directory (required unless --resume)")
    g.add_argument("--resume", type=Path, metavar="DIR", help="continue the sweep in DIR")
    g.add_argument("--overwrite", action="store_true", help="replace another sweep in --out")
    g.add_argument(
        "--bootstrap-reps", type=int, default=2000, help="bootstrap resamples (default 2000)"
    )
    g.add_argument("--no-figure", action="store_true", help="skip curves.png")
    g.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def _plan_options(g: argparse._ArgumentGroup) -> None:
    g.add_argument("--config", type=Path, metavar="YAML", help="base settings (python -m train)")
    g.add_argument(
        "--seeds", type=at_least(0), nargs="+", metavar="N", help="training seeds (default 0)"
    )
    g.add_argument("--total-steps", type=int_like, help="steps per trial (default: the config's)")
    g.add_argument(
        "--grid",
        action="append",
        metavar="KEY=V1,V2",
        help="values of one setting, repeatable: the grid is their product (keys below)",
    )
    g.add_argument(
        "--set",
        dest="sets",
        action="append",
        metavar="KEY=VALUE",
        help="a setting for every trial, repeatable (same keys as --grid)",
    )
    g.add_argument(
        "--search",
        choices=("grid", "optuna"),
        help="grid (default) or Ray Tune's OptunaSearch over the --grid domains",
    )
    g.add_argument("--samples", type=int, help="settings drawn by --search optuna")
    g.add_argument(
        "--metric",
        help="result column optimised by --search optuna (default final_score; e.g. "
        "best_score, final_ss_error_median, aims_met)",
    )
    g.add_argument("--mode", choices=("min", "max"), help="minimise (default) or maximise")


def _backend_options(g: argparse._ArgumentGroup) -> None:
    g.add_argument("--backend", choices=BACKENDS, default="local", help="default local")
    g.add_argument("--address", help="Ray cluster to join (e.g. HEAD_IP:6379 or auto)")
    g.add_argument("--num-cpus", type=int, help="CPUs of a new local Ray instance (default all)")
    g.add_argument(
        "--cpus-per-trial", type=float, default=1.0, help="Ray resources per trial (default 1)"
    )
    g.add_argument(
        "--max-concurrent",
        type=int,
        help="trials at once (local default: the CPU count; Ray default: as resources allow)",
    )


def main(argv: Sequence[str] | None = None) -> int:
    """Run the sweep; exit status 0 (all trials done), 1 (some failed), 130 (interrupted)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    with user_errors(parser, ImportError, ConnectionError):
        return _main(args, parser)


def _plan_from_args(args: argparse.Namespace):
    search = None if args.search in (None, "grid") else args.search
    if search is None and (args.samples is not None or args.metric or args.mode):
        raise ValueError("--samples, --metric and --mode belong to --search optuna")
    parse = parse_domain if search else parse_grid
    grid = [parse(t, "--grid") for t in args.grid or []]
    fixed = []
    for t in args.sets or []:
        key, values = parse_grid(t, "--set")
        if len(values) != 1:
            raise ValueError(f"--set {t!r} is invalid: one value (use --grid for several)")
        fixed.append((key, values[0]))
    plan = SweepPlan(
        base=load_yaml(args.config) if args.config is not None else {},
        fixed=fixed,
        grid=grid,
        seeds=list(args.seeds or [0]),
        total_steps=args.total_steps,
        search=search,
        samples=args.samples or 0,
        metric=args.metric or "final_score",
        mode=args.mode or "min",
    )
    if search:
        _check_search(plan)
    return plan


def _check_search(plan) -> None:
    if plan.samples < 1:
        raise ValueError(f"--samples {plan.samples} is invalid: --search optuna needs >= 1")
    if not plan.grid:
        raise ValueError("--search optuna needs at least one --grid dimension")
    names = [f"{p}_{k}" for p in ("final", "best") for k in (*SUMMARY, "band_never", "score")]
    names.append("aims_met")
    if plan.metric not in names:
        raise ValueError(f"--metric {plan.metric!r} is invalid: one of {', '.join(names)}")
    plan.check_search_space()


def _prepare(args: argparse.Namespace):
    """The sweep directory and plan (new, repeated or resumed) and the stored record."""
    if args.resume is not None:
        given = [f for f in _PLAN_FLAGS if getattr(args, f) not in (None, [])]
        if given or args.overwrite:
            raise ValueError(
                f"--resume continues a sweep as it was defined; drop {given or '--overwrite'}"
            )
        out = args.resume
        stored = load_sweep(out)
        if stored is None:
            raise FileNotFoundError(f"--resume {str(out)!r} is invalid: no sweep.json there")
        return out, SweepPlan.from_dict(stored["plan"]), stored
    if args.out is None:
        raise ValueError("--out is required (or --resume DIR)")
    out, plan = args.out, _plan_from_args(args)
    stored = load_sweep(out)
    if stored is not None and same_plan(stored["plan"], plan.to_dict()):
        return out, plan, stored  # the same sweep again: continue it
    if out.exists() and any(out.iterdir()):
        if not args.overwrite:
            what = "another sweep" if stored is not None else "other files"
            raise FileExistsError(
                f"--out {str(out)!r} holds {what}; pass --overwrite to replace it, or "
                f"--resume {str(out)!r} to continue the sweep stored there"
            )
        shutil.rmtree(out)
    return out, plan, None


def _main(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    out, plan, stored = _prepare(args)
    if plan.search and args.backend != "ray":
        raise ValueError("--search optuna runs on Ray Tune's OptunaSearch: add --backend ray")
    for name in ("max_concurrent", "num_cpus", "bootstrap_reps"):
        v = getattr(args, name)
        if v is not None and v < 1:
            raise ValueError(f"--{name.replace('_', '-')} {v} is invalid: must be >= 1")
    if args.cpus_per_trial <= 0:
        raise ValueError(f"--cpus-per-trial {args.cpus_per_trial} is invalid: must be > 0")
    trials = [] if plan.search else plan.trials()
    sessions = list(stored["sessions"]) if stored else []
    record = {"plan": plan.to_dict(), "trials": [t.to_dict() for t in trials]}
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / SWEEP_FILE, {**record, "sessions": sessions})
    done = [t.name for t in trials if finished_result(t, out) is not None]
    pending = [t for t in trials if t.name not in done]
    total = len(trials) or plan.samples * len(plan.seeds)
    progress = Progress(total, done=len(done), disable=args.quiet)
    t0 = time.perf_counter()
    try:
        outcome = _run_backend(args, plan, pending, out, progress)
    finally:
        progress.close()
    wall = time.perf_counter() - t0
    results = _gather(plan, trials, out, outcome)
    session = run_record(
        backend=args.backend,
        address=args.address,
        wall_s=round(wall, 2),
        skipped=done,
        ran=progress.started,
        failed=outcome.failed,
        interrupted=outcome.interrupted,
    )
    write_json(out / SWEEP_FILE, {**record, "sessions": [*sessions, session]})
    _write_outputs(args, plan, out, results, total, wall)
    _report(out, results, total, outcome, args.quiet)
    if outcome.interrupted:
        return 130
    return 1 if outcome.failed else 0


def _run_backend(args, plan, pending, out: Path, progress):
    if not plan.search and not pending:
        return Outcome()  # every trial finished already
    return run_backend(
        args.backend,
        plan,
        pending,
        out,
        progress,
        address=args.address,
        num_cpus=args.num_cpus,
        cpus_per_trial=args.cpus_per_trial,
        max_concurrent=args.max_concurrent,
    )


def _gather(plan, trials, out: Path, outcome) -> list[dict[str, Any]]:
    """Every finished trial's result, in the plan's order (search: by setting, then seed)."""
    if not trials:
        return sorted(outcome.results.values(), key=lambda r: (r["label"], r["seed"]))
    results = []
    for t in trials:
        r = finished_result(t, out) or outcome.results.get(t.name)
        if r is not None:
            results.append(r)
    return results


def _write_outputs(args, plan, out: Path, results, total: int, wall: float) -> None:
    keys = [k for k, _ in plan.grid]
    write_csv(out / "sweep.csv", csv_rows(results, keys))
    if not results:
        return
    figure = None if args.no_figure else "curves.png"
    header = [
        "# Training sweep",
        "",
        f"`{' '.join(['python -m train.sweep', *sys.argv[1:]])}`",
        "",
        f"{len(results)} of {total} trials finished; seeds {plan.seeds}; backend "
        f"{args.backend}; this session {wall / 60:.1f} min.",
    ]
    md = summary_markdown(results, header, reps=args.bootstrap_reps, figure=figure)
    atomic_write_text(out / "summary.md", md)
    if figure:
        curves_figure(results, out / figure)


def _report(out: Path, results, total: int, outcome, quiet: bool) -> None:
    state = "interrupted" if outcome.interrupted else "done"
    msg = f"sweep {state}: {len(results)}/{total} trials finished"
    if outcome.failed:
        msg += f", {len(outcome.failed)} failed"
    if results:
        msg += f" -> {out / 'summary.md'}"
    if outcome.interrupted:
        msg += f"\ncontinue with: python -m train.sweep --resume {out}"
    print(msg, file=sys.stderr if quiet else sys.stdout)
