"""Everything a training run is built from, in one validated structure.

A run is described by :class:`RunSettings`: the task (preset, dynamics, config overrides,
number of swarms), the learning interface (``interface`` and its parameters), the algorithm and
its stable-baselines3 hyperparameters, the schedule (total steps, evaluation, checkpoints) and
the seed. The CLI builds it from defaults, then a YAML file (``--config``), then flags, and
stores the result in the run directory, so ``--config <run>/settings.yaml`` reruns it.

YAML layout (every key optional; see ``train/configs/*.yaml``, which ship with the package:
``--config pair_n20_a50`` names one, :func:`resolve_config`)::

    algo: ppo                  # ppo | sac | td3
    preset: paper
    env:                       # PairFlockConfig overrides (validated by make_config)
      n_uavs: 20
      pair_accel_limit: 50.0
    eval_env: {horizon: 50.0}  # overrides applied on top of env for evaluation
    interface: pair            # pair | world (the learning interface; old key: frame)
    interface_params: {}       # PairInterfaceParams fields (old key: frame_params)
    num_swarms: 32
    tasks:                     # optional: train on a mix (train/tasks.py, docs/learning.md)
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
in files and in ``--set``/``--hp``/``--interface-param`` values alike.
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import inspect
import re
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import yaml

from baselines import POLICIES
from baselines.controllers.zoo import find_packaged, packaged_names, resolve_model
from baselines.evaluation.specs import parse_assignment
from pairflock_env import make_config
from pairflock_env.interfaces import make_interface
from train.hyperparameters import (
    ALGOS,
    DEFAULT_HYPERPARAMETERS,
    algo_hyperparameters,
    check_hyperparameters,
)
from train.mix.tasks import check_tasks

__all__ = [
    "ALGOS",
    "DEFAULT_HYPERPARAMETERS",
    "RENAMED_KEYS",
    "RunSettings",
    "config_names",
    "env_interface_kwargs",
    "load_yaml",
    "parse_assignment",
    "resolve_config",
    "settings_from_sources",
]

#: old settings keys -> new ones (the old ones still load, with a deprecation note)
RENAMED_KEYS = {"frame": "interface", "frame_params": "interface_params"}


def env_interface_kwargs(interface: str, params: Mapping[str, Any]) -> dict[str, Any]:
    """The keyword arguments that choose the learning interface on the env constructors.

    The one place that knows the env's keyword names.
    """
    return {"interface": interface, "interface_params": dict(params)}


def _renamed(data: Mapping[str, Any], where: str, category: type[Warning] | None) -> dict:
    """``data`` with old keys (:data:`RENAMED_KEYS`) under their new names; warns with
    ``category`` (None: silently, e.g. for stored model metadata)."""
    out = dict(data)
    for old, new in RENAMED_KEYS.items():
        if old not in out:
            continue
        if new in out:
            raise ValueError(
                f"{where}: {old!r} and {new!r} are the same setting; give only {new!r}"
            )
        if category is not None:
            warnings.warn(f"{where}: {old!r} is deprecated; write {new!r}", category, stacklevel=3)
        out[new] = out.pop(old)
    return out


@dataclasses.dataclass
class RunSettings:
    """A complete, validated description of one training run (see the module docstring)."""

    algo: str = "ppo"
    preset: str = "paper"
    dynamics: str | None = None
    env: dict[str, Any] = dataclasses.field(default_factory=dict)
    eval_env: dict[str, Any] = dataclasses.field(default_factory=dict)
    interface: str = "pair"
    interface_params: dict[str, Any] = dataclasses.field(default_factory=dict)
    num_swarms: int = 32
    total_steps: int = 1_000_000
    seed: int = 0
    hyperparameters: dict[str, Any] = dataclasses.field(default_factory=dict)
    eval_every: int = 1_000_000
    eval_seeds: list[int] = dataclasses.field(default_factory=lambda: list(range(1000, 1010)))
    eval_baselines: list[str] = dataclasses.field(default_factory=lambda: ["smc", "proportional"])
    checkpoint_every: int = 1_000_000
    keep_checkpoints: int = 3
    tensorboard: bool = True
    time_limit: float | None = None
    tasks: list[dict[str, Any]] | None = None
    eval_tasks: list[dict[str, Any]] | None = None
    eval_aggregate: str = "worst"
    eval_targets: str = "learned"
    init_model: str | None = None

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> RunSettings:
        """Settings from a stored mapping (``settings.yaml``, model metadata), old keys too;
        not validated."""
        return cls(**_renamed(data, "settings", None))

    @property
    def frame(self) -> str:
        """Deprecated name of :attr:`interface`."""
        warnings.warn("RunSettings.frame is deprecated; use .interface", DeprecationWarning, 2)
        return self.interface

    @frame.setter
    def frame(self, value: str) -> None:
        warnings.warn("RunSettings.frame is deprecated; use .interface", DeprecationWarning, 2)
        self.interface = value

    @property
    def frame_params(self) -> dict[str, Any]:
        """Deprecated name of :attr:`interface_params`."""
        warnings.warn(
            "RunSettings.frame_params is deprecated; use .interface_params", DeprecationWarning, 2
        )
        return self.interface_params

    @frame_params.setter
    def frame_params(self, value: dict[str, Any]) -> None:
        warnings.warn(
            "RunSettings.frame_params is deprecated; use .interface_params", DeprecationWarning, 2
        )
        self.interface_params = value

    # ------------------------------------------------------------------ derived
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

    def to_dict(self) -> dict[str, Any]:
        """A plain dict of the settings; the task-mix fields only when they are set, so that
        a run on one task stores exactly what it stored before they existed."""
        out = dataclasses.asdict(self)
        for name, default in _MIX_DEFAULTS.items():
            if out[name] == default:
                del out[name]
        return out

    # ------------------------------------------------------------------ validation
    def validate(self) -> RunSettings:
        if self.algo not in ALGOS:
            raise ValueError(f"algo={self.algo!r} is invalid: must be one of {', '.join(ALGOS)}")
        for name in (
            "num_swarms",
            "total_steps",
            "eval_every",
            "checkpoint_every",
            "seed",
            "keep_checkpoints",
        ):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int):
                raise TypeError(f"{name}={v!r} is invalid: must be an integer")
            lo = 0 if name in ("seed", "eval_every", "checkpoint_every", "keep_checkpoints") else 1
            if v < lo:
                raise ValueError(f"{name}={v!r} is invalid: must be >= {lo}")
        if self.time_limit is not None and not (
            isinstance(self.time_limit, (int, float)) and self.time_limit > 0
        ):
            raise ValueError(
                f"time_limit={self.time_limit!r} is invalid: must be > 0 minutes or None"
            )
        if self.init_model is not None:
            init_model_path(self.init_model)
        for name in ("env", "eval_env", "interface_params", "hyperparameters"):
            if not isinstance(getattr(self, name), Mapping):
                raise TypeError(f"{name}={getattr(self, name)!r} is invalid: must be a mapping")
        if not isinstance(self.eval_seeds, list) or not all(
            isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in self.eval_seeds
        ):
            raise ValueError(f"eval_seeds={self.eval_seeds!r} is invalid: a list of ints >= 0")
        cfg = make_config(self.preset, **self.config_overrides())
        make_config(self.preset, **self.eval_overrides())
        make_interface(self.interface, cfg, **self.interface_params)

        for b in self.eval_baselines:
            if b not in POLICIES or b.endswith(":"):
                raise ValueError(
                    f"eval_baselines entry {b!r} is invalid: analytic controllers are "
                    f"{', '.join(k for k in POLICIES if not k.endswith(':'))}"
                )

        check_tasks(self)
        check_hyperparameters(self.algo, self.algo_hyperparameters())
        return self


def init_model_path(value: Any) -> Path:
    """The model file of the ``init_model`` setting (a zip path or a packaged policy's name);
    ``TypeError`` / ``ValueError`` naming the setting otherwise."""
    if not isinstance(value, (str, Path)):
        raise TypeError(f"init_model={value!r} is invalid: must be a path or a model name")
    try:
        return resolve_model(value)
    except FileNotFoundError as e:
        raise ValueError(f"init_model={value!r} is invalid: {e}") from None


#: fields of a task mix and their defaults (left out of :meth:`RunSettings.to_dict` when unset)
_MIX_DEFAULTS = {
    "tasks": None,
    "eval_tasks": None,
    "eval_aggregate": "worst",
    "eval_targets": "learned",
    "init_model": None,
}


def _wrap_init(cls):
    """Let ``RunSettings(frame=...)`` (the old keyword names) keep working, with a warning."""
    init = cls.__init__

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        init(self, *args, **_renamed(kwargs, "RunSettings", DeprecationWarning))

    __init__.__doc__ = init.__doc__
    __init__.__signature__ = inspect.signature(init)  # type: ignore[attr-defined]
    cls.__init__ = __init__
    return cls


_wrap_init(RunSettings)


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
    (:func:`resolve_config`); unknown top-level keys raise with suggestions, the old keys
    ``frame``/``frame_params`` load with a deprecation note."""
    path = resolve_config(path)
    with open(path, encoding="utf-8") as f:
        try:
            data = yaml.load(f, Loader=_yaml_loader()) or {}
        except yaml.YAMLError as e:
            raise ValueError(f"--config {str(path)!r} is not valid YAML: {e}") from None
    if not isinstance(data, Mapping):
        raise ValueError(f"--config {str(path)!r} must hold a mapping, got {type(data).__name__}")
    where = f"--config {path}"
    _check_keys(data, where)
    return _renamed(data, where, FutureWarning)


def _check_keys(data: Mapping[str, Any], where: str) -> None:
    names = [f.name for f in dataclasses.fields(RunSettings)]
    for k in data:
        if k not in names and k not in RENAMED_KEYS:
            hint = difflib.get_close_matches(k, names, n=3)
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
    env_sets: list[tuple[str, Any]] = (),
    hp_sets: list[tuple[str, Any]] = (),
    interface_sets: list[tuple[str, Any]] = (),
    *,
    frame_sets: list[tuple[str, Any]] = (),
) -> RunSettings:
    """Defaults < YAML < flags (< ``--set`` / ``--hp`` / ``--interface-param`` assignments).

    ``frame_sets`` is the old name of ``interface_sets`` (both are applied); old keys in
    ``yaml_data`` and ``flags`` are accepted too (:data:`RENAMED_KEYS`).
    """
    data: dict[str, Any] = {}
    if yaml_data:
        _check_keys(yaml_data, "settings")
        data.update(copy.deepcopy(_renamed(yaml_data, "settings", DeprecationWarning)))
    given = {k: v for k, v in (flags or {}).items() if v is not None}
    data.update(_renamed(given, "flags", DeprecationWarning))
    if frame_sets:
        warnings.warn("frame_sets is deprecated; use interface_sets", DeprecationWarning, 2)
    s = RunSettings(**data)
    s.env = dict(s.env)
    s.hyperparameters = copy.deepcopy(dict(s.hyperparameters))
    s.interface_params = dict(s.interface_params)
    for k, v in env_sets:
        s.env[k] = v
    for k, v in hp_sets:
        _set_nested(s.hyperparameters, k, v)
    for k, v in [*interface_sets, *frame_sets]:
        s.interface_params[k] = v
    if isinstance(s.eval_seeds, tuple):
        s.eval_seeds = list(s.eval_seeds)
    return s.validate()
