"""Vehicle models behind the swarm protocol, and their registry :data:`VEHICLES`.

Every model takes the same command: a desired acceleration ``a_des`` of shape (B, N, dim),
held over one control period (zero-order hold), and advances positions ``q`` and velocities
``p`` (B, N, dim) in place over ``config.substeps`` physics steps. A model may keep extra state
(attitude, rotor speeds) of its own and report per-swarm diagnostics through ``info()``.

A vehicle is one :class:`Vehicle` entry, registered with ``VEHICLES.register(...)``; then
``dynamics="<name>"`` works in every view, controller and command line (docs/extending.md).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from pairflock_env.config.registry import VEHICLES, Plugin
from pairflock_env.dynamics.particle import ParticleModel
from pairflock_env.dynamics.quadrotor import QuadrotorModel
from pairflock_env.dynamics.quadrotor import section as quadrotor_section

__all__ = [
    "VEHICLES",
    "ParticleModel",
    "QuadrotorModel",
    "Vehicle",
    "VehicleModel",
    "make_vehicle",
]


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


VEHICLES.register(
    Vehicle(
        name="particle",
        doc="double integrator q' = p, p' = u (eq. 1)",
        model=ParticleModel,
    )
)
VEHICLES.register(
    Vehicle(
        name="quadrotor",
        doc="6-DOF rigid body with rotor lag behind a geometric attitude controller "
        "(docs/quadrotor.md)",
        section=quadrotor_section.QUADROTOR,
        rules=quadrotor_section.RULES,
        derived=quadrotor_section.DERIVED,
        model=QuadrotorModel,
        dims=(3,),
        substeps=quadrotor_section.min_substeps,
        accel_bound=quadrotor_section.accel_bound,
        reaction_time=quadrotor_section.reaction_time,
        safety_decay=0.1,
        info_keys=QuadrotorModel.INFO_KEYS,
    )
)

# plug-in vehicles of this package, registered through the same seam (their own sections)
from pairflock_env.dynamics import crazyflie as _crazyflie  # noqa: E402, F401
