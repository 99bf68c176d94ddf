"""Everything a training run is built from: :class:`RunSettings`, one frozen, validated record.

A run is the task (preset, dynamics, config overrides, number of swarms), the learning
interface (``interface`` and its parameters), the algorithm and its stable-baselines3
hyperparameters, the schedule (total steps, evaluation, checkpoints) and the seed. Each setting
is a :class:`~pairflock_env.config.fields.Field` declared below with the env config's field
kinds and record machinery (:func:`~pairflock_env.config.schema.declare_record`), so a
setting is checked, named in errors and documented (:func:`settings_help`, in ``python -m
train --help``) from one declaration. The checks between settings - the task's configs build,
the interface fits the task, every task of a mix gives the same spaces, the hyperparameters
fit the algorithm - run with them, so an accepted ``RunSettings`` is a run that starts.

The CLI builds it from defaults, then a YAML file (``--config``), then flags
(:func:`settings_from_sources`), and stores the result in the run directory, so ``--config
<run>/settings.yaml`` reruns it. YAML layout (every key optional; see
``train/configs/*.yaml``, which ship with the package: ``--config pair_n20_a50`` names one,
:func:`resolve_config`)::

    algo: ppo                  # ppo | sac | td3
    preset: paper
    env:                       # PairFlockConfig overrides (validated by make_config)
      n_uavs: 20
      pair_accel_limit: 50.0
    eval_env: {horizon: 50.0}  # overrides applied on top of env for evaluation
    interface: pair            # pair | world (the learning interface)
    interface_params: {}       # PairInterfaceParams fields
    num_swarms: 32
    tasks:                     # optional: train on a mix (train/mix/tasks.py, docs/learning.md)
      - {n_uavs: 20, init: corners, num_swarms: 8}
    eval_tasks: null           # optional: select on a mix (default: the training tasks)
    eval_aggregate: worst      # worst | sum of the per-task scores
    eval_targets: learned      # learned | generalist: the targets the best model is kept by
    init_model: null           # optional: start from this model's weights (path or packaged name)
    total_steps: 20000000
    seed: 0
    hyperparameters:           # SB3 constructor keyword arguments for the algorithm
      learning_rate: 3e-4      # or lin_3e-4: linear decay to 0 (also clip_range)
      policy_kwargs: {net_arch: [128, 128], log_std_init: -1.0}

Numbers are read as written, also in exponent form without a point (``3e-4``, ``5e1``),
in files and in ``--set``/``--hp``/``--interface-param`` values alike. Model files store the
settings (:meth:`RunSettings.from_dict` reads older ones through
:func:`pairflock_env.compat.upgrade_stored`).
"""

from __future__ import annotations

import copy
import difflib
import math
import re
import textwrap
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import yaml

from baselines.controllers.zoo import find_packaged, packaged_names
from baselines.reporting.criteria import TARGETS
from pairflock_env import make_config
from pairflock_env.compat import upgrade_stored
from pairflock_env.config.fields import Choice, Field, Flag, Int, OrNone, Real, fmt_num
from pairflock_env.config.schema import Record, Schema, Section, declare_record
from pairflock_env.interfaces import INTERFACES, make_interface
from train.fields import ControllerNames, ModelFile, Overrides, SeedList, TaskList, Text
from train.hyperparameters import ALGOS, algo_hyperparameters, check_hyperparameters
from train.mix.tasks import AGGREGATES, TASK_KEYS, check_tasks

__all__ = [
    "RUN_SCHEMA",
    "RunSettings",
    "config_names",
    "env_interface_kwargs",
    "load_yaml",
    "resolve_config",
    "settings_from_sources",
    "settings_help",
]

_MANY = 10**12  # a count no run reaches (the upper end of the integer settings)

SECTIONS = (
    Section("task", "The task and the algorithm", "", (
        Field("algo", Choice(ALGOS), "ppo", "", "algorithm (stable-baselines3)"),
        Field("preset", Text("a preset's name"), "paper", "", "pairflock_env preset"),
        Field("dynamics", OrNone(Text("a vehicle model's name"), "the preset's"), None, "",
              "vehicle model, e.g. particle"),
        Field("env", Overrides("PairFlockConfig fields"), {}, "",
              "config overrides of the training task"),
        Field("eval_env", Overrides("PairFlockConfig fields"), {}, "",
              "overrides on top of env, for evaluation only"),
    )),
    Section("interface", "The learning interface", "", (
        Field("interface", Choice(tuple(INTERFACES)), "pair", "",
              "what the policy sees and outputs (pairflock_env.interfaces)"),
        Field("interface_params", Overrides("the interface's parameters"), {}, "",
              "parameters of the interface, e.g. {w_separation: 2}"),
    )),
    Section("training", "Training", "", (
        Field("num_swarms", Int(1, _MANY), 32, "",
              "swarms side by side; SB3 sees num_swarms x paired UAVs rows"),
        Field("total_steps", Int(1, _MANY), 1_000_000, "decisions",
              "environment steps (rows x vector steps) to train for"),
        Field("seed", Int(0, 2**63 - 1), 0, "", "seed of the model, the swarms and SB3"),
        Field("hyperparameters", Overrides("SB3 keyword arguments"), {}, "",
              "on top of the algorithm's defaults (train.hyperparameters)"),
    )),
    Section("schedule", "Evaluation, checkpoints and output", "", (
        Field("eval_every", Int(0, _MANY), 1_000_000, "decisions",
              "between evaluations (0: none)"),
        Field("eval_seeds", SeedList(), list(range(1000, 1010)), "",
              "evaluation seeds (full episodes each)"),
        Field("eval_baselines", ControllerNames(), ["smc", "proportional"], "",
              "analytic controllers evaluated once for comparison"),
        Field("checkpoint_every", Int(0, _MANY), 1_000_000, "decisions",
              "between checkpoints (0: none)"),
        Field("keep_checkpoints", Int(0, _MANY), 3, "", "newest checkpoints kept (0: all)"),
        Field("tensorboard", Flag(), True, "", "a TensorBoard log next to the CSV one"),
        Field("time_limit", OrNone(Real(0.0, math.inf, lo_open=True, hi_open=True), "none"),
              None, "min", "stop cleanly (checkpoint, final model) after this long"),
    )),
    Section("mix", "Task mix, selection and warm start", "", (
        Field("tasks", OrNone(TaskList(TASK_KEYS), "one task: env"), None, "",
              "train on a mix of tasks (train/mix/tasks.py)"),
        Field("eval_tasks", OrNone(TaskList(("name",)), "the training tasks"), None, "",
              "select the best model on these tasks"),
        Field("eval_aggregate", Choice(AGGREGATES), "worst", "",
              "how the per-task scores become one"),
        Field("eval_targets", Choice(tuple(TARGETS)), "learned", "",
              "the targets the best model is kept by (baselines.reporting.criteria)"),
        Field("init_model", OrNone(ModelFile(), "a fresh network"), None, "",
              "start from this model's weights (fine-tuning)"),
    )),
)  # fmt: skip
RUN_SCHEMA = Schema("run setting", SECTIONS)
#: settings a run on one task stores only when they are set (it stores what it stored before
#: they existed)
_STORED_WHEN_SET = ("tasks", "eval_tasks", "eval_aggregate", "eval_targets", "init_model")


def env_interface_kwargs(interface: str, params: Mapping[str, Any]) -> dict[str, Any]:
    """The keyword arguments that choose the learning interface on the env constructors.

    The one place that knows the env's keyword names.
    """
    return {"interface": interface, "interface_params": dict(params)}


class _RunSettingsMethods(Record):
    """What a run's settings derive, and the checks between them."""

    stored_as = "settings"

    def _fill(self, values: Mapping[str, Any], user_set: Sequence[str]) -> None:
        # every way a record is made (constructor, from_dict, replace, unpickling) fills it
        # here: the checks between settings follow the declared ones
        super()._fill(values, user_set)
        self._check_run()

    def _check_run(self) -> None:
        """The task's configs build, the interface fits them, every task of a mix gives the
        same spaces, the hyperparameters fit the algorithm (each error names its setting)."""
        cfg = make_config(self.preset, **self.config_overrides())
        make_config(self.preset, **self.eval_overrides())
        make_interface(self.interface, cfg, **self.interface_params)
        check_tasks(self)
        check_hyperparameters(self.algo, self.algo_hyperparameters())

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Any:
        """Settings as stored (``settings.yaml``, a model file's metadata), keys of older
        releases included (:func:`pairflock_env.compat.upgrade_stored`)."""
        if not isinstance(data, Mapping):
            return super().from_dict(data)  # its error
        data = upgrade_stored("settings", data)
        nested = {"env": "config", "eval_env": "config", "interface_params": "interface"}
        for key, kind in nested.items():
            if isinstance(data.get(key), Mapping):
                data[key] = upgrade_stored(kind, data[key])
        for key in ("tasks", "eval_tasks"):
            if isinstance(data.get(key), list):
                data[key] = [
                    upgrade_stored("config", t) if isinstance(t, Mapping) else t for t in data[key]
                ]
        return super().from_dict(data)

    def to_dict(self) -> dict[str, Any]:
        """A plain dict of the settings; the task-mix and warm-start settings only when they
        are set."""
        fields = self.schema.fields
        return {
            k: v
            for k, v in super().to_dict().items()
            if k not in _STORED_WHEN_SET or v != fields[k].default
        }

    def env_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of the training env's interface (:func:`env_interface_kwargs`)."""
        return env_interface_kwargs(self.interface, self.interface_params)

    def config_overrides(self) -> dict[str, Any]:
        """PairFlockConfig overrides of the training task (``dynamics`` folded in)."""
        out = dict(self.env)
        if self.dynamics is not None:
            out["dynamics"] = self.dynamics
        return out

    def eval_overrides(self) -> dict[str, Any]:
        """Overrides of the evaluation task: the training task with ``eval_env`` on top; the
        episode length is the preset's unless ``eval_env`` sets one."""
        out = self.config_overrides()
        for k in ("max_cycles", "horizon"):
            out.pop(k, None)
        out.update(self.eval_env)
        return out

    def algo_hyperparameters(self) -> dict[str, Any]:
        """The algorithm's defaults with the run's ``hyperparameters`` on top."""
        return algo_hyperparameters(self.algo, self.hyperparameters)


RunSettings = declare_record(
    "RunSettings",
    RUN_SCHEMA,
    _RunSettingsMethods,
    __name__,
    "A complete, validated description of one training run (see the module docstring).",
)


def settings_help(width: int = 92) -> str:
    """The settings, section by section: name, default, meaning and what is valid (the keys
    of ``--config`` files and of ``<run>/settings.yaml``)."""
    lines = []
    for sec in RUN_SCHEMA.sections:
        lines.append(f"  {sec.title.lower()}:")
        for f in sec.fields:
            default = f.default if isinstance(f.default, (dict, list)) else fmt_num(f.default)
            unit = f" {f.unit}" if f.unit and f.default is not None else ""
            text = f"{f.doc}; default {default}{unit}; {f.kind.valid()}"
            lines += textwrap.wrap(
                text, width, initial_indent=f"    {f.name:<17} ", subsequent_indent=" " * 22
            )
    return "\n".join(lines)


def _yaml_loader():
    """PyYAML's safe loader reading numbers as a user writes them: YAML 1.1 takes ``1e-3``
    and ``5e1`` (an exponent without a decimal point) for text, YAML 1.2 and Python for
    numbers."""

    class Loader(yaml.SafeLoader):
        pass

    exponent_float = re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$")
    Loader.add_implicit_resolver("tag:yaml.org,2002:float", exponent_float, list("-+0123456789"))
    return Loader


def config_names() -> list[str]:
    """Names of the packaged training configs (``train/configs/*.yaml``), e.g.
    ``pair_n20_a50``."""
    return packaged_names("train", "configs", ".yaml")


def resolve_config(value: str | Path) -> Path:
    """The settings file of ``--config VALUE``: a path (``.yaml`` may be left out), or the
    name of a packaged config (:func:`config_names`) when no such file exists, so that
    ``--config pair_n20_a50`` works from an installed wheel in any folder
    (:func:`baselines.controllers.zoo.find_packaged`)."""
    return find_packaged(value, package="train", folder="configs", suffix=".yaml", what="config")


def load_yaml(path: str | Path) -> dict[str, Any]:
    """A settings mapping from a YAML file or a packaged config's name
    (:func:`resolve_config`); unknown top-level keys raise with suggestions."""
    path = resolve_config(path)
    with open(path, encoding="utf-8") as f:
        try:
            data = yaml.load(f, Loader=_yaml_loader()) or {}
        except yaml.YAMLError as e:
            raise ValueError(f"--config {str(path)!r} is not valid YAML: {e}") from None
    if not isinstance(data, Mapping):
        raise ValueError(f"--config {str(path)!r} must hold a mapping, got {type(data).__name__}")
    _check_keys(data, f"--config {path}")
    return dict(data)


def _check_keys(data: Mapping[str, Any], where: str) -> None:
    names = list(RUN_SCHEMA.fields)
    for k in data:
        if k not in names:
            hint = difflib.get_close_matches(str(k), names, n=3)
            extra = f" Did you mean {', '.join(map(repr, hint))}?" if hint else ""
            raise ValueError(f"{where}: unknown key {k!r}.{extra} Valid keys: {', '.join(names)}")


def _set_nested(d: dict[str, Any], key: str, value: Any) -> None:
    """``a.b=1`` sets d["a"]["b"]."""
    parts = key.split(".")
    for p in parts[:-1]:
        d = d.setdefault(p, {})
        if not isinstance(d, dict):
            raise ValueError(f"cannot set {key!r}: {p!r} is not a mapping")
    d[parts[-1]] = value


def settings_from_sources(
    yaml_data: Mapping[str, Any] | None = None,
    flags: Mapping[str, Any] | None = None,
    env_sets: Sequence[tuple[str, Any]] = (),
    hp_sets: Sequence[tuple[str, Any]] = (),
    interface_sets: Sequence[tuple[str, Any]] = (),
) -> Any:
    """Defaults < YAML < flags (< ``--set`` / ``--hp`` / ``--interface-param`` assignments):
    the validated :class:`RunSettings`."""
    data: dict[str, Any] = {}
    if yaml_data:
        _check_keys(yaml_data, "settings")
        data.update(copy.deepcopy(dict(yaml_data)))
    data.update({k: v for k, v in (flags or {}).items() if v is not None})
    for key, sets in (("env", env_sets), ("interface_params", interface_sets)):
        if sets and isinstance(data.get(key, {}), Mapping):
            data[key] = {**data.get(key, {}), **dict(sets)}
    if hp_sets and isinstance(data.get("hyperparameters", {}), Mapping):
        hp = copy.deepcopy(dict(data.get("hyperparameters", {})))
        for k, v in hp_sets:
            _set_nested(hp, k, v)
        data["hyperparameters"] = hp
    return RunSettings(**data)
