"""What a vehicle model is to the env: the :class:`VehicleModel` protocol the core drives and the
:class:`Vehicle` entry of the registry :data:`~pairflock_env.config.registry.VEHICLES`."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from pairflock_env.config.registry import VEHICLES, Plugin

__all__ = ["Vehicle", "VehicleModel", "make_vehicle"]


class VehicleModel(Protocol):
    """What the core asks of a vehicle model built as ``model(config, num_swarms)``."""

    def reset_rows(self, rows: np.ndarray, q: np.ndarray, p: np.ndarray) -> None:
        """(Re)initialise the model's own state for swarms ``rows`` at positions q, velocities p."""
        ...

    def advance(self, q: np.ndarray, p: np.ndarray, a_des: np.ndarray) -> None:
        """Integrate one control period in place under the held command ``a_des``."""
        ...

    def info(self) -> dict[str, np.ndarray]:
        """Diagnostics of the last control period, arrays with leading axis B (per swarm
        (B,), or per agent (B, M)); the key ``vehicle_terminated`` (B,) bool, if present, ends
        the episode."""
        ...


@dataclasses.dataclass(frozen=True, kw_only=True)
class Vehicle(Plugin):
    """A registered vehicle model and what the rest of the env asks about it.

    Attributes (besides :class:`~pairflock_env.config.registry.Plugin`'s name, doc and own
    config section):
        model: builds the model, ``model(config, num_swarms) -> VehicleModel``.
        dims: the spatial dimensions it flies in; the first is ``dim``'s default.
        substeps: the default of ``substeps`` for a config (None: 1).
        accel_bound: the acceleration it can realise for a config (m/s^2; None: unbounded);
            the safety filter's unset braking bounds stay within it.
        reaction_time: how late it realises a command (s; None: at once); the filter's
            default reaction time. It must lie in [0, ``MAX_REACTION_TIME``] for every config
            the vehicle's section accepts (the quadrotor's section has the rule).
        safety_decay: the filter's default barrier rate on it (None: the filter's own).
        info_keys: the keys of ``model.info()``.
    """

    model: Callable[[Any, int], VehicleModel]
    dims: tuple[int, ...] = (2, 3)
    substeps: Callable[[Any], int] | None = None
    accel_bound: Callable[[Any], float] | None = None
    reaction_time: Callable[[Any], float] | None = None
    safety_decay: float | None = None
    info_keys: tuple[str, ...] = ()


def make_vehicle(config: Any, num_swarms: int) -> VehicleModel:
    """The vehicle model ``config.dynamics`` for ``num_swarms`` swarms."""
    return VEHICLES[config.dynamics].model(config, num_swarms)
