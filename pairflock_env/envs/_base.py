"""What every view (PettingZoo, Gymnasium Env and VectorEnv, SB3 VecEnv) shares: the view base
class :class:`SwarmView` (building the core and the learning interface from keyword
arguments, rendering, the closed-env guard), validating actions and reset options, and holding
a policy action for a decision period. No physics here."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.config.arrays import real_array
from pairflock_env.core import PairFlockCore, check_count
from pairflock_env.interfaces import INTERFACES, LearningInterface, make_interface
from pairflock_env.interfaces.hold import DecisionHold
from pairflock_env.render import SwarmRenderer
from pairflock_env.swarm.placement import check_reset_options

__all__ = [
    "RENDER_MODES",
    "HeldStep",
    "SwarmRenderers",
    "SwarmView",
    "check_policy_actions",
    "check_render_mode",
    "check_reset_options",
    "held_step",
]

RENDER_MODES = ("rgb_array", "human")


def check_render_mode(render_mode: Any) -> str | None:
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ValueError(
            f"render_mode={render_mode!r} is invalid: must be None or one of {RENDER_MODES}"
        )
    return render_mode


def _interface_args(interface: Any, params: Any, default: str) -> tuple[str, dict[str, Any]]:
    """The learning interface's name and parameters from a view's keywords."""
    name = default if interface is None else interface
    if not isinstance(name, str) or name not in INTERFACES:
        raise ValueError(f"interface={name!r} is invalid: must be one of {list(INTERFACES)}")
    if params is not None and not isinstance(params, Mapping):
        raise TypeError(f"interface_params={params!r} is invalid: must be a dict or None")
    return name, dict(params or {})


class SwarmView:
    """The base of every view: one core of ``num_swarms`` swarms, its learning interface,
    its renderers, and the closed-env guard.

    A view calls :meth:`_open` first thing in its constructor; after ``close()`` it refuses
    ``reset()`` / ``step()`` with a ``RuntimeError`` (a closed env has released its windows
    and is not reused).
    """

    _closed = False
    #: the learning interface a view uses when ``interface`` is not given
    default_interface = "pair"

    def _open(
        self,
        *,
        preset: str | None,
        config: PairFlockConfig | None,
        overrides: Mapping[str, Any],
        num_swarms: int,
        seed: Any,
        interface: str | None,
        interface_params: Mapping[str, Any] | None,
        render_mode: str | None,
    ) -> None:
        """Validate the keywords, then build the core (the config is resolved in one place,
        the core's constructor: ``config``, else ``preset`` plus the flat ``overrides``) and
        its learning interface."""
        name, params = _interface_args(interface, interface_params, self.default_interface)
        check_render_mode(render_mode)
        check_count("num_swarms", num_swarms)
        if config is not None and not isinstance(config, PairFlockConfig):
            raise TypeError(f"config={config!r} is invalid: must be a PairFlockConfig or None")
        core = PairFlockCore(config, num_swarms=num_swarms, seed=seed, preset=preset, **overrides)
        self.core = core
        self.interface: LearningInterface = make_interface(name, core.config, **params)
        self.interface_name = name
        self.config = core.config
        self.layout = core.layout
        self.render_mode = render_mode
        #: the physical observation (B, M, obs_size) behind the last encoded one
        self.physical_obs: np.ndarray | None = None
        self._renderers = SwarmRenderers(core, render_mode)

    def _check_open(self, method: str) -> None:
        if self._closed:
            raise RuntimeError(f"{method}() called after close(); create a new env")

    def _mark_closed(self) -> None:
        self._closed = True


def check_policy_actions(actions: Any, shape: tuple[int, ...], name: str = "actions") -> np.ndarray:
    """Policy actions as float64 of exactly ``shape``; TypeError/ValueError naming ``name``
    otherwise.

    :func:`~pairflock_env.task.actions.real_array` rejects NaN/inf and saturates finite values
    beyond float64's range (``np.longdouble("1e400")``, huge ints) to +-float64 max, so the
    result is always finite: one check per action, nothing to repeat here.
    """
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
    """Apply checked policy actions (B, M, dim) for ``interface.decision_period`` control steps.

    Each control step decodes the held policy action against the fresh physical observation
    (:class:`~pairflock_env.interfaces.hold.DecisionHold`) and steps the core. A swarm whose episode
    ends part-way keeps its results from that step; while other swarms go on, it integrates
    with no pair term until the view resets it (the core steps all swarms together). The
    decision stops early once every swarm has ended, so a single swarm's state stays at the
    step its episode ended. The returned arrays may be the core's own (read, do not write).
    """
    k = interface.decision_period
    if k != 1:
        return _held_decision(core, interface, obs, actions, k)
    if interface.passes_through:  # the identity: the policy's action is the env's
        res = core.step(actions)
        return HeldStep(res.obs, res.reward, res.terminated, res.truncated, res.info)
    res = core.step(interface.decode(obs, actions))
    r = interface.reward(res.reward, res.info, actions, res.obs)
    return HeldStep(res.obs, r, res.terminated, res.truncated, res.info)


def _held_decision(
    core: PairFlockCore, interface: LearningInterface, obs: np.ndarray, actions: np.ndarray, k: int
) -> HeldStep:
    """:func:`held_step` for k > 1 control steps. While every swarm is live the results are
    the latest step's; once some (not all) swarms have ended, row by row."""
    B, M = actions.shape[:2]
    hold = DecisionHold.decided(interface, actions)
    total = np.zeros((B, M))
    count = np.zeros(B)
    ended = np.zeros(B, bool)
    terminated = np.zeros(B, bool)
    truncated = np.zeros(B, bool)
    out_obs = out_info = None  # set once some swarms have ended and others go on
    for _ in range(k):
        env_a = hold.env_action(obs)
        if out_obs is not None:
            env_a = np.where(ended[:, None, None], 0.0, env_a)
        res = core.step(env_a)
        r = interface.reward(res.reward, res.info, actions, res.obs)
        done = res.terminated | res.truncated
        if out_obs is None:  # every swarm live
            total += r
            count += 1
            now = done
        else:
            live = ~ended
            total[live] += r[live]
            count[live] += 1
            out_obs[live] = res.obs[live]
            for key, v in res.info.items():
                out_info[key][live] = v[live]
            now = live & done
        if now.any():
            terminated[now] = res.terminated[now]
            truncated[now] = res.truncated[now]
            ended |= now
            if ended.all():
                break
            if out_obs is None:
                out_obs = res.obs.copy()
                out_info = {key: v.copy() for key, v in res.info.items()}
        obs = res.obs
    if out_obs is None:
        out_obs, out_info = res.obs, res.info
    return HeldStep(out_obs, total / count[:, None], terminated, truncated, out_info)


class SwarmRenderers:
    """The one render path of every view: lazily created renderers, one per swarm.

    ``render(b)`` with ``render_mode=None`` warns and returns None (Gymnasium's convention);
    before the first :meth:`reset` it raises ``RuntimeError`` (there is no swarm to draw yet).
    """

    def __init__(self, core: PairFlockCore, render_mode: str | None) -> None:
        self.core = core
        self.render_mode = render_mode
        self._renderers: dict[int, Any] = {}
        self._ready = False

    def render(self, b: int, title: str | None = None):
        if self.render_mode is None:
            warnings.warn(
                "render() called without a render_mode; pass render_mode=...", stacklevel=3
            )
            return None
        if not self._ready:
            raise RuntimeError("call reset() before render(): there is no swarm to draw yet")
        r = self._renderers.get(b)
        if r is None:
            cfg = self.core.config
            r = self._renderers[b] = SwarmRenderer(cfg.pairs, cfg.d_m, self.render_mode)
        core = self.core
        lq, _ = core.leader_state()
        if title is None:
            title = f"swarm {b}   t = {core.t[b]:.2f} s"
        if self.render_mode == "rgb_array":
            return r.rgb_array(core.q[b], core.p[b], lq[b], title)
        r.human(core.q[b], core.p[b], lq[b], title)
        return None

    def reset(self, rows=None) -> None:
        """Swarms ``rows`` (all when None) start a new episode: forget their headings."""
        self._ready = True
        for b, r in self._renderers.items():
            if rows is None or b in rows:
                r.reset()

    def close(self) -> None:
        for r in self._renderers.values():
            r.close()
        self._renderers.clear()
