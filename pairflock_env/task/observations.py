"""The named observation layout of a paired UAV (an agent), and the observation-field seam.

Each agent sees a flat float32 vector. Its layout is a contract: controllers and policies read
it by name through :class:`ObsLayout` (``layout.get(obs, "partner_offset")``), never by
index, and the documentation table is generated from the same object
(``layout.markdown_table()``), so code and docs cannot drift apart.

Values are physical (SI units, world frame, relative to the observing UAV), so the analytic
controllers of the paper read them directly; learning views may rescale them on top. More
fields are :class:`ObservationField` entries of :data:`OBSERVATIONS`, appended after the
built-in ones for the names a config lists in ``obs_extra`` (docs/extending.md).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from pairflock_env.config.registry import OBSERVATIONS, Plugin
from pairflock_env.layout import Field as LayoutField
from pairflock_env.layout import FlatLayout

__all__ = [
    "OBSERVATIONS",
    "ObsLayout",
    "ObservationContext",
    "ObservationField",
    "add_sensor_noise",
]

#: largest float32: noisy observations saturate here instead of overflowing to inf
_F32_MAX = float(np.finfo(np.float32).max)


@dataclasses.dataclass(frozen=True)
class ObservationContext:
    """What an :class:`ObservationField` computes its value from: the true state after a
    step (arrays with leading axis B; M agents)."""

    config: Any
    q: np.ndarray
    """positions of every UAV (B, N, dim), m"""
    p: np.ndarray
    """velocities (B, N, dim), m/s"""
    t: np.ndarray
    """sim time (B,), s"""
    leader_q: np.ndarray
    """leader position (B, dim), m"""
    leader_p: np.ndarray
    """leader velocity (B, dim), m/s"""
    agent_uavs: np.ndarray
    """UAV index of each agent (M,)"""
    partner_uavs: np.ndarray
    """UAV index of each agent's partner (M,)"""
    flock_accel: np.ndarray
    """every UAV's flocking command (B, N, dim), m/s^2"""


@dataclasses.dataclass(frozen=True, kw_only=True)
class ObservationField(Plugin):
    """A registered observation field.

    Attributes (besides :class:`~pairflock_env.config.registry.Plugin`'s):
        shape: its shape for (dim, obs_neighbors), e.g. ``lambda dim, k: (dim,)``.
        unit: its unit, for the docs table.
        value: its value ``value(ctx) -> (B, M, *shape)`` from an :class:`ObservationContext`.
        bound: a bound on |value| for a config (every entry; the views' observation space).
    """

    shape: Callable[[int, int], tuple[int, ...]]
    unit: str
    value: Callable[[ObservationContext], np.ndarray]
    bound: Callable[[Any], float]

    def size(self, dim: int, n_neighbors: int) -> int:
        return math.prod(self.shape(dim, n_neighbors))

    def layout_field(self, dim: int, n_neighbors: int) -> LayoutField:
        return LayoutField(self.name, tuple(self.shape(dim, n_neighbors)), self.unit, self.doc)


def _builtin_fields(D: int, K: int) -> list[LayoutField]:
    """Every field of the layout for dim D and K neighbour slots (some may have size 0)."""
    return [
        LayoutField(
            "partner_offset",
            (D,),
            "m",
            "q_partner - q_self (y of eq. 21 for UAV A, -y for UAV B)",
        ),
        LayoutField(
            "partner_velocity",
            (D,),
            "m/s",
            "p_partner - p_self (y' of eq. 22 for A, -y' for B)",
        ),
        LayoutField("target_distance", (1,), "m", "d_m of this pair"),
        LayoutField(
            "shared_neighbors",
            (1,),
            "count",
            "N of eq. 28: neighbours shared by the pair, +2 if A and B are neighbours",
        ),
        LayoutField("leader_offset", (D,), "m", "q_leader - q_self"),
        LayoutField("leader_velocity", (D,), "m/s", "p_leader - p_self"),
        LayoutField(
            "flock_accel",
            (D,),
            "m/s^2",
            "own flocking command f^g + f^v + h f^gamma this control period",
        ),
        LayoutField(
            "partner_flock_accel",
            (D,),
            "m/s^2",
            "the partner's flocking command this control period",
        ),
        LayoutField(
            "neighbor_offsets",
            (K, D),
            "m",
            "q_j - q_self of the K nearest non-partner UAVs, nearest first",
        ),
        LayoutField("neighbor_velocities", (K, D), "m/s", "p_j - p_self of the same UAVs"),
        LayoutField(
            "neighbor_mask",
            (K,),
            "0/1",
            "1 where the neighbour slot holds a UAV (0 when N - 2 < K)",
        ),
    ]


class ObsLayout(FlatLayout):
    """Ordered named fields of the per-agent observation for a given ``dim``, K and extra
    (registered) fields."""

    def __init__(self, dim: int, n_neighbors: int, extra: tuple[str, ...] = ()) -> None:
        self.dim = dim
        self.n_neighbors = n_neighbors
        self.extra = tuple(extra)
        more = [OBSERVATIONS[name].layout_field(dim, n_neighbors) for name in self.extra]
        super().__init__([*_builtin_fields(dim, n_neighbors), *more], "observation")

    @classmethod
    def for_config(cls, config: Any) -> ObsLayout:
        """The layout of ``config``'s observation (``dim``, ``obs_neighbors``, ``obs_extra``)."""
        return cls(config.dim, config.obs_neighbors, config.obs_extra)

    def _size_hint(self) -> str:
        return f" (dim={self.dim}, obs_neighbors={self.n_neighbors})"


def add_sensor_noise(clean: np.ndarray, noise: np.ndarray) -> np.ndarray:
    """``clean + noise`` (float64), saturated to the float32 range of the observation.

    Sensor noise changes what an agent sees, never whether its swarm counts as diverged: where
    the true value ``clean`` fits in float32, the noisy value is clipped to +-float32 max
    instead of overflowing to inf; where it does not (a runaway or non-finite state), the
    true value is kept, so the observation check flags the swarm as it would without noise.
    """
    noisy = clean + noise
    if np.all(np.abs(noisy) <= _F32_MAX):
        return noisy
    return np.where(np.abs(clean) <= _F32_MAX, np.clip(noisy, -_F32_MAX, _F32_MAX), clean)
