"""A trained stable-baselines3 model in the pair action slot.

``make_pair_policy("sb3:<path>", env)`` loads it; ``"sb3:pair_n20_a50"`` (a bare name) loads a
policy that ships with the package (:mod:`baselines.controllers.zoo`).

The model was trained on the observation/action of a learning interface
(:mod:`pairflock_env.interfaces`, stored in the model file by ``python -m train``); the adapter
applies the same interface, so it takes the env's standard (physical, world-frame)
observation and returns the env's standard action, like the analytic controllers::

    policy = make_pair_policy("sb3:runs/ppo/final_model.zip", env)
    action, _ = policy.predict(obs["uav_0"])

Imports stable-baselines3 and torch when an ``sb3:`` policy is loaded (through
:mod:`baselines.runtime.optional`: they come with ``pairflock-env[train]``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from baselines.controllers.base import check_observation, resolve_env
from baselines.controllers.zoo import resolve_model
from baselines.runtime import optional
from pairflock_env.interfaces import interface_from_dict
from pairflock_env.interfaces.hold import DecisionHold

__all__ = ["ALGORITHMS", "METADATA_KEY", "SB3PairPolicy", "load_sb3_policy", "read_metadata"]

#: attribute of a saved SB3 model holding the pairflock metadata (algorithm, interface, config)
METADATA_KEY = "pairflock"
ALGORITHMS = ("PPO", "SAC", "TD3")


def _algo_class(name: str):
    if name not in ALGORITHMS:
        raise ValueError(f"algorithm {name!r} is invalid: must be one of {', '.join(ALGORITHMS)}")
    return getattr(optional.load("stable_baselines3", "an sb3: policy"), name)


def read_metadata(path: str | Path) -> dict[str, Any]:
    """The pairflock metadata stored in a model zip (without building the model); ``path``
    may name a packaged policy (:func:`~baselines.controllers.zoo.resolve_model`)."""
    save_util = optional.load("stable_baselines3.common.save_util", "an sb3: policy")
    path = resolve_model(path)
    data, _, _ = save_util.load_from_zip_file(path, device="cpu", load_data=True)
    meta = (data or {}).get(METADATA_KEY)
    if not isinstance(meta, dict) or "algo" not in meta or "interface" not in meta:
        raise ValueError(
            f"{str(path)!r} is not a pairflock model: it has no {METADATA_KEY!r} metadata "
            "(train it with `python -m train`)"
        )
    return meta


class SB3PairPolicy:
    """SB3 model + learning interface, with the analytic controllers' ``predict`` signature.

    ``predict(observation, state=None, episode_start=None, deterministic=True)`` takes the
    env's observation ``(obs_size,)`` or ``(n, obs_size)`` and returns env actions ``(dim,)``
    or ``(n, dim)`` in units of the env's ``pair_accel_limit``, plus a state.

    The policy decides every ``interface.decision_period`` control steps, as in training: the
    returned state holds each row's last network output and its age, and passing it back
    (with ``episode_start`` True where an episode begins, as SB3 does for recurrent policies
    and ``baselines.evaluation.rollout`` does) makes the next calls reuse that output, decoded
    against the fresh observation. Without a state (``state=None``) the network decides on
    every call.
    """

    def __init__(self, model: Any, env: Any, interface: dict[str, Any]) -> None:
        self.config, self.layout = resolve_env(env)
        self.model = model
        self.interface = interface_from_dict(interface, self.config)
        expected = self.interface.observation_size
        got = model.observation_space.shape
        if got != (expected,):
            raise ValueError(
                f"the model observes shape {got} but the {self.interface.name!r} interface for "
                f"this env gives ({expected},); evaluate on an env with the same dim and "
                f"obs_neighbors as in training"
            )

    @classmethod
    def load(cls, path: str | Path, env: Any) -> SB3PairPolicy:
        """The model saved at ``path`` (or the packaged policy of that name) for ``env``."""
        path = resolve_model(path)
        meta = read_metadata(path)
        algo = _algo_class(meta["algo"])
        model = algo.load(str(path), device="cpu")
        return cls(model, env, meta["interface"])

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        obs = check_observation(observation, self.layout.size)
        batch = obs.reshape(-1, self.layout.size)
        n = batch.shape[0]
        starts = None
        if state is None:
            hold = DecisionHold.empty(self.interface, n)
        else:
            ok = isinstance(state, tuple) and len(state) == 2
            if not ok or np.shape(state[0]) != (n, self.config.dim):
                raise ValueError(
                    "state must be the state returned by the previous predict() call on a batch "
                    f"of the same size ({n} rows), or None"
                )
            held, age = np.array(state[0], dtype=np.float64), np.array(state[1], dtype=np.int64)
            hold = DecisionHold(self.interface, held, age)
            if episode_start is not None:
                starts = np.asarray(episode_start, dtype=bool).reshape(-1)
                if starts.shape != (n,):
                    raise ValueError(
                        f"episode_start has shape {np.shape(episode_start)}; expected ({n},)"
                    )
        decide = hold.due(starts)
        if decide.any():
            enc = self.interface.encode(batch[decide])
            a, _ = self.model.predict(enc, deterministic=deterministic)
            hold.decide(decide, np.asarray(a, dtype=np.float64).reshape(-1, self.config.dim))
        env_a = hold.env_action(batch)
        new_state = (hold.held, hold.age)
        return env_a.reshape((*obs.shape[:-1], self.config.dim)).astype(np.float32), new_state

    def __repr__(self) -> str:
        return f"SB3PairPolicy({type(self.model).__name__}, interface={self.interface.name!r})"


def load_sb3_policy(path: str, env: Any, **gains: Any) -> SB3PairPolicy:
    """Factory behind the ``"sb3:"`` prefix of :func:`baselines.make_pair_policy`."""
    if gains:
        raise TypeError(f"an sb3 policy takes no gains, got {sorted(gains)}")
    if not path:
        raise ValueError(
            "name 'sb3:' needs a model path or a packaged model's name, e.g. "
            "'sb3:runs/ppo/final_model.zip' or 'sb3:pair_n20_a50'"
        )
    return SB3PairPolicy.load(path, env)
