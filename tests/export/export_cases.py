"""What the export tests share: the committed policies, the observations each meets in its
own task (cached per process), their exports, and small untrained models of every exported
algorithm and interface (saved with pairflock metadata, as training saves them)."""

from __future__ import annotations

import functools
import tempfile
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3 import PPO, SAC, TD3
from torch import nn

from baselines.controllers.sb3 import METADATA_KEY
from baselines.export import build, verify
from pairflock_env import make_config
from pairflock_env.interfaces import make_interface

#: the committed policies (baselines/models), 2-D and 3-D, with and without the filter
MODELS = ("pair_n20_a50", "pair_n20_a50_safe", "pair_safe_a50", "pair_quad3d")
#: observations per committed policy (the issue: at least 10,000)
N_OBS = 10_000
TOL = 1e-5

#: small untrained models: algorithm, task, interface, interface parameters, policy kwargs
TINY = {
    "sac-pair-2d": ("SAC", "paper", "pair", {}, {}),
    "td3-pair-3d": ("TD3", "paper-quadrotor", "pair", {"decision_period": 3}, {}),
    "ppo-sde-squashed": (
        "PPO",
        "paper",
        "pair",
        {"threat_neighbors": 0},
        {"use_sde": True, "squash_output": True},
    ),
    "ppo-world-relu": ("PPO", "paper", "world", {}, {"activation_fn": "relu"}),
}
_KEEP: list[tempfile.TemporaryDirectory] = []


def scratch() -> Path:
    """A folder that lives until the test process ends."""
    d = tempfile.TemporaryDirectory(prefix="pairflock-export-")
    _KEEP.append(d)
    return Path(d.name)


@functools.cache
def loaded(spec: str) -> build.LoadedPolicy:
    """The policy ``spec`` (``"sb3:<name>"``) loaded for export."""
    return build.load_policy(spec)


@functools.cache
def observations(spec: str, n: int = N_OBS) -> np.ndarray:
    """At least ``n`` observations the policy meets flying its own task."""
    lp = loaded(spec)
    return verify.rollout_observations(lp.policy, lp.config, n)


@functools.cache
def reference(spec: str, n: int = N_OBS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(encoded observations, SB3 predict on them, the sb3: policy's env action)."""
    lp, obs = loaded(spec), observations(spec, n)
    features = lp.interface.encode(obs)
    net, _ = lp.policy.model.predict(features, deterministic=True)
    env, _ = lp.policy.predict(obs)
    return features, net, env


@functools.cache
def exported(spec: str) -> Path:
    """The export folder of ``spec`` (ONNX included when onnx is installed)."""
    out = scratch() / "export"
    build.write_export(loaded(spec), out, with_onnx=build.onnx.onnx is not None)
    return out


class Spaces(gym.Env):
    """An env with the given spaces only: what SB3 needs to build a model."""

    def __init__(self, obs_space: gym.Space, act_space: gym.Space) -> None:
        self.observation_space, self.action_space = obs_space, act_space


def spaces_of(spec: str) -> tuple[gym.Space, gym.Space]:
    """The observation and action spaces of the model ``spec``."""
    model = loaded(spec).policy.model
    return model.observation_space, model.action_space


@functools.cache
def tiny(case: str) -> str:
    """The spec ``"sb3:<path>"`` of the small untrained model ``case`` of :data:`TINY`."""
    algo, preset, name, params, kwargs = TINY[case]
    cfg = make_config(preset, n_uavs=6, max_cycles=120, dynamics="particle")
    it = make_interface(name, cfg, **params)
    low, high = it.observation_bounds()
    env = Spaces(gym.spaces.Box(low, high), gym.spaces.Box(-1.0, 1.0, (cfg.dim,), np.float32))
    policy_kwargs: dict[str, Any] = {"net_arch": [24, 16]}
    if kwargs.pop("activation_fn", None) == "relu":
        policy_kwargs["activation_fn"] = nn.ReLU
    cls = {"PPO": PPO, "SAC": SAC, "TD3": TD3}[algo]
    if algo == "PPO" and kwargs.get("squash_output"):
        policy_kwargs["squash_output"] = kwargs.pop("squash_output")
    if algo != "PPO":
        kwargs["buffer_size"] = 100  # no replay memory to speak of: the model is not trained
    model = cls("MlpPolicy", env, seed=3, device="cpu", policy_kwargs=policy_kwargs, **kwargs)
    setattr(model, METADATA_KEY, {"algo": algo, "interface": it.to_dict(),
                                  "config": cfg.to_dict()})  # fmt: skip
    path = scratch() / f"{case}.zip"
    model.save(path)
    return f"sb3:{path}"
