"""``python -m train`` / ``pairflock-train``: train a pair policy with stable-baselines3.

Settings come from defaults, then ``--config FILE.yaml``, then flags (later wins); the
effective settings are written to ``<out>/settings.yaml``, so ``--config <out>/settings.yaml``
reproduces a run.
"""

from __future__ import annotations

import argparse
import sys
import textwrap
from collections.abc import Sequence
from pathlib import Path

from baselines.evaluation.specs import parse_assignment
from baselines.runtime.cli import ArgumentParser, int_like, user_errors
from train.callbacks import GracefulInterrupt
from train.checkpoint import latest_checkpoint
from train.hyperparameters import ALGOS
from train.mix.tasks import evaluation_tasks, is_mix
from train.run import ALREADY_COMPLETE, train
from train.settings import load_yaml, settings_from_sources, settings_help

__all__ = ["build_parser", "main"]

EPILOG = textwrap.dedent(
    """\
    files written to --out:
      settings.yaml          effective settings (rerun with --config <out>/settings.yaml)
      run.json               config, interface, seed, package versions, git commit, status,
                             timing, final evaluation; a resumed session writes its own
                             run_resumed_<N>.json and updates the status in run.json
      eval.csv               periodic evaluation of the policy (step, summary over seeds)
      eval_baselines.json    the analytic controllers on the same seeds (computed once)
      logs/progress_*.csv    SB3 training log; tensorboard/ for `tensorboard --logdir <out>`
      checkpoints/step_<N>/  model + optimizer, replay buffer (SAC/TD3), env and RNG state;
                             checkpoints/latest names the newest
      best_model.zip         the model with the best evaluation score so far
      final_model.zip        the model at the end (also after Ctrl-C)
    every file is written atomically (temporary file + rename).

    evaluation: every --eval-every steps the policy runs full episodes (the preset's 50 s) on
    --eval-seeds through baselines.evaluation.rollout, the code of the paper reproduction, and is
    logged next to --eval-baselines. Ctrl-C stops cleanly: a checkpoint and final_model.zip are
    written and the exit status is 130; a second Ctrl-C aborts at once.

    examples:
      python -m train --config train/configs/pair_n20_a50.yaml --out runs/pair_n20_a50
      python -m train --config pair_n20_a50 --out runs/pair_n20_a50   # the packaged config
      python -m train --algo sac --set n_uavs=20 --set pair_accel_limit=50 \\
          --total-steps 300000 --hp buffer_size=200000 --out runs/sac
      python -m train --resume runs/pair_n20_a50          # continue from the latest checkpoint
      python -m train --resume runs/pair_n20_a50 --total-steps 2e7   # train a finished run on
      python -m train.evaluate runs/pair_n20_a50/final_model.zip --n-uavs 20 50 100
    """
)


def _seed_list(text: str) -> list[int]:
    """``1000-1009`` or ``1,2,5``."""
    try:
        if "-" in text:
            a, b = text.split("-", 1)
            lo, hi = int(a), int(b)
            if hi < lo:
                raise ValueError
            return list(range(lo, hi + 1))
        return [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is invalid: give a range like 1000-1009 or a list like 1,2,5"
        ) from None


def _task_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("task")
    g.add_argument(
        "--config",
        type=Path,
        metavar="YAML",
        help="settings file (keys of train.settings.RunSettings), or the name of a packaged "
        "one (e.g. pair_n20_a50: train/configs/pair_n20_a50.yaml); flags override it",
    )
    g.add_argument("--algo", choices=ALGOS, help="algorithm (default: ppo)")
    g.add_argument("--preset", help="pairflock_env preset (default: paper)")
    g.add_argument("--dynamics", help="vehicle model, e.g. particle (default: the preset's)")
    g.add_argument(
        "--set",
        dest="env_sets",
        action="append",
        default=[],
        metavar="FIELD=VALUE",
        help="PairFlockConfig override of the training task, repeatable "
        "(e.g. --set n_uavs=20 --set pair_accel_limit=50 --set max_cycles=2000)",
    )
    g.add_argument(
        "--eval-set",
        dest="eval_sets",
        action="append",
        default=[],
        metavar="FIELD=VALUE",
        help="override applied on top for evaluation only (e.g. --eval-set horizon=50)",
    )
    g.add_argument(
        "--num-swarms",
        type=int,
        help="swarms simulated side by side (default: 32); SB3 sees num_swarms x paired UAVs rows",
    )
    g = p.add_argument_group("learning interface")
    g.add_argument(
        "--interface",
        choices=("pair", "world"),
        help="what the policy sees and outputs (default: pair; see pairflock_env.interfaces)",
    )
    g.add_argument(
        "--interface-param",
        dest="interface_sets",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="PairInterfaceParams field, repeatable (e.g. --interface-param w_separation=2)",
    )


def _algorithm_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("algorithm")
    g.add_argument(
        "--total-steps",
        type=int_like,
        help="environment steps (rows x vector steps) to train for, e.g. 2e7",
    )
    g.add_argument("--seed", type=int, help="seed of the model, the swarms and SB3 (default: 0)")
    g.add_argument(
        "--hp",
        dest="hp_sets",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="SB3 hyperparameter, repeatable; nested with dots "
        "(e.g. --hp learning_rate=1e-3 --hp policy_kwargs.net_arch=[64,64])",
    )


def _schedule_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("schedule and output")
    g.add_argument("--out", type=Path, help="run directory (required unless --resume)")
    g.add_argument("--overwrite", action="store_true", help="replace a non-empty --out")
    g.add_argument(
        "--resume",
        type=Path,
        metavar="PATH",
        help="continue a run: its directory or a checkpoints/step_<N> directory; "
        "only --total-steps, --time-limit and --quiet may change",
    )
    g.add_argument("--eval-every", type=int_like, help="steps between evaluations (0: none)")
    g.add_argument(
        "--eval-seeds",
        type=_seed_list,
        metavar="SEEDS",
        help="evaluation seeds, e.g. 1000-1009 (default)",
    )
    g.add_argument(
        "--eval-baselines",
        nargs="*",
        metavar="NAME",
        help="analytic controllers evaluated once for comparison (default: smc proportional)",
    )
    g.add_argument("--checkpoint-every", type=int_like, help="steps between checkpoints (0: none)")
    g.add_argument("--keep-checkpoints", type=int, help="newest checkpoints kept (0: all)")
    g.add_argument(
        "--time-limit",
        type=float,
        metavar="MIN",
        help="stop cleanly (checkpoint, final model) after this many minutes",
    )
    g.add_argument("--no-tensorboard", action="store_true", help="CSV log only")
    g.add_argument("--quiet", action="store_true", help="no progress bar")


def build_parser() -> argparse.ArgumentParser:
    """The training CLI's argument parser."""
    p = ArgumentParser(
        prog="python -m train",
        description="Train a policy for the pairflock pair action slot with stable-baselines3 "
        "(PPO, SAC, TD3) on the native batched VecEnv, one row per paired UAV.",
        epilog=EPILOG
        + "\nsettings (the keys of --config files and of <out>/settings.yaml; flags set them "
        "too):\n" + settings_help(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _task_options(p)
    _algorithm_options(p)
    _schedule_options(p)
    return p


def _parse_sets(items: list[str], flag: str):
    return [parse_assignment(t, flag) for t in items]


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m train`` / ``pairflock-train``; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    with user_errors(parser), GracefulInterrupt() as interrupt:
        return _main(args, parser, interrupt)


#: options a resumed run may not change (it continues as it was set up)
_FIXED_ON_RESUME = (
    "config",
    "algo",
    "preset",
    "dynamics",
    "num_swarms",
    "interface",
    "seed",
    "eval_every",
    "eval_seeds",
    "eval_baselines",
    "checkpoint_every",
    "keep_checkpoints",
)


def _resume_settings(args: argparse.Namespace):
    """(settings, run directory) of ``--resume``."""
    changing = [name for name in _FIXED_ON_RESUME if getattr(args, name) is not None]
    changing += [
        f for f in ("env_sets", "eval_sets", "interface_sets", "hp_sets") if getattr(args, f)
    ]
    if changing or args.overwrite or args.no_tensorboard:
        raise ValueError(
            "--resume continues a run as it was set up; it cannot change "
            f"{changing or '--overwrite'} "
            "(only --total-steps, --time-limit and --quiet)"
        )
    run_dir = latest_checkpoint(args.resume).parent.parent
    if args.out is not None and Path(args.out).resolve() != run_dir.resolve():
        raise ValueError(f"--out {str(args.out)!r} differs from the resumed run {str(run_dir)!r}")
    data = load_yaml(run_dir / "settings.yaml")
    flags = {"total_steps": args.total_steps, "time_limit": args.time_limit}
    return settings_from_sources(data, flags), run_dir


def _new_settings(args: argparse.Namespace, parser: argparse.ArgumentParser):
    """Settings of a new run: defaults < ``--config`` < flags < assignments."""
    if args.out is None:
        parser.error("--out is required (or --resume RUN_DIR)")
    data = load_yaml(args.config) if args.config is not None else None
    flags = {
        "algo": args.algo,
        "preset": args.preset,
        "dynamics": args.dynamics,
        "interface": args.interface,
        "num_swarms": args.num_swarms,
        "total_steps": args.total_steps,
        "seed": args.seed,
        "eval_every": args.eval_every,
        "eval_seeds": args.eval_seeds,
        "eval_baselines": args.eval_baselines,
        "checkpoint_every": args.checkpoint_every,
        "keep_checkpoints": args.keep_checkpoints,
        "time_limit": args.time_limit,
        "tensorboard": False if args.no_tensorboard else None,
    }
    eval_sets = _parse_sets(args.eval_sets, "--eval-set")
    if eval_sets:
        flags["eval_env"] = {**dict((data or {}).get("eval_env", {})), **dict(eval_sets)}
    return settings_from_sources(
        data,
        flags,
        env_sets=_parse_sets(args.env_sets, "--set"),
        hp_sets=_parse_sets(args.hp_sets, "--hp"),
        interface_sets=_parse_sets(args.interface_sets, "--interface-param"),
    )


def _message(result, settings, out) -> str:
    if result.status == ALREADY_COMPLETE:
        return (
            f"{out} is complete: {result.num_timesteps} steps of {settings.total_steps}; "
            "nothing to do, nothing changed (raise --total-steps to train on)"
        )
    s = result.final_summary
    msg = f"{result.status}: {result.num_timesteps} steps in {result.wall_s / 60:.1f} min -> {out}"
    if s:
        tasks = f" (worst of {len(evaluation_tasks(settings))} tasks)" if is_mix(settings) else ""
        msg += (
            f"\nevaluation on seeds {settings.eval_seeds[0]}-{settings.eval_seeds[-1]}{tasks}: "
            f"steady error median {s['ss_error_median']:.3f} m, max {s['ss_error_max']:.3f} m; "
            f"in the 0.5 m band for good by {s['band_time_max']:.2f} s; min pair-other "
            f"distance {s['min_separation_min']:.2f} m"
        )
    return msg


def _main(args: argparse.Namespace, parser: argparse.ArgumentParser, interrupt) -> int:
    if args.resume is not None:
        settings, out = _resume_settings(args)
    else:
        settings, out = _new_settings(args, parser), args.out
    result = train(
        settings,
        out,
        resume=args.resume,
        quiet=args.quiet,
        overwrite=args.overwrite,
        interrupt=interrupt,
    )
    print(_message(result, settings, out), file=sys.stderr if args.quiet else sys.stdout)
    return 130 if result.interrupted else 0


if __name__ == "__main__":
    sys.exit(main())
