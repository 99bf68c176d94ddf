"""The Crazyflie kernel's parameters, packed from a validated config (one
:class:`~pairflock_env.kernels.KernelParams` layout, one name per quantity)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from pairflock_env.dynamics.crazyflie.data import (
    CRAZYFLIE_MODELS,
    FIRMWARE,
    FIRMWARE_RATE,
    MELLINGER_GAINS,
)
from pairflock_env.dynamics.crazyflie.kernels import (
    CRAZYFLIE_KERNEL,
    axis_names,
    rotor_speed_for_thrust,
)

__all__ = ["CRAZYFLIE_KERNEL", "CrazyflieParams", "hover_rpm"]


def hover_rpm(model: str) -> float:
    """Rotor speed (RPM) at which the four rotors of set ``model`` carry its weight."""
    a = CRAZYFLIE_MODELS[model]
    return rotor_speed_for_thrust(a["mass"] * FIRMWARE["gravity"] / 4.0, *a["rpm2thrust"])


_ROTOR_LAW = ("spin_up_linear", "spin_up_quadratic", "spin_down_linear", "spin_down_quadratic")


def _per_axis(name: str, values: Any) -> dict[str, float]:
    return dict(zip(axis_names(name), map(float, values), strict=True))


class CrazyflieParams:
    """The derived constants of a config with ``dynamics="crazyflie"`` and the packed vector
    ``vector`` (the config has been validated: dt is a whole number of ticks, substeps a
    multiple of them, the rates divide them).

    Attributes: ``model`` (the set's name), ``airframe`` (its data), ``dt``, ``ticks``
    (firmware ticks per period), ``physics_substeps`` (plant steps per tick),
    ``position_every`` and ``setpoint_every`` (ticks between updates), ``yaw`` (rad),
    ``anchored``, ``hover_rpm``.
    """

    def __init__(self, cfg: Any) -> None:
        self.model = cfg.crazyflie_model
        self.airframe = CRAZYFLIE_MODELS[self.model]
        self.dt = float(cfg.dt)
        self.ticks = round(self.dt * FIRMWARE_RATE)
        self.physics_substeps = int(cfg.substeps) // self.ticks
        self.position_every = round(FIRMWARE_RATE / cfg.crazyflie_position_rate)
        sp = cfg.crazyflie_setpoint_rate
        self.setpoint_every = self.ticks if sp is None else round(FIRMWARE_RATE / sp)
        self.yaw = math.radians(cfg.crazyflie_yaw)
        self.anchored = cfg.crazyflie_reference == "anchored"
        self.hover_rpm = hover_rpm(self.model)
        ground = cfg.crazyflie_ground_altitude
        self.vector = self._pack(cfg, -math.inf if ground is None else ground)

    def _pack(self, cfg: Any, ground: float) -> np.ndarray:
        a, fw, g = self.airframe, FIRMWARE, MELLINGER_GAINS
        values = dict(
            mass=a["mass"],
            gravity=fw["gravity"],
            arm=a["arm"],
            prop_inertia=a["prop_inertia"],
            **_per_axis("inertia", a["inertia"]),
            **_per_axis("inv_inertia", [1.0 / j for j in a["inertia"]]),
            **dict(zip(("thrust_k0", "thrust_k1", "thrust_k2"), a["rpm2thrust"], strict=True)),
            **dict(zip(("torque_k0", "torque_k1", "torque_k2"), a["rpm2torque"], strict=True)),
            **dict(zip(_ROTOR_LAW, a["rotor_dyn"], strict=True)),
            **_per_axis("drag", a["drag"]),
            ctrl_mass=a["ctrl_mass"],
            **{k: v for name, val in g.items() for k, v in _per_axis(name, val).items()},
            position_h=self.position_every / FIRMWARE_RATE,
            thrust_scale=fw["mass_thrust"] / fw["pwm_max"] * 4.0 * a["thrust_max"],
            **_per_axis("torque_pwm_max", fw["torque_pwm_max"]),
            tick=1.0 / FIRMWARE_RATE,
            pwm_min=fw["pwm_min"],
            pwm_max=fw["pwm_max"],
            thrust_min=a["thrust_min"],
            thrust_max=a["thrust_max"],
            physics_h=1.0 / (FIRMWARE_RATE * self.physics_substeps),
            cos_crash_tilt=math.cos(math.radians(cfg.crazyflie_crash_tilt)),
            ground_altitude=ground,
            accel_limit=cfg.crazyflie_accel_limit,
            leash=cfg.crazyflie_leash,
            leash_velocity=cfg.crazyflie_leash_velocity,
            dt=self.dt,
            yaw=self.yaw,
            anchored=float(self.anchored),
            ticks=self.ticks,
            position_every=self.position_every,
            setpoint_every=self.setpoint_every,
            physics_substeps=self.physics_substeps,
        )
        return CRAZYFLIE_KERNEL.pack(**values)
