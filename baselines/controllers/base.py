"""The common shape of every pair controller: SB3's ``predict`` over named observations."""

from __future__ import annotations

import difflib
import numbers
from typing import Any

import numpy as np

from pairflock_env import ObsLayout, PairFlockConfig

__all__ = ["PairPolicy", "ZeroPolicy", "check_observation", "gain_value", "resolve_env"]


def resolve_env(env: Any) -> tuple[PairFlockConfig, ObsLayout]:
    """(config, observation layout) of any pairflock view, core, or a bare config."""
    if isinstance(env, PairFlockConfig):
        return env, ObsLayout(env.dim, env.obs_neighbors)
    for obj in (env, getattr(env, "unwrapped", None), getattr(env, "core", None)):
        cfg = getattr(obj, "config", None)
        layout = getattr(obj, "layout", None)
        if isinstance(cfg, PairFlockConfig) and isinstance(layout, ObsLayout):
            return cfg, layout
    raise TypeError(
        f"env={env!r} is invalid: expected a pairflock env, core or PairFlockConfig "
        "(an object with .config and .layout)"
    )


def check_observation(observation: Any, size: int) -> np.ndarray:
    """``observation`` as float64, shaped (size,) or (n, size), every entry finite; a
    TypeError (not numbers) or ValueError (shape, NaN/inf) naming it otherwise."""
    try:
        obs = np.asarray(observation, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise TypeError(f"observation is invalid: expected an array of numbers ({e})") from None
    if obs.ndim not in (1, 2) or obs.shape[-1] != size:
        raise ValueError(f"observation has shape {obs.shape}; expected ({size},) or (n, {size})")
    if not np.isfinite(obs).all():
        rows = np.flatnonzero(~np.isfinite(obs.reshape(-1, size)).all(axis=1)).tolist()
        raise ValueError(
            f"observation holds NaN or inf (rows {rows}); a pairflock observation is finite"
        )
    return obs


def gain_value(name: str, value: Any, *, minimum: float, allow_minimum: bool) -> float:
    """A gain as a finite float ``> minimum`` (or ``>= minimum`` with ``allow_minimum``);
    TypeError for a non-number, ValueError for a bad number, both naming the gain."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(
            f"{name}={value!r} is invalid: must be a number, not {type(value).__name__}"
        )
    v = float(value)
    ok = np.isfinite(v) and (v >= minimum if allow_minimum else v > minimum)
    if not ok:
        op = ">=" if allow_minimum else ">"
        raise ValueError(f"{name}={v!r} is invalid: must be a finite number {op} {minimum:g}")
    return v


class PairPolicy:
    """A per-agent pair controller with stable-baselines3's ``predict`` signature.

    Subclasses implement :meth:`accel` (pairwise acceleration f^x_i in m/s^2, world frame)
    from a batch of observations; ``predict`` turns it into the env's normalised action
    (units of ``pair_accel_limit``). The env clips, so every controller is treated alike.
    """

    #: gain name -> (default, description); subclasses fill this in
    GAINS: dict[str, tuple[Any, str]] = {}

    def __init__(self, env: Any, **gains: Any) -> None:
        self.config, self.layout = resolve_env(env)
        unknown = sorted(set(gains) - set(self.GAINS))
        if unknown:
            valid = ", ".join(self.GAINS) or "none"
            hints = [h for u in unknown for h in difflib.get_close_matches(u, self.GAINS, n=1)]
            extra = f" (did you mean {', '.join(map(repr, hints))}?)" if hints else ""
            raise TypeError(
                f"unknown gain(s) {unknown} for {type(self).__name__}{extra}; valid gains: {valid}"
            )
        self.gains = {k: gains.get(k, self._default(k)) for k in self.GAINS}

    def _default(self, name: str) -> Any:
        return self.GAINS[name][0]

    def accel(self, obs: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """Action(s) for one observation (obs_size,) or a batch (n, obs_size); a NaN/inf,
        non-numeric or wrongly shaped observation raises (ValueError / TypeError)."""
        u = self.accel(check_observation(observation, self.layout.size))
        return (u / self.config.pair_accel_limit).astype(np.float32), state

    def __repr__(self) -> str:
        g = ", ".join(f"{k}={v!r}" for k, v in self.gains.items())
        return f"{type(self).__name__}({g})"


class ZeroPolicy(PairPolicy):
    """No pair term: the paired UAVs fly the flocking protocol only."""

    def accel(self, obs: np.ndarray) -> np.ndarray:
        return np.zeros((*obs.shape[:-1], self.config.dim))
