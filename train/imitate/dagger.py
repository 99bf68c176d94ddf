"""DAgger on one run: an analytic pair controller cloned into the run's policy network.

:func:`imitate` builds the run of a training config for one seed (its task or task mix,
learning interface, network and seed, exactly as ``python -m train`` would; ``init_model``
is ignored) and fits the policy network's mean action to a teacher's commands with DAgger
(Ross, Gordon and Bagnell, 2011):

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
the network's command in the loop as it will in evaluation. Only the actor is fitted; the
value head stays as initialised. The model is evaluated the way ``python -m train`` selects
its best model (:func:`validation_summary`). :mod:`train.imitate.cli` runs every seed.
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch

from baselines.controllers import make_pair_policy
from baselines.reporting.criteria import TARGETS
from baselines.runtime.threads import pin_threads
from train.mix.evaluation import score_function
from train.mix.tasks import evaluation_tasks
from train.model import METADATA_KEY, build_model, metadata, save_model_atomic
from train.run import evaluate_model, make_vec_env
from train.settings import load_yaml, resolve_config, settings_from_sources

__all__ = [
    "collect",
    "dagger",
    "fit",
    "imitate",
    "mse",
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
    pin_threads()

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
    cfgs = {t.name: t.config(settings.preset) for t in evaluation_tasks(settings)}
    targets = TARGETS[settings.eval_targets]
    _, summary = evaluate_model(model, interface, cfgs, settings.eval_seeds, targets)
    summary["score"] = float(score_function(settings)(summary))
    return summary
