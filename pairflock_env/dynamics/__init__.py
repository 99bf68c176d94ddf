"""Vehicle models behind the swarm protocol, and their registry :data:`VEHICLES`.

Every model takes the same command: a desired acceleration ``a_des`` of shape (B, N, dim),
held over one control period (zero-order hold), and advances positions ``q`` and velocities
``p`` (B, N, dim) in place over ``config.substeps`` physics steps. A model may keep extra state
(attitude, rotor speeds) of its own and report per-swarm diagnostics through ``info()``.

A vehicle is one :class:`Vehicle` entry, registered with ``VEHICLES.register(...)``; then
``dynamics="<name>"`` works in every view, controller and command line (docs/extending.md).
"""

from __future__ import annotations

from pairflock_env.config.registry import VEHICLES
from pairflock_env.dynamics.particle import ParticleModel
from pairflock_env.dynamics.quadrotor import QuadrotorModel
from pairflock_env.dynamics.quadrotor import section as quadrotor_section
from pairflock_env.dynamics.vehicle import Vehicle, VehicleModel, make_vehicle

__all__ = [
    "VEHICLES",
    "ParticleModel",
    "QuadrotorModel",
    "Vehicle",
    "VehicleModel",
    "make_vehicle",
]

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

# the Crazyflie registers itself when imported, as a plug-in does (after the built-ins, so the
# registry and the docs list them in this order)
from pairflock_env.dynamics import crazyflie  # noqa: E402, F401
