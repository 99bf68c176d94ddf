"""Checkpoints that let a run continue exactly where it stopped.

A checkpoint is a directory ``checkpoints/step_<N>/`` holding

* ``model.zip``: the SB3 model (parameters, optimizer state, step count, the last
  observation and episode-start flags, the learning-rate schedule position);
* ``replay_buffer.pkl``: the replay buffer (SAC, TD3);
* ``state.pkl``: the batched environment (core state and per-swarm generators), the
  episode statistics of the monitor, the global random states SB3 draws from (torch, numpy,
  python) and the action space's generator, and the callbacks' schedule;
* ``checkpoint.json``: step count and file list (human-readable).

It is written to a temporary directory and renamed into place, so a crash never leaves a half
checkpoint; ``checkpoints/latest`` names the newest one.
"""

from __future__ import annotations

import os
import pickle
import random
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import torch
from stable_baselines3.common.vec_env import VecMonitor

from baselines.runtime.files import atomic_write_text, write_json

__all__ = [
    "latest_checkpoint",
    "load_checkpoint_state",
    "restore_monitor",
    "rng_state",
    "save_checkpoint",
    "set_rng_state",
]


def rng_state(model: Any) -> dict[str, Any]:
    return {
        "torch": torch.get_rng_state(),
        "numpy": np.random.get_state(),
        "python": random.getstate(),
        "action_space": model.action_space.np_random.bit_generator.state,
    }


def set_rng_state(model: Any, state: dict[str, Any]) -> None:
    torch.set_rng_state(state["torch"])
    np.random.set_state(state["numpy"])
    random.setstate(state["python"])
    model.action_space.np_random.bit_generator.state = state["action_space"]


def save_checkpoint(root: Path, model: Any, venv: Any, extra: dict[str, Any], keep: int) -> Path:
    """Write checkpoint ``root/step_<N>`` (N = model.num_timesteps) atomically; keep the
    newest ``keep`` checkpoints (0 keeps all)."""
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    step = int(model.num_timesteps)
    final = root / f"step_{step:012d}"
    tmp = root / f".tmp_step_{step:012d}_{os.getpid()}"
    if tmp.exists():
        shutil.rmtree(tmp)
    tmp.mkdir()
    try:
        model.save(tmp / "model.zip")
        files = ["model.zip", "state.pkl", "checkpoint.json"]
        if hasattr(model, "replay_buffer") and model.replay_buffer is not None:
            model.save_replay_buffer(tmp / "replay_buffer.pkl")
            files.append("replay_buffer.pkl")
        monitor = _find_monitor(venv)
        state = {
            "num_timesteps": step,
            "env": venv.unwrapped.get_state(),
            "monitor": None
            if monitor is None
            else {
                "episode_returns": monitor.episode_returns.copy(),
                "episode_lengths": monitor.episode_lengths.copy(),
                "episode_count": monitor.episode_count,
            },
            "rng": rng_state(model),
            **extra,
        }
        with open(tmp / "state.pkl", "wb") as f:
            pickle.dump(state, f, protocol=pickle.HIGHEST_PROTOCOL)
        write_json(tmp / "checkpoint.json", {"num_timesteps": step, "files": files})
        if final.exists():
            shutil.rmtree(final)
        os.replace(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    atomic_write_text(root / "latest", final.name + "\n")
    if keep > 0:
        old = sorted(p for p in root.glob("step_*") if p.is_dir())[:-keep]
        for p in old:
            shutil.rmtree(p, ignore_errors=True)
    return final


def _find_monitor(venv: Any) -> Any:
    v = venv
    while v is not None:
        if isinstance(v, VecMonitor):
            return v
        v = getattr(v, "venv", None)
    return None


def restore_monitor(venv: Any, state: dict[str, Any] | None) -> None:
    monitor = _find_monitor(venv)
    if monitor is not None and state is not None:
        monitor.episode_returns = state["episode_returns"].copy()
        monitor.episode_lengths = state["episode_lengths"].copy()
        monitor.episode_count = state["episode_count"]


def latest_checkpoint(path: Path) -> Path:
    """The checkpoint directory named by ``path``: a checkpoint itself, a run directory or a
    ``checkpoints`` directory (then the one ``latest`` names)."""
    path = Path(path)
    if (path / "checkpoint.json").is_file():
        return path
    for root in (path / "checkpoints", path):
        latest = root / "latest"
        if latest.is_file():
            ck = root / latest.read_text(encoding="utf-8").strip()
            if (ck / "checkpoint.json").is_file():
                return ck
    raise FileNotFoundError(
        f"--resume {str(path)!r} is invalid: no checkpoint there (expected a run directory "
        "with checkpoints/latest, or a checkpoints/step_<N> directory)"
    )


def load_checkpoint_state(ckpt: Path) -> dict[str, Any]:
    with open(Path(ckpt) / "state.pkl", "rb") as f:
        return pickle.load(f)
