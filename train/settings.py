"""Everything a training run is built from, in one validated structure.

A run is described by :class:`RunSettings`: the task (preset, dynamics, config overrides,
number of swarms), the learning interface (``frame`` and its parameters), the algorithm and
its stable-baselines3 hyperparameters, the schedule (total steps, evaluation, checkpoints) and
the seed. The CLI builds it from defaults, then a YAML file (``--config``), then flags, and
stores the result in the run directory, so ``--config <run>/settings.yaml`` reruns it.

YAML layout (every key optional; see ``train/configs/*.yaml``)::

    algo: ppo                  # ppo | sac | td3
    preset: paper
    env:                       # PairFlockConfig overrides (validated by make_config)
      n_uavs: 20
      pair_accel_limit: 50.0
    eval_env: {horizon: 50.0}  # overrides applied on top of env for evaluation
    frame: pair                # pair | world
    frame_params: {}           # PairFrameParams fields
    num_swarms: 32
    total_steps: 20000000
    seed: 0
    hyperparameters:           # SB3 constructor keyword arguments for the algorithm
      learning_rate: 3.0e-4    # or lin_3e-4: linear decay to 0 (also clip_range)
      policy_kwargs: {net_arch: [128, 128], log_std_init: -1.0}
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

__all__ = [
    "ALGOS",
    "DEFAULT_HYPERPARAMETERS",
    "RunSettings",
    "load_yaml",
    "parse_assignment",
    "settings_from_sources",
]

ALGOS = ("ppo", "sac", "td3")

#: defaults per algorithm (SB3 keyword arguments); ``action_noise_std`` (TD3) is ours
DEFAULT_HYPERPARAMETERS: dict[str, dict[str, Any]] = {
    "ppo": {
        "learning_rate": 3e-4,
        "n_steps": 128,
        "batch_size": 2048,
        "n_epochs": 5,
        "gamma": 0.98,
        "gae_lambda": 0.95,
        "clip_range": 0.2,
        "ent_coef": 0.0,
        "vf_coef": 0.5,
        "max_grad_norm": 0.5,
        "policy_kwargs": {"net_arch": [128, 128], "log_std_init": -1.0},
    },
    "sac": {
        "learning_rate": 3e-4,
        "buffer_size": 1_000_000,
        "learning_starts": 10_000,
        "batch_size": 256,
        "tau": 0.005,
        "gamma": 0.99,
        "train_freq": 1,
        "gradient_steps": 1,
        "ent_coef": "auto",
        "policy_kwargs": {"net_arch": [256, 256]},
    },
    "td3": {
        "learning_rate": 1e-3,
        "buffer_size": 1_000_000,
        "learning_starts": 10_000,
        "batch_size": 256,
        "tau": 0.005,
        "gamma": 0.99,
        "train_freq": 1,
        "gradient_steps": 1,
        "action_noise_std": 0.1,
        "policy_kwargs": {"net_arch": [256, 256]},
    },
}


@dataclasses.dataclass
class RunSettings:
    """A complete, validated description of one training run (see the module docstring)."""

    algo: str = "ppo"
    preset: str = "paper"
    dynamics: str | None = None
    env: dict[str, Any] = dataclasses.field(default_factory=dict)
    eval_env: dict[str, Any] = dataclasses.field(default_factory=dict)
    frame: str = "pair"
    frame_params: dict[str, Any] = dataclasses.field(default_factory=dict)
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

    # ------------------------------------------------------------------ derived
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
        hp = copy.deepcopy(DEFAULT_HYPERPARAMETERS[self.algo])
        for k, v in self.hyperparameters.items():
            if k == "policy_kwargs" and isinstance(v, Mapping):
                hp.setdefault("policy_kwargs", {}).update(v)
            else:
                hp[k] = v
        return hp

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    # ------------------------------------------------------------------ validation
    def validate(self) -> RunSettings:
        from pairflock_env import make_config
        from pairflock_env.learning import make_interface

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
        for name in ("env", "eval_env", "frame_params", "hyperparameters"):
            if not isinstance(getattr(self, name), Mapping):
                raise TypeError(f"{name}={getattr(self, name)!r} is invalid: must be a mapping")
        if not isinstance(self.eval_seeds, list) or not all(
            isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in self.eval_seeds
        ):
            raise ValueError(f"eval_seeds={self.eval_seeds!r} is invalid: a list of ints >= 0")
        cfg = make_config(self.preset, **self.config_overrides())
        make_config(self.preset, **self.eval_overrides())
        make_interface(self.frame, cfg, **self.frame_params)
        from baselines import POLICIES

        for b in self.eval_baselines:
            if b not in POLICIES or b.endswith(":"):
                raise ValueError(
                    f"eval_baselines entry {b!r} is invalid: analytic controllers are "
                    f"{', '.join(k for k in POLICIES if not k.endswith(':'))}"
                )
        _check_hyperparameters(self.algo, self.algo_hyperparameters())
        from .run import resolve_schedules

        resolve_schedules(self.algo_hyperparameters())
        return self


def _check_hyperparameters(algo: str, hp: Mapping[str, Any]) -> None:
    import inspect

    import stable_baselines3 as sb3

    cls = getattr(sb3, algo.upper())
    valid = set(inspect.signature(cls.__init__).parameters) - {"self", "policy", "env"}
    if algo == "td3":
        valid.add("action_noise_std")
    for k in hp:
        if k not in valid:
            hint = difflib.get_close_matches(k, sorted(valid), n=3)
            extra = f" Did you mean {', '.join(map(repr, hint))}?" if hint else ""
            raise ValueError(
                f"hyperparameter {k!r} is invalid for {algo.upper()}.{extra} "
                f"Valid: {', '.join(sorted(valid))}"
            )
    for k in ("seed", "device", "tensorboard_log", "verbose"):
        if k in hp:
            raise ValueError(
                f"hyperparameter {k!r} is set by the CLI (use --seed / --out / --quiet), not in "
                "hyperparameters"
            )


def load_yaml(path: str | Path) -> dict[str, Any]:
    """A settings mapping from a YAML file (unknown top-level keys raise with suggestions)."""
    import yaml

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"--config {str(path)!r} does not exist")
    with open(path, encoding="utf-8") as f:
        data = yaml.safe_load(f) or {}
    if not isinstance(data, Mapping):
        raise ValueError(f"--config {str(path)!r} must hold a mapping, got {type(data).__name__}")
    _check_keys(data, f"--config {path}")
    return dict(data)


def _check_keys(data: Mapping[str, Any], where: str) -> None:
    names = [f.name for f in dataclasses.fields(RunSettings)]
    for k in data:
        if k not in names:
            hint = difflib.get_close_matches(k, names, n=3)
            extra = f" Did you mean {', '.join(map(repr, hint))}?" if hint else ""
            raise ValueError(f"{where}: unknown key {k!r}.{extra} Valid keys: {', '.join(names)}")


def parse_assignment(text: str, flag: str) -> tuple[str, Any]:
    """``key=value`` with the value parsed as YAML (``1e-3``, ``[64, 64]``, ``true``, ``auto``)."""
    import yaml

    if "=" not in text:
        raise ValueError(f"{flag} {text!r} is invalid: expected key=value")
    key, raw = text.split("=", 1)
    key = key.strip()
    if not key:
        raise ValueError(f"{flag} {text!r} is invalid: empty key")
    try:
        value = yaml.safe_load(raw)
    except yaml.YAMLError as e:
        raise ValueError(f"{flag} {text!r} is invalid: cannot parse the value ({e})") from None
    return key, value


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
    frame_sets: list[tuple[str, Any]] = (),
) -> RunSettings:
    """Defaults < YAML < flags (< ``--set`` / ``--hp`` / ``--frame-param`` assignments)."""
    data: dict[str, Any] = {}
    if yaml_data:
        _check_keys(yaml_data, "settings")
        data.update(copy.deepcopy(dict(yaml_data)))
    for k, v in (flags or {}).items():
        if v is not None:
            data[k] = v
    s = RunSettings(**data)
    s.env = dict(s.env)
    s.hyperparameters = copy.deepcopy(dict(s.hyperparameters))
    s.frame_params = dict(s.frame_params)
    for k, v in env_sets:
        s.env[k] = v
    for k, v in hp_sets:
        _set_nested(s.hyperparameters, k, v)
    for k, v in frame_sets:
        s.frame_params[k] = v
    if isinstance(s.eval_seeds, tuple):
        s.eval_seeds = list(s.eval_seeds)
    return s.validate()
