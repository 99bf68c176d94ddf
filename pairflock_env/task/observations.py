"""The named observation layout of a paired UAV (an agent).

Each agent sees a flat float32 vector. Its layout is a contract: controllers and policies read
it by name through :class:`ObsLayout` (``layout.get(obs, "partner_offset")``), never by
index, and the documentation table is generated from the same object
(``layout.markdown_table()``), so code and docs cannot drift apart.

Values are physical (SI units, world frame, relative to the observing UAV), so the analytic
controllers of the paper read them directly; learning views may rescale them on top.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator, Mapping

import numpy as np

__all__ = ["ObsField", "ObsLayout", "add_sensor_noise", "build_observation"]

#: largest float32: noisy observations saturate here instead of overflowing to inf
_F32_MAX = float(np.finfo(np.float32).max)


@dataclasses.dataclass(frozen=True)
class ObsField:
    """One named field of the observation: its shape, unit and meaning."""

    name: str
    shape: tuple[int, ...]
    unit: str
    description: str

    @property
    def size(self) -> int:
        """Number of values of the field in the flat observation."""
        return math.prod(self.shape)


def _all_fields(D: int, K: int) -> list[ObsField]:
    """Every field of the layout for dim D and K neighbour slots (some may have size 0)."""
    return [
        ObsField(
            "partner_offset",
            (D,),
            "m",
            "q_partner - q_self (y of eq. 21 for UAV A, -y for UAV B)",
        ),
        ObsField(
            "partner_velocity",
            (D,),
            "m/s",
            "p_partner - p_self (y' of eq. 22 for A, -y' for B)",
        ),
        ObsField("target_distance", (1,), "m", "d_m of this pair"),
        ObsField(
            "shared_neighbors",
            (1,),
            "count",
            "N of eq. 28: neighbours shared by the pair, +2 if A and B are neighbours",
        ),
        ObsField("leader_offset", (D,), "m", "q_leader - q_self"),
        ObsField("leader_velocity", (D,), "m/s", "p_leader - p_self"),
        ObsField(
            "flock_accel",
            (D,),
            "m/s^2",
            "own flocking command f^g + f^v + h f^gamma this control period",
        ),
        ObsField(
            "partner_flock_accel",
            (D,),
            "m/s^2",
            "the partner's flocking command this control period",
        ),
        ObsField(
            "neighbor_offsets",
            (K, D),
            "m",
            "q_j - q_self of the K nearest non-partner UAVs, nearest first",
        ),
        ObsField("neighbor_velocities", (K, D), "m/s", "p_j - p_self of the same UAVs"),
        ObsField(
            "neighbor_mask",
            (K,),
            "0/1",
            "1 where the neighbour slot holds a UAV (0 when N - 2 < K)",
        ),
    ]


class ObsLayout:
    """Ordered named fields of the per-agent observation for a given ``dim`` and K."""

    def __init__(self, dim: int, n_neighbors: int) -> None:
        self.dim = dim
        self.n_neighbors = n_neighbors
        fields = _all_fields(dim, n_neighbors)
        self.fields: tuple[ObsField, ...] = tuple(f for f in fields if f.size > 0)
        self._slices: dict[str, slice] = {}
        offset = 0
        for f in self.fields:
            self._slices[f.name] = slice(offset, offset + f.size)
            offset += f.size
        self.size = offset
        self._by_name = {f.name: f for f in self.fields}
        # what build_observation needs per field, resolved once
        self._plan = tuple((f.name, self._slices[f.name], f.size) for f in self.fields)

    def __iter__(self) -> Iterator[ObsField]:
        return iter(self.fields)

    def __contains__(self, name: str) -> bool:
        return name in self._slices

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self._slices)

    def slice(self, name: str) -> slice:
        try:
            return self._slices[name]
        except KeyError:
            raise KeyError(
                f"no observation field {name!r}; fields are {', '.join(self.names)}"
            ) from None

    def get(self, obs: np.ndarray, name: str) -> np.ndarray:
        """The named field of ``obs`` (..., size) with its own shape: (..., *field.shape)."""
        obs = np.asarray(obs)
        if obs.shape[-1] != self.size:
            raise ValueError(
                f"observation has last dimension {obs.shape[-1]}, expected {self.size} "
                f"(dim={self.dim}, obs_neighbors={self.n_neighbors})"
            )
        f = self._by_name.get(name) or self.slice(name)  # raises KeyError with names
        return obs[..., self._slices[name]].reshape(obs.shape[:-1] + f.shape)

    def markdown_table(self) -> str:
        rows = ["| slice | field | shape | unit | meaning |", "|---|---|---|---|---|"]
        for f in self.fields:
            s = self._slices[f.name]
            rows.append(
                f"| {s.start}:{s.stop} | `{f.name}` | {f.shape} | {f.unit} | {f.description} |"
            )
        return "\n".join(rows)


def build_observation(
    layout: ObsLayout, batch: tuple[int, int], fields: Mapping[str, np.ndarray]
) -> np.ndarray:
    """The observation (B, M, layout.size) float32, filled field by field by name.

    Args:
        layout: the layout to fill.
        batch: (B, M).
        fields: an array per field of the layout, shaped (B, M, *field.shape) or broadcastable
            to it with its own leading axes (e.g. (1, M, 1) for one value per agent); names
            that the layout does not hold (fields of size 0) are ignored.

    Raises:
        KeyError: a field of the layout is missing from ``fields``.
    """
    B, M = batch
    obs = np.empty((B, M, layout.size), np.float32)
    for name, sl, size in layout._plan:
        try:
            v = fields[name]
        except KeyError:
            raise KeyError(f"no values for observation field {name!r}") from None
        obs[:, :, sl] = v if v.ndim == 3 else v.reshape((*v.shape[:2], size))  # not [...]: faster
    return obs


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
