"""The quadrotor vehicle model: the state it keeps and the control period it flies."""

from __future__ import annotations

import math

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.dynamics.quadrotor.kernels import quadrotor_kernel
from pairflock_env.dynamics.quadrotor.params import QuadrotorParams

__all__ = ["QuadrotorModel"]


class QuadrotorModel:
    """B x N quadrotors behind the desired-acceleration interface (see the module docstring).

    Attributes (read-only views of the vehicle state; the core owns q and p):
        R: attitude, body to world, (B, N, 3, 3).
        R_des: the attitude the controller commanded in the last physics step, (B, N, 3, 3)
            (for Euler-angle plots: ``math3d.euler_zyx(model.R_des)`` vs ``euler_zyx(model.R)``).
        omega: body rates (B, N, 3), rad/s.  rotor_speed: (B, N, 4), rad/s.
        crashed: (B, N) bool, sticky until the swarm is reset.
        motor_saturated, accel_limited: (B, N) bool flags of the last control period.
    """

    name = "quadrotor"
    #: the keys of :meth:`info`
    INFO_KEYS = (
        "vehicle_terminated",
        "crashed_uavs",
        "motor_saturated_uavs",
        "accel_limited_uavs",
        "crashed",
        "motor_saturated",
        "accel_limited",
        "tilt",
    )

    def __init__(self, config: PairFlockConfig, num_swarms: int) -> None:
        if config.dim != 3:
            raise ValueError(f"dim={config.dim!r} is invalid: the quadrotor model needs dim=3")
        self.params = prm = QuadrotorParams(config)
        B, N = int(num_swarms), config.n_uavs
        self.agent_uavs = np.asarray(config.pairs, dtype=np.int64).reshape(-1)
        self.R = np.zeros((B, N, 3, 3))
        self.R_des = np.zeros((B, N, 3, 3))
        self.omega = np.zeros((B, N, 3))
        self.rotor_speed = np.zeros((B, N, 4))
        self.crashed = np.zeros((B, N), np.bool_)
        self.motor_saturated = np.zeros((B, N), np.bool_)
        self.accel_limited = np.zeros((B, N), np.bool_)
        self._crashed_now = np.zeros((B, N), np.bool_)
        c, s = math.cos(prm.yaw), math.sin(prm.yaw)
        self._R0 = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    @property
    def motor_thrust(self) -> np.ndarray:
        """Rotor thrusts k_f W_i^2 (B, N, 4), N."""
        return self.params.k_f * self.rotor_speed**2

    def reset_rows(self, rows: np.ndarray, q: np.ndarray, p: np.ndarray) -> None:
        """Swarms ``rows`` start level at the fixed heading, body rates zero, every rotor at
        the exact hover speed sqrt(m g / (4 k_f)); q and p are the core's initial state."""
        self.R[rows] = self._R0
        self.R_des[rows] = self._R0
        self.omega[rows] = 0.0
        self.rotor_speed[rows] = self.params.hover_speed
        for arr in (self.crashed, self.motor_saturated, self.accel_limited, self._crashed_now):
            arr[rows] = False

    def advance(self, q: np.ndarray, p: np.ndarray, a_des: np.ndarray) -> None:
        """Fly ``substeps`` physics steps under the held desired acceleration a_des (B, N, 3)."""
        prm = self.params
        quadrotor_kernel(
            q,
            p,
            np.ascontiguousarray(a_des, dtype=np.float64),
            self.R,
            self.omega,
            self.rotor_speed,
            self.crashed,
            self.R_des,
            self.motor_saturated,
            self.accel_limited,
            self._crashed_now,
            prm.substeps,
            prm.h,
            prm.vector,
        )

    def tilt(self) -> np.ndarray:
        """Angle between each body z axis and the vertical, (B, N), degrees."""
        return np.degrees(np.arccos(np.clip(self.R[..., 2, 2], -1.0, 1.0)))

    def info(self) -> dict[str, np.ndarray]:
        """Diagnostics of the last control period.

        Swarm level (B,): ``vehicle_terminated`` (some UAV of the swarm has crashed: the core
        ends the episode), ``crashed_uavs``, ``motor_saturated_uavs``, ``accel_limited_uavs``
        (counts over all N UAVs). Per agent (B, M): ``crashed``, ``motor_saturated`` (a
        rotor command was clipped to its thrust limits during the period), ``accel_limited``
        (the command was cut by the acceleration limit or the tilt cone), ``tilt`` (deg).
        """
        ia = self.agent_uavs
        crashed = self.crashed
        return {
            "vehicle_terminated": crashed.any(axis=1),
            "crashed_uavs": crashed.sum(axis=1),
            "motor_saturated_uavs": self.motor_saturated.sum(axis=1),
            "accel_limited_uavs": self.accel_limited.sum(axis=1),
            "crashed": crashed[:, ia].copy(),
            "motor_saturated": self.motor_saturated[:, ia].copy(),
            "accel_limited": self.accel_limited[:, ia].copy(),
            "tilt": np.degrees(np.arccos(np.clip(self.R[:, ia, 2, 2], -1.0, 1.0))),
        }
