"""Helpers shared by the view tests: one factory per view and a deep state snapshot."""

from __future__ import annotations

from typing import Any

import numpy as np

import pairflock_env
from pairflock_env.envs.single import PairFlockGymEnv
from pairflock_env.envs.vector import PairFlockGymVectorEnv

try:  # the SB3 view needs stable-baselines3 (the train extra)
    from pairflock_env.envs.sb3 import PairFlockSB3VecEnv
except ImportError:  # pragma: no cover - depends on the install
    PairFlockSB3VecEnv = None

#: a small, fast task
SMALL = dict(n_uavs=8, pair_accel_limit=50.0, max_cycles=40)

VIEWS = ("parallel", "aec", "gym", "vector", "sb3")


def make_view(kind: str, **kw: Any):
    """A view of the small task (``kind`` in :data:`VIEWS`), not yet reset."""
    kw = {**SMALL, **kw}
    if kind == "parallel":
        return pairflock_env.parallel_env(**kw)
    if kind == "aec":
        return pairflock_env.env(**kw)
    if kind == "gym":
        return PairFlockGymEnv(**kw)
    if kind == "vector":
        return PairFlockGymVectorEnv(num_envs=2, **kw)
    if kind == "sb3":
        return PairFlockSB3VecEnv(num_swarms=2, **kw)
    raise ValueError(kind)


def reset_view(env, kind: str, seed: Any = 0, options: Any = None):
    """Reset through the view's own API (SB3: ``seed`` / ``set_options`` then ``reset``)."""
    if kind == "sb3":
        if seed is not None:
            env.seed(seed)
        if options is not None:
            env.set_options(options)
        return env.reset()
    return env.reset(seed=seed, options=options)


def zero_action(env, kind: str):
    """A valid action for the view's next step."""
    if kind == "parallel":
        return {a: np.zeros(env.config.dim) for a in env.agents}
    if kind == "aec":
        return np.zeros(env.unwrapped.config.dim)
    if kind == "sb3":
        return np.zeros((env.num_envs, env.config.dim))
    return np.zeros(env.action_space.shape)


def step_view(env, kind: str, action: Any):
    if kind == "sb3":
        return env.step(action)
    if kind == "aec":
        env.step(action)
        return env.last()
    return env.step(action)


_SKIP = {"_frames", "_renderers", "metadata", "spec", "_np_random"}


def snapshot(obj: Any, _seen: set[int] | None = None) -> Any:
    """Everything that determines an env's future, as comparable plain data: arrays (bytes,
    so NaN == NaN), generator states, and the attributes of every object of the project or of
    PettingZoo's wrappers, recursively (renderers and metadata skipped)."""
    seen = set() if _seen is None else _seen
    if isinstance(obj, np.ndarray):
        return ("nd", obj.dtype.str, obj.shape, obj.tobytes())
    if isinstance(obj, np.random.Generator):
        return ("rng", repr(obj.bit_generator.state))
    if isinstance(obj, (str, int, float, bool, type(None), np.generic)):
        return obj if not isinstance(obj, float) or obj == obj else "nan"
    if isinstance(obj, dict):
        return tuple((repr(k), snapshot(v, seen)) for k, v in obj.items() if k not in _SKIP)
    if isinstance(obj, (list, tuple)):
        return tuple(snapshot(v, seen) for v in obj)
    mod = type(obj).__module__
    if mod.startswith(("pairflock_env", "pettingzoo")) and hasattr(obj, "__dict__"):
        if id(obj) in seen or mod.startswith("pairflock_env.config"):
            return type(obj).__name__
        seen.add(id(obj))
        return (type(obj).__name__, snapshot(vars(obj), seen))
    return type(obj).__name__
