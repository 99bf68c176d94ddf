"""The algorithms a run can use and their stable-baselines3 hyperparameters: the defaults,
the check of a run's values against the algorithm's signature, and the ``lin_<v>`` schedules.
"""

from __future__ import annotations

import copy
import difflib
import inspect
from collections.abc import Mapping
from typing import Any

import stable_baselines3 as sb3

__all__ = [
    "ALGOS",
    "DEFAULT_HYPERPARAMETERS",
    "algo_hyperparameters",
    "check_hyperparameters",
    "linear_schedule",
    "resolve_schedules",
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


def algo_hyperparameters(algo: str, given: Mapping[str, Any]) -> dict[str, Any]:
    """The defaults of ``algo`` with ``given`` on top (``policy_kwargs`` merged key by key)."""
    hp = copy.deepcopy(DEFAULT_HYPERPARAMETERS[algo])
    for k, v in given.items():
        if k == "policy_kwargs" and isinstance(v, Mapping):
            hp.setdefault("policy_kwargs", {}).update(v)
        else:
            hp[k] = v
    return hp


def check_hyperparameters(algo: str, hp: Mapping[str, Any]) -> None:
    """``ValueError`` naming a key of ``hp`` that ``algo``'s constructor does not take (with
    suggestions), or one the CLI sets itself; and a malformed ``lin_<v>`` schedule."""
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
    resolve_schedules(dict(hp))


def linear_schedule(start: float):
    """SB3 schedule falling linearly from ``start`` to 0 over training (rl-zoo's ``lin_<v>``)."""

    def schedule(progress_remaining: float) -> float:
        return progress_remaining * start

    schedule.start = start  # type: ignore[attr-defined]
    return schedule


def resolve_schedules(hp: dict[str, Any]) -> dict[str, Any]:
    """``"lin_3e-4"`` for learning_rate / clip_range means a linear decay from 3e-4 to 0."""
    out = dict(hp)
    for key in ("learning_rate", "clip_range"):
        v = out.get(key)
        if isinstance(v, str) and v.startswith("lin_"):
            try:
                start = float(v[4:])
            except ValueError:
                raise ValueError(
                    f"hyperparameter {key}={v!r} is invalid: use lin_<number>"
                ) from None
            if start <= 0:
                raise ValueError(f"hyperparameter {key}={v!r} is invalid: the start must be > 0")
            out[key] = linear_schedule(start)
    return out
