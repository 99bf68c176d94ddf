"""Vehicle models behind the swarm protocol.

Every model takes the same command: a desired acceleration ``a_des`` of shape (B, N, dim),
held over one control period (zero-order hold), and advances positions ``q`` and velocities
``p`` (B, N, dim) in place over ``config.substeps`` physics steps. A model may keep extra state
(attitude, rotor speeds) of its own and report per-swarm diagnostics through ``info()``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.dynamics.particle import ParticleModel
from pairflock_env.dynamics.quadrotor import QuadrotorModel

__all__ = ["VEHICLES", "ParticleModel", "QuadrotorModel", "VehicleModel", "make_vehicle"]


class VehicleModel(Protocol):
    name: str

    def reset_rows(self, rows: np.ndarray, q: np.ndarray, p: np.ndarray) -> None:
        """(Re)initialise the model's own state for swarms ``rows`` at positions q, velocities p."""
        ...

    def advance(self, q: np.ndarray, p: np.ndarray, a_des: np.ndarray) -> None:
        """Integrate one control period in place under the held command ``a_des``."""
        ...

    def info(self) -> dict[str, np.ndarray]:
        """Per-swarm diagnostics of the last control period, arrays with leading axis B."""
        ...


VEHICLES: dict[str, Callable[[PairFlockConfig, int], VehicleModel]] = {
    "particle": ParticleModel,
    "quadrotor": QuadrotorModel,
}


def make_vehicle(config: PairFlockConfig, num_swarms: int) -> VehicleModel:
    return VEHICLES[config.dynamics](config, num_swarms)
