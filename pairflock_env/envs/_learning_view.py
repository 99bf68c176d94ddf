"""What the learning views (Gymnasium Env, Gymnasium VectorEnv, SB3 VecEnv) share: building
the core and the learning interface from keyword arguments, validating the policy's actions,
and rendering one swarm. No physics here."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..config import PairFlockConfig, make_config
from ..core import PairFlockCore, real_array
from ..learning import LearningInterface, make_interface

__all__ = [
    "RENDER_MODES",
    "HeldStep",
    "SwarmFrames",
    "build_core_and_interface",
    "check_policy_actions",
    "held_step",
]

RENDER_MODES = ("rgb_array", "human")


def build_core_and_interface(
    preset: str | None,
    config: PairFlockConfig | None,
    overrides: Mapping[str, Any],
    num_envs: int,
    seed: Any,
    frame: str,
    frame_params: Mapping[str, Any] | None,
    render_mode: str | None,
) -> tuple[PairFlockCore, LearningInterface]:
    """Validated core of ``num_envs`` swarms plus its learning interface."""
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ValueError(
            f"render_mode={render_mode!r} is invalid: must be None or one of {RENDER_MODES}"
        )
    if frame_params is not None and not isinstance(frame_params, Mapping):
        raise TypeError(f"frame_params={frame_params!r} is invalid: must be a dict or None")
    if config is None:
        config = make_config(preset, **overrides)
    elif overrides:
        config = config.replace(**overrides)
    interface = make_interface(frame, config, **dict(frame_params or {}))
    core = PairFlockCore(config, num_envs=num_envs, seed=seed)
    return core, interface


def check_policy_actions(actions: Any, shape: tuple[int, ...], name: str = "actions") -> np.ndarray:
    """Policy actions as float64 of exactly ``shape``; TypeError/ValueError otherwise."""
    return real_array(actions, name, shape)


@dataclasses.dataclass
class HeldStep:
    """One policy decision of every swarm (arrays with leading axis B)."""

    obs: np.ndarray
    """(B, M, obs_size) physical observation after the decision, or at the control step where
    the swarm's episode ended."""
    reward: np.ndarray
    """(B, M) the interface's reward averaged over the control steps actually run."""
    terminated: np.ndarray
    truncated: np.ndarray
    info: dict[str, np.ndarray]
    """The core's infos at the same control step as ``obs``."""


def held_step(
    core: PairFlockCore, interface: LearningInterface, obs: np.ndarray, actions: np.ndarray
) -> HeldStep:
    """Apply policy actions (B, M, dim) for ``interface.decision_period`` control steps.

    Each control step decodes the held policy action against the fresh physical observation
    (so frame and feed-forward stay current) and steps the core. A swarm whose episode ends
    part-way keeps its results from that step; it goes on integrating with no pair term
    until the view resets it (the core steps all swarms together).
    """
    B, M = actions.shape[:2]
    k = interface.decision_period
    if k == 1:
        res = core.step(interface.decode(obs, actions))
        r = interface.reward(res.reward, res.info, actions, res.obs)
        return HeldStep(res.obs, r, res.terminated, res.truncated, res.info)
    total = np.zeros((B, M))
    count = np.zeros(B)
    ended = np.zeros(B, bool)
    terminated = np.zeros(B, bool)
    truncated = np.zeros(B, bool)
    out_obs = out_info = None
    for _ in range(k):
        env_a = interface.decode(obs, actions)
        if ended.any():
            env_a[ended] = 0.0
        res = core.step(env_a)
        live = ~ended
        total[live] += interface.reward(res.reward, res.info, actions, res.obs)[live]
        count[live] += 1
        if out_obs is None:
            out_obs = res.obs.copy()
            out_info = {key: v.copy() for key, v in res.info.items()}
        else:
            out_obs[live] = res.obs[live]
            for key, v in res.info.items():
                out_info[key][live] = v[live]
        now = live & (res.terminated | res.truncated)
        terminated[now] = res.terminated[now]
        truncated[now] = res.truncated[now]
        ended |= now
        obs = res.obs
    return HeldStep(out_obs, total / count[:, None], terminated, truncated, out_info)


class SwarmFrames:
    """Lazily created renderers, one per swarm, drawing a core's swarm b."""

    def __init__(self, core: PairFlockCore, render_mode: str | None) -> None:
        self.core = core
        self.render_mode = render_mode
        self._renderers: dict[int, Any] = {}

    def render(self, b: int, title: str | None = None):
        if self.render_mode is None:
            import warnings

            warnings.warn(
                "render() called without a render_mode; pass render_mode=...", stacklevel=3
            )
            return None
        from ..render import SwarmRenderer

        r = self._renderers.get(b)
        if r is None:
            cfg = self.core.config
            r = self._renderers[b] = SwarmRenderer(cfg.pairs, cfg.d_m, self.render_mode)
        core = self.core
        lq, _ = core.leader_state()
        if title is None:
            t = core.t[b]
            title = f"swarm {b}   t = {t:.2f} s"
        if self.render_mode == "rgb_array":
            return r.rgb_array(core.q[b], core.p[b], lq[b], title)
        r.human(core.q[b], core.p[b], lq[b], title)
        return None

    def reset(self, rows=None) -> None:
        for b, r in self._renderers.items():
            if rows is None or b in rows:
                r.reset()

    def close(self) -> None:
        for r in self._renderers.values():
            r.close()
        self._renderers.clear()
