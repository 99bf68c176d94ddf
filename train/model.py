"""The SB3 model of a run: construction (with a warm start), loading, metadata, saving."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import stable_baselines3 as sb3
from stable_baselines3.common.noise import NormalActionNoise
from stable_baselines3.common.save_util import load_from_zip_file

from baselines.controllers.sb3 import METADATA_KEY
from baselines.controllers.zoo import resolve_model
from train.hyperparameters import resolve_schedules
from train.settings import RunSettings

__all__ = [
    "METADATA_KEY",
    "build_model",
    "load_model",
    "metadata",
    "save_model_atomic",
    "warm_start",
]


def build_model(settings: RunSettings, venv: Any) -> Any:
    """A fresh SB3 model of the run's algorithm and hyperparameters, seeded by the run."""
    hp = resolve_schedules(settings.algo_hyperparameters())
    cls = getattr(sb3, settings.algo.upper())
    if settings.algo == "td3":
        std = float(hp.pop("action_noise_std"))
        D = venv.action_space.shape[0]
        hp["action_noise"] = NormalActionNoise(np.zeros(D), std * np.ones(D))
    model = cls("MlpPolicy", venv, seed=settings.seed, device="cpu", verbose=0, **hp)
    if settings.init_model is not None:
        warm_start(model, resolve_model(settings.init_model))
    return model


def warm_start(model: Any, path: Path) -> None:
    """Copy the weights (and optimizer state) of the model saved at ``path`` into ``model``;
    the spaces must be the same (``ValueError`` naming both otherwise)."""
    data, params, _ = load_from_zip_file(path, device="cpu")
    for space in ("observation_space", "action_space"):
        if data.get(space) != getattr(model, space):
            raise ValueError(
                f"init_model={str(path)!r} is invalid: its {space} {data.get(space)} is not "
                f"the run's {getattr(model, space)}"
            )
    model.set_parameters(params, exact_match=True, device="cpu")


def load_model(settings: RunSettings, ckpt: Path, venv: Any) -> Any:
    """The model of checkpoint ``ckpt`` on ``venv`` (with its replay buffer, if any)."""
    cls = getattr(sb3, settings.algo.upper())
    # force_reset=False keeps the saved last observation: the env continues, not resets
    model = cls.load(str(ckpt / "model.zip"), env=venv, device="cpu", force_reset=False)
    if (ckpt / "replay_buffer.pkl").is_file():
        model.load_replay_buffer(str(ckpt / "replay_buffer.pkl"))
    return model


def metadata(settings: RunSettings, interface: Any, cfg: Any) -> dict[str, Any]:
    """What a saved model carries (``model.pairflock``): algorithm, interface, task, settings."""
    return {
        "algo": settings.algo.upper(),
        "interface": interface.to_dict(),
        "config": cfg.to_dict(),
        "settings": settings.to_dict(),
    }


def save_model_atomic(model: Any, path: Path) -> None:
    """``model.save`` to a temporary file next to ``path``, then renamed onto it."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp.zip")
    model.save(tmp)
    os.replace(tmp, path)
