"""``python -m train.imitate``: the imitation warm start of every seed, its summary and the
command line.

    python -m train.imitate --config pair_safe_a50 --teacher braking --gain detour=80 \\
        --seeds 0 1 2 3 4 --workers 2 --set safety_brake_accel=40 \\
        --set safety_other_accel=20 --set safety_margin=0 --out runs/imitate_safe

builds the run of a training config for each seed (its task or task mix, learning interface,
network and seed, exactly as ``python -m train`` would; ``init_model`` is ignored) and fits
the policy network's mean action to a teacher's commands with DAgger
(:mod:`train.imitate.dagger`). Each seed's model is then evaluated the way ``python -m train``
selects its best model (the config's evaluation tasks, seeds and targets). Written to ``OUT``:

* ``seed_<s>/model.zip``: an ordinary model of the run (same spaces, metadata and interface
  as ``python -m train`` writes, plus how it was made under ``imitation``):
  ``make_pair_policy("sb3:OUT/seed_0/model.zip", env)``, ``python -m train.evaluate`` and
  ``init_model:`` (PPO fine-tuning) all take it; ``seed_<s>/imitation.json``: the settings,
  the loss per round, the time and the validation summary;
* ``summary.md``: each seed's validation (worst task) and IQM [95 % CI] over the seeds;
* ``best_model.zip``: the model of the seed with the best validation score.
"""

from __future__ import annotations

import argparse
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from baselines.controllers import make_pair_policy
from baselines.evaluation.specs import parse_assignment
from baselines.reporting.stats import iqm_ci
from baselines.runtime.cli import ArgumentParser, at_least, user_errors
from baselines.runtime.pool import imap_unordered
from pairflock_env import make_config
from train.imitate.dagger import _settings, imitate
from train.mix.tasks import training_tasks

__all__ = ["SEED_METRICS", "build_parser", "imitate_seeds", "main", "seed_summary"]


#: the worst-task validation metrics the seed summary reports (name, unit)
SEED_METRICS = (
    ("score", "-"),
    ("ss_error_median", "m"),
    ("ss_error_max", "m"),
    ("band_time_median", "s"),
    ("band_time_max", "s"),
    ("min_separation_min", "m"),
    ("peak_accel_max", "m/s^2"),
)


def seed_summary(records: Sequence[dict[str, Any]]) -> tuple[str, int]:
    """Markdown of the validation of every seed and IQM [95 % CI] over seeds (rliable,
    :func:`baselines.reporting.stats.iqm_ci`); and the seed with the best (lowest) score."""
    rows = sorted(records, key=lambda r: r["seed"])
    vals = np.array([[r["validation"][k] for k, _ in SEED_METRICS] for r in rows], float)
    best = rows[int(np.argmin(vals[:, 0]))]["seed"]
    head = "| seed | " + " | ".join(f"{k} ({u})" for k, u in SEED_METRICS) + " |"
    lines = [head, "|---" * (len(SEED_METRICS) + 1) + "|"]
    lines += ["| " + " | ".join([str(r["seed"]), *(f"{v:.4g}" for v in row)]) + " |"
              for r, row in zip(rows, vals, strict=True)]  # fmt: skip
    if np.isfinite(vals).all():
        point, low, high = iqm_ci(vals)
        cells = [
            f"{p:.4g} [{lo:.4g}, {hi:.4g}]" for p, lo, hi in zip(point, low, high, strict=True)
        ]
        lines.append("| IQM [95 % CI] | " + " | ".join(cells) + " |")
    text = (
        "Validation of each seed (worst of the evaluation tasks, the run's evaluation seeds);\n"
        f"selected: seed {best} (lowest score).\n\n" + "\n".join(lines) + "\n"
    )
    return text, best


def _one_seed(config: str, out: str, seed: int, kwargs: dict[str, Any]) -> dict[str, Any]:
    return imitate(config, Path(out) / f"seed_{seed}", seed=seed, **kwargs)


def imitate_seeds(
    config: str, out: Path, seeds: Sequence[int], *, workers: int = 1, **kwargs: Any
) -> dict[str, Any]:
    """:func:`imitate` for every seed (``out/seed_<s>``, ``workers`` processes), then
    ``out/summary.md`` (:func:`seed_summary`) and ``out/best_model.zip``, the model of the
    seed with the best validation score; returns ``{"seeds": records, "best": seed}``."""

    kwargs = {**kwargs, "validate": True}
    tasks = [(str(config), str(out), int(s), kwargs) for s in seeds]
    records = [rec for _, rec in imap_unordered(_one_seed, tasks, workers)]
    text, best = seed_summary(records)
    (out / "summary.md").write_text(text)
    shutil.copyfile(out / f"seed_{best}" / "model.zip", out / "best_model.zip")
    return {"seeds": records, "best": best}


def build_parser() -> argparse.ArgumentParser:
    """The command line of ``python -m train.imitate``."""
    p = ArgumentParser(
        prog="python -m train.imitate",
        description=__doc__.split("\n\n")[0].replace("\n", " "),
        epilog="Writes OUT/seed_<s>/model.zip, OUT/summary.md and OUT/best_model.zip; "
        "evaluate a model on held-out seeds with python -m train.evaluate.",
    )
    p.add_argument("--config", required=True, help="training config (name or YAML path)")
    p.add_argument("--teacher", default="braking", help="controller name (make_pair_policy)")
    p.add_argument("--gain", action="append", default=[], metavar="NAME=VALUE",
                   help="teacher gain (repeatable)")  # fmt: skip
    p.add_argument("--seeds", type=at_least(0), nargs="+", default=[0],
                   help="run seeds (envs, network, shuffling); default 0")  # fmt: skip
    p.add_argument("--workers", type=int, default=1, help="processes, one seed each")
    p.add_argument("--iterations", type=int, default=5,
                   help="DAgger rounds (first: teacher)")  # fmt: skip
    p.add_argument("--decisions", type=int, default=800,
                   help="decisions per row per round")  # fmt: skip
    p.add_argument("--epochs", type=int, default=25,
                   help="passes over the data per round")  # fmt: skip
    p.add_argument("--lr", type=float, default=1e-3, help="Adam learning rate")
    p.add_argument("--batch", type=int, default=4096, help="minibatch size")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="FIELD=VALUE",
                   help="env override for every task (repeatable)")  # fmt: skip
    p.add_argument("--eval-set", dest="eval_sets", action="append", default=[],
                   metavar="FIELD=VALUE",
                   help="validation-only override, on top of --set (repeatable)")  # fmt: skip
    p.add_argument("--out", type=Path, required=True, help="output folder")
    p.add_argument("--quiet", action="store_true", help="no per-round lines")
    return p


def _checked(args: argparse.Namespace) -> dict[str, Any]:
    """The options as :func:`imitate_seeds` takes them, checked before anything runs: every
    seed's run builds (config, ``--set``, ``--eval-set``) and so does the teacher with its
    gains on every training task (``TypeError``/``ValueError`` naming the bad one)."""
    for name in ("iterations", "decisions", "epochs", "batch", "workers"):
        if getattr(args, name) < 1:
            raise ValueError(f"--{name}={getattr(args, name)} is invalid: must be >= 1")
    if not args.lr > 0:
        raise ValueError(f"--lr={args.lr} is invalid: must be > 0")
    if len(set(args.seeds)) != len(args.seeds):
        raise ValueError(f"--seeds {args.seeds} is invalid: the seeds must differ")
    gains = dict(parse_assignment(item, "--gain") for item in args.gain)
    env_sets = [parse_assignment(item, "--set") for item in args.sets]
    eval_sets = [parse_assignment(item, "--eval-set") for item in args.eval_sets]
    for seed in args.seeds:
        settings = _settings(args.config, seed, env_sets, eval_sets)
    tasks = training_tasks(settings)
    for cfg in (
        [t.config(settings.preset) for t in tasks]
        if tasks
        else [make_config(settings.preset, **settings.config_overrides())]
    ):
        try:
            make_pair_policy(args.teacher, cfg, **gains)
        except (TypeError, ValueError) as e:
            raise type(e)(f"--teacher {args.teacher!r} with --gain {gains}: {e}") from None
    return dict(teacher=args.teacher, gains=gains, env_sets=env_sets, eval_sets=eval_sets)


def main(argv: Sequence[str] | None = None) -> int:
    """Imitate on every seed and print the summary; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    with user_errors(parser):
        options = _checked(args)
    result = imitate_seeds(
        args.config, args.out, args.seeds, workers=args.workers, iterations=args.iterations,
        decisions=args.decisions, epochs=args.epochs, lr=args.lr, batch=args.batch,
        quiet=args.quiet, **options,
    )  # fmt: skip
    print((args.out / "summary.md").read_text())
    print(f"wrote {args.out / 'best_model.zip'} (seed {result['best']})")
    return 0
