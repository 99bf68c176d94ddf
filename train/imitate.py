"""Imitation warm start: clone an analytic pair controller into the run's policy network.

    python -m train.imitate --config pair_safe_a50 --teacher braking --gain detour=80 \\
        --seeds 0 1 2 3 4 --workers 2 --set safety_brake_accel=40 \\
        --set safety_other_accel=20 --set safety_margin=0 --out runs/imitate_safe

builds the run of a training config for each seed (its task or task mix, learning interface,
network and seed, exactly as ``python -m train`` would; ``init_model`` is ignored) and fits
the policy network's mean action to a teacher's commands with DAgger (Ross, Gordon and
Bagnell, 2011):

1. the teacher flies the training envs for ``--decisions`` policy decisions per row, each of
   its world-frame commands turned into the network's pair-frame action by the interface's
   inverse (:meth:`~pairflock_env.interfaces.PairInterface.action_for`) and held for the
   interface's decision period, exactly like a network action;
2. the network is fitted to every (encoded observation, teacher action) pair collected so far
   (mean squared error of the Gaussian's mean, Adam, ``--epochs`` passes, the learning rate
   falling linearly to 1 % of ``--lr``);
3. the *network* then flies for ``--iterations - 1`` more rounds, every state it visits
   labelled with the teacher's action, and is refitted on the growing dataset after each.

The teacher is labelled with its own (nominal) command; a safety filter in the config acts on
the network's command in the loop as it will in evaluation. Each seed's model is then
evaluated the way ``python -m train`` selects its best model (the config's evaluation tasks,
seeds and targets). Written to ``OUT``:

* ``seed_<s>/model.zip``: an ordinary model of the run (same spaces, metadata and interface
  as ``python -m train`` writes, plus how it was made under ``imitation``):
  ``make_pair_policy("sb3:OUT/seed_0/model.zip", env)``, ``python -m train.evaluate`` and
  ``init_model:`` (PPO fine-tuning) all take it; ``seed_<s>/imitation.json``: the settings,
  the loss per round, the time and the validation summary;
* ``summary.md``: each seed's validation (worst task) and IQM [95 % CI] over the seeds;
* ``best_model.zip``: the model of the seed with the best validation score.

Only the actor is fitted; the value head stays as initialised.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "build_parser",
    "collect",
    "dagger",
    "fit",
    "imitate",
    "imitate_seeds",
    "main",
    "mse",
    "seed_summary",
    "teacher_actions",
    "validation_summary",
]


def _task_envs(venv: Any) -> list[Any]:
    """The PairFlockSB3VecEnv of each task, in row order (one for a single-task run)."""
    inner = venv.unwrapped
    return list(getattr(inner, "envs", [inner]))


def teacher_actions(venv: Any, teachers: Sequence[Any]) -> np.ndarray:
    """The teacher's network action (num_envs, dim) for every row's current state."""
    out = []
    for env, teacher in zip(_task_envs(venv), teachers, strict=True):
        raw = env.physical_obs.reshape(env.num_envs, -1)
        out.append(env.interface.action_for(raw, teacher.accel(raw)))
    return np.concatenate(out).astype(np.float32)


def collect(venv: Any, obs: np.ndarray, teachers, act, decisions: int):
    """Fly ``decisions`` decisions with ``act(obs, teacher_action)`` choosing the action;
    returns (observations, teacher actions, the last observation)."""
    xs, ys = [], []
    for _ in range(decisions):
        target = teacher_actions(venv, teachers)
        xs.append(obs.copy())
        ys.append(target)
        obs, _, _, _ = venv.step(act(obs, target))
    return np.concatenate(xs), np.concatenate(ys), obs


def _mean_action(policy: Any, x: Any) -> Any:
    features = policy.extract_features(x, policy.pi_features_extractor)
    return policy.action_net(policy.mlp_extractor.forward_actor(features))


def fit(
    policy: Any, x: np.ndarray, y: np.ndarray, *, epochs: int, lr: float, batch: int, rng
) -> float:
    """Fit the actor's mean to ``y`` on ``x``; returns the last epoch's mean squared error."""
    import torch

    params = [*policy.mlp_extractor.policy_net.parameters(), *policy.action_net.parameters()]
    opt = torch.optim.Adam(params, lr=lr)
    per_epoch = -(-len(x) // batch)
    # linear decay to 1 % of lr over the fit: the last passes refine the small actions near
    # the target, where a policy's bias becomes steady-state error
    sched = torch.optim.lr_scheduler.LambdaLR(
        opt, lambda k: max(0.01, 1.0 - k / (epochs * per_epoch))
    )
    xt, yt = torch.as_tensor(x), torch.as_tensor(y)
    policy.set_training_mode(True)
    loss_sum = 0.0
    for _ in range(epochs):
        order = torch.as_tensor(rng.permutation(len(x)))
        loss_sum = 0.0
        for start in range(0, len(x), batch):
            idx = order[start : start + batch]
            loss = torch.mean((_mean_action(policy, xt[idx]) - yt[idx]) ** 2)
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            loss_sum += float(loss.detach()) * len(idx)
    policy.set_training_mode(False)
    return loss_sum / len(x)


def mse(policy: Any, x: np.ndarray, y: np.ndarray) -> float:
    """Mean squared error of the actor's mean action against ``y``."""
    import torch

    with torch.no_grad():
        return float(
            torch.mean((_mean_action(policy, torch.as_tensor(x)) - torch.as_tensor(y)) ** 2)
        )


def dagger(
    model: Any,
    venv: Any,
    teachers,
    *,
    iterations: int,
    decisions: int,
    rng,
    quiet: bool,
    **fit_kw: Any,
) -> dict[str, Any]:
    """The DAgger rounds of the module docstring on ``model``'s policy (in place); returns
    the sample count and the loss before the first fit and after each."""
    obs = venv.reset()
    xs, ys, losses = [], [], []
    for it in range(iterations):
        if it == 0:
            act = lambda o, target: target  # noqa: E731 - the teacher flies
        else:
            act = lambda o, target: model.predict(o, deterministic=True)[0]  # noqa: E731
        x, y, obs = collect(venv, obs, teachers, act, decisions)
        xs.append(x)
        ys.append(y)
        if it == 0:
            before = mse(model.policy, x, y)
        losses.append(fit(model.policy, np.concatenate(xs), np.concatenate(ys), rng=rng, **fit_kw))
        if not quiet:
            print(f"round {it + 1}/{iterations}: {sum(map(len, xs))} samples, mse {losses[-1]:.2e}")
    return {"samples": int(sum(map(len, xs))), "mse_before": before, "mse": losses}


def _settings(config: str, seed: int, env_sets: list[tuple[str, Any]], eval_sets):
    from train.settings import load_yaml, resolve_config, settings_from_sources

    data = dict(load_yaml(resolve_config(config)))
    data.pop("init_model", None)  # imitation starts from the run's fresh network
    flags: dict[str, Any] = {"seed": seed}
    if eval_sets:  # as python -m train --eval-set: on top of the config's eval_env
        flags["eval_env"] = {**dict(data.get("eval_env", {})), **dict(eval_sets)}
    return settings_from_sources(data, flags, env_sets=env_sets)


def imitate(
    config: str,
    out: Path,
    *,
    teacher: str = "braking",
    gains: dict[str, Any] | None = None,
    seed: int = 0,
    iterations: int = 5,
    decisions: int = 800,
    epochs: int = 25,
    lr: float = 1e-3,
    batch: int = 4096,
    env_sets: list[tuple[str, Any]] = (),
    eval_sets: list[tuple[str, Any]] = (),
    quiet: bool = False,
    validate: bool = False,
) -> dict[str, Any]:
    """Clone ``teacher`` into the policy of ``config``'s run; writes ``out/model.zip`` and
    ``out/imitation.json`` and returns the record (with ``validate``, also the run's own
    evaluation of the model: :func:`validation_summary`)."""
    from baselines.controllers import make_pair_policy
    from baselines.evaluation.parallel import pin_threads

    pin_threads(load_torch=True)
    from train.model import METADATA_KEY, build_model, metadata, save_model_atomic
    from train.run import make_vec_env

    t0 = time.perf_counter()
    settings = _settings(config, seed, list(env_sets), list(eval_sets))
    venv = make_vec_env(settings)
    model = build_model(settings, venv)
    teachers = [make_pair_policy(teacher, env.config, **(gains or {})) for env in _task_envs(venv)]
    fits = dagger(
        model, venv, teachers, iterations=iterations, decisions=decisions, epochs=epochs,
        lr=lr, batch=batch, rng=np.random.default_rng(seed), quiet=quiet,
    )  # fmt: skip
    out.mkdir(parents=True, exist_ok=True)
    cfg = _task_envs(venv)[0].config
    record = {
        "config": str(config), "teacher": teacher, "gains": gains or {}, "seed": seed,
        "iterations": iterations, "decisions": decisions, "epochs": epochs, "lr": lr,
        "batch": batch, **fits, "wall_s": round(time.perf_counter() - t0, 1),
    }  # fmt: skip
    interface = venv.unwrapped.interface
    venv.close()
    meta = metadata(settings, interface, cfg)
    setattr(model, METADATA_KEY, {**meta, "imitation": record})  # how the weights were made
    save_model_atomic(model, out / "model.zip")
    if validate:
        record["validation"] = validation_summary(model, settings, interface)
    (out / "imitation.json").write_text(json.dumps(record, indent=2) + "\n")
    return record


def validation_summary(model: Any, settings: Any, interface: Any) -> dict[str, float]:
    """The run's own evaluation of ``model`` (its evaluation tasks and seeds, full episodes)
    and the score ``python -m train`` keeps its best model by (lower is better)."""
    from baselines.reporting.criteria import TARGETS
    from train.mix_eval import score_function
    from train.run import evaluate_model
    from train.tasks import evaluation_tasks

    cfgs = {t.name: t.config(settings.preset) for t in evaluation_tasks(settings)}
    targets = TARGETS[settings.eval_targets]
    _, summary = evaluate_model(model, interface, cfgs, settings.eval_seeds, targets)
    summary["score"] = float(score_function(settings)(summary))
    return summary


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
    :func:`train.sweep_stats.iqm_ci`); and the seed with the best (lowest) score."""
    from train.sweep_stats import iqm_ci

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
    import shutil

    from baselines.evaluation.parallel import imap_unordered

    kwargs = {**kwargs, "validate": True}
    tasks = [(str(config), str(out), int(s), kwargs) for s in seeds]
    records = [rec for _, rec in imap_unordered(_one_seed, tasks, workers)]
    text, best = seed_summary(records)
    (out / "summary.md").write_text(text)
    shutil.copyfile(out / f"seed_{best}" / "model.zip", out / "best_model.zip")
    return {"seeds": records, "best": best}


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m train.imitate",
        description=__doc__.split("\n\n")[0],
        epilog="Writes OUT/seed_<s>/model.zip, OUT/summary.md and OUT/best_model.zip; "
        "evaluate a model on held-out seeds with python -m train.evaluate.",
    )
    p.add_argument("--config", required=True, help="training config (name or YAML path)")
    p.add_argument("--teacher", default="braking", help="controller name (make_pair_policy)")
    p.add_argument("--gain", action="append", default=[], metavar="NAME=VALUE",
                   help="teacher gain (repeatable)")  # fmt: skip
    p.add_argument("--seeds", type=int, nargs="+", default=[0],
                   help="run seeds (envs, network, shuffling); default 0")  # fmt: skip
    p.add_argument("--workers", type=int, default=1, help="processes, one seed each")
    p.add_argument("--iterations", type=int, default=5, help="DAgger rounds (first: teacher)")
    p.add_argument("--decisions", type=int, default=800, help="decisions per row per round")
    p.add_argument("--epochs", type=int, default=25, help="passes over the data per round")
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


def _pairs(items: list[str], flag: str, parser: argparse.ArgumentParser) -> list[tuple]:
    from baselines.evaluation.specs import parse_assignment

    try:
        return [parse_assignment(item, flag) for item in items]
    except ValueError as e:
        parser.error(str(e))


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    for name in ("iterations", "decisions", "epochs", "batch", "workers"):
        if getattr(args, name) < 1:
            parser.error(f"--{name}={getattr(args, name)} is invalid: must be >= 1")
    if not args.lr > 0:
        parser.error(f"--lr={args.lr} is invalid: must be > 0")
    if len(set(args.seeds)) != len(args.seeds):
        parser.error(f"--seeds {args.seeds} is invalid: the seeds must differ")
    result = imitate_seeds(
        args.config, args.out, args.seeds, workers=args.workers, teacher=args.teacher,
        gains=dict(_pairs(args.gain, "--gain", parser)), iterations=args.iterations,
        decisions=args.decisions, epochs=args.epochs, lr=args.lr, batch=args.batch,
        env_sets=_pairs(args.sets, "--set", parser),
        eval_sets=_pairs(args.eval_sets, "--eval-set", parser), quiet=args.quiet,
    )  # fmt: skip
    print((args.out / "summary.md").read_text())
    print(f"wrote {args.out / 'best_model.zip'} (seed {result['best']})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
