"""Training on a mix of tasks: the ``tasks`` and ``eval_tasks`` settings, resolved and checked.

A run may train one policy on several tasks at once (swarm sizes, start kinds, ...) and pick
its best model on several. In the settings (YAML)::

    env: {pair_accel_limit: 50.0, obs_neighbors: 12, max_cycles: 2000}   # shared by all
    num_swarms: 8                     # the swarms of a task that gives none
    tasks:                            # PairFlockConfig overrides on top of env, per task
      - {n_uavs: 20, init: corners, num_swarms: 8}
      - {n_uavs: 50, init: random, name: mid_random}
    eval_tasks:                       # optional; default: the training tasks
      - {n_uavs: 100, init: corners}
    eval_aggregate: worst             # worst | sum: how per-task scores become one

A task is a mapping of PairFlockConfig fields plus two keys of its own: ``num_swarms`` (training
tasks only) and ``name`` (default ``n<N>_<init>``, e.g. ``n20_corners``; it names the task's
columns in ``eval.csv``). The config of training task k is the preset, then ``env``, then the
task's fields. The config of evaluation task j is the preset, then ``env`` without its episode
length (``max_cycles``, ``horizon``), then ``eval_env``, then the task's fields (the default
evaluation tasks are the training tasks without their episode length and ``num_swarms``), so
evaluation runs the preset's episodes unless ``eval_env`` or the task sets a length.

Every task, for training or evaluation, must give the same observation and action spaces and
the same learning interface as the first training task (one network serves them all): the same
``pair_accel_limit``, ``dim`` and ``obs_neighbors`` (and ``radius``, which sets the interface's
default ``cohesion_distance``). Put these in ``env``.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping
from typing import Any

from pairflock_env import make_config
from pairflock_env.interfaces import make_interface

__all__ = [
    "AGGREGATES",
    "TASK_KEYS",
    "Task",
    "check_tasks",
    "evaluation_tasks",
    "is_mix",
    "task_entries",
    "task_fields",
    "training_tasks",
]

#: keys of a task that are not PairFlockConfig fields
TASK_KEYS = ("name", "num_swarms")
#: how the per-task scores of an evaluation become the run's one score
AGGREGATES = ("worst", "sum")
#: config fields the learning interface and the spaces depend on (named in errors)
INTERFACE_FIELDS = ("pair_accel_limit", "dim", "obs_neighbors", "radius", "dynamics")
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.=+-]*$")
_EPISODE_LENGTH = ("max_cycles", "horizon")


@dataclasses.dataclass(frozen=True)
class Task:
    """One resolved task: its name, its PairFlockConfig overrides (shared ones included) and,
    for a training task, its number of swarms (0 for an evaluation task)."""

    name: str
    overrides: dict[str, Any]
    num_swarms: int = 0

    def config(self, preset: str | None):
        """The task's validated PairFlockConfig."""
        return make_config(preset, **self.overrides)


def is_mix(settings: Any) -> bool:
    """Whether the run trains or evaluates on a list of tasks (else: one task, as before)."""
    return settings.tasks is not None or settings.eval_tasks is not None


def task_fields(entry: Any, where: str, allowed: tuple[str, ...]) -> dict[str, Any]:
    """The config fields of a task entry (its own keys checked and removed; ``allowed``: the
    keys of its own it may have)."""
    if not isinstance(entry, Mapping):
        raise TypeError(
            f"{where}={entry!r} is invalid: a task is a mapping of PairFlockConfig fields "
            f"(plus {', '.join(allowed)}), e.g. {{n_uavs: 20, init: corners}}"
        )
    if "preset" in entry:
        raise ValueError(f"{where}: key 'preset' is invalid: the preset is shared by all tasks")
    if "num_swarms" in entry and "num_swarms" not in allowed:
        raise ValueError(
            f"{where}: key 'num_swarms' is invalid: an evaluation task runs each of eval_seeds "
            "as one swarm (num_swarms belongs to training tasks)"
        )
    return {k: v for k, v in entry.items() if k not in TASK_KEYS}


def _name(entry: Mapping[str, Any], cfg: Any, where: str) -> str:
    name = entry.get("name", f"n{cfg.n_uavs}_{cfg.init}")
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(
            f"{where}: name={name!r} is invalid: a non-empty text of letters, digits and "
            "_ . = + - (it names the task's evaluation columns)"
        )
    return name


def _num_swarms(entry: Mapping[str, Any], default: int, where: str) -> int:
    v = entry.get("num_swarms", default)
    if isinstance(v, bool) or not isinstance(v, int):
        raise TypeError(f"{where}: num_swarms={v!r} is invalid: must be an integer")
    if v < 1:
        raise ValueError(f"{where}: num_swarms={v!r} is invalid: must be >= 1")
    return v


def _config(preset: str | None, overrides: Mapping[str, Any], where: str):
    """make_config with the task named in its error (same exception type)."""
    try:
        return make_config(preset, **overrides)
    except (TypeError, ValueError) as e:
        raise type(e)(f"{where}: {e}") from None


def task_entries(value: Any, key: str) -> list[Any]:
    """The entries of the ``tasks``/``eval_tasks`` setting ``key``: a non-empty list."""
    if not isinstance(value, list):
        raise TypeError(
            f"{key}={value!r} is invalid: must be a list of tasks (mappings), e.g. "
            "[{n_uavs: 20, init: corners}, {n_uavs: 50, init: random}]"
        )
    if not value:
        raise ValueError(f"{key}=[] is invalid: give at least one task (or leave {key} out)")
    return value


def _unique(tasks: list[Task], key: str) -> list[Task]:
    seen: dict[str, int] = {}
    for i, t in enumerate(tasks):
        if t.name in seen:
            raise ValueError(
                f"{key}[{i}] and {key}[{seen[t.name]}] have the same name {t.name!r}: give "
                "each task its own `name`"
            )
        seen[t.name] = i
    return tasks


def training_tasks(settings: Any) -> list[Task] | None:
    """The resolved training tasks, or None for a run on one task (``tasks`` not given)."""
    if settings.tasks is None:
        return None
    shared = settings.config_overrides()
    out = []
    for i, entry in enumerate(task_entries(settings.tasks, "tasks")):
        where = f"tasks[{i}]"
        over = {**shared, **task_fields(entry, where, TASK_KEYS)}
        cfg = _config(settings.preset, over, where)
        n = _num_swarms(entry, settings.num_swarms, where)
        out.append(Task(_name(entry, cfg, where), over, n))
    return _unique(out, "tasks")


def evaluation_tasks(settings: Any) -> list[Task]:
    """The resolved evaluation tasks: ``eval_tasks``, else the training tasks, else the one
    evaluation task of :meth:`~train.settings.RunSettings.eval_overrides` (name ``""``)."""
    if settings.eval_tasks is None and settings.tasks is None:
        return [Task("", settings.eval_overrides())]
    key = "eval_tasks" if settings.eval_tasks is not None else "tasks"
    entries = task_entries(settings.eval_tasks if key == "eval_tasks" else settings.tasks, key)
    base = settings.eval_overrides()
    out = []
    for i, entry in enumerate(entries):
        where = f"{key}[{i}]"
        own = task_fields(entry, where, ("name",) if key == "eval_tasks" else TASK_KEYS)
        if key == "tasks":  # a training task, evaluated with the evaluation's episode length
            own = {k: v for k, v in own.items() if k not in _EPISODE_LENGTH}
        over = {**base, **own}
        cfg = _config(settings.preset, over, where)
        out.append(Task(_name(entry, cfg, where), over))
    return _unique(out, key)


def _interface(settings: Any, cfg: Any, where: str):
    try:
        return make_interface(settings.interface, cfg, **settings.interface_params)
    except (TypeError, ValueError) as e:
        raise type(e)(f"{where}: {e}") from None


def _signature(interface: Any) -> tuple:
    """What one network needs to be the same across tasks: spaces and interface."""
    low, high = interface.observation_bounds()
    return (low.tolist(), high.tolist(), interface.config.dim, interface.to_dict())


def _mismatch(where: str, ref_where: str, iface: Any, ref: Any) -> ValueError:
    a, b = iface.to_dict(), ref.to_dict()
    parts = [f"observation size {iface.observation_size} vs {ref.observation_size}"]
    parts += [f"interface {k}={a.get(k)!r} vs {b.get(k)!r}" for k in a if a.get(k) != b.get(k)]
    ca, cb = iface.config, ref.config
    parts += [
        f"{k}={getattr(ca, k)!r} vs {getattr(cb, k)!r}"
        for k in INTERFACE_FIELDS
        if getattr(ca, k) != getattr(cb, k)
    ]
    return ValueError(
        f"{where} gives other observation/action spaces or another learning interface than "
        f"{ref_where} ({'; '.join(parts)}). Every task must give the same observation/action "
        "spaces and the same learning interface: the same pair_accel_limit, dim and "
        "obs_neighbors (and radius, unless interface_params sets cohesion_distance); set "
        "them in env, shared by all tasks"
    )


def check_tasks(settings: Any) -> None:
    """Resolve ``tasks`` and ``eval_tasks`` against the rest of the settings: every task's
    config builds and gives the first training task's spaces and learning interface
    (TypeError / ValueError naming the task index and key); a check of
    :class:`~train.settings.RunSettings`."""
    if not is_mix(settings):
        return
    train = training_tasks(settings)
    evals = evaluation_tasks(settings)
    if train is None:
        ref_where, ref_cfg = "the training task (env)", settings.config_overrides()
    else:
        ref_where, ref_cfg = "tasks[0]", train[0].overrides
    ref = _interface(settings, _config(settings.preset, ref_cfg, ref_where), ref_where)
    key = "eval_tasks" if settings.eval_tasks is not None else "tasks"
    named = [(f"tasks[{i}]", t) for i, t in enumerate(train or [])]
    named += [(f"{key}[{j}] (evaluation)", t) for j, t in enumerate(evals)]
    for where, task in named:
        iface = _interface(settings, _config(settings.preset, task.overrides, where), where)
        if _signature(iface) != _signature(ref):
            raise _mismatch(where, ref_where, iface, ref)
