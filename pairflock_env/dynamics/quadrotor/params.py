"""The quadrotor's derived constants from a config, and its rotor geometry."""

from __future__ import annotations

import math

import numpy as np

from pairflock_env.config import PairFlockConfig
from pairflock_env.dynamics.quadrotor.kernels import QUADROTOR, mix_rows

__all__ = ["ROTOR_ANGLES_DEG", "ROTOR_SPIN", "QuadrotorParams"]

#: rotor positions: angle from the body x axis (deg), X configuration
ROTOR_ANGLES_DEG = (45.0, 135.0, 225.0, 315.0)
#: sign of each rotor's reaction torque about body z (Mz = kappa * sum(spin_i T_i))
ROTOR_SPIN = (1.0, -1.0, 1.0, -1.0)


class QuadrotorParams:
    """Derived constants of the quadrotor model and its inner loop, from a config."""

    def __init__(self, cfg: PairFlockConfig) -> None:
        self.mass = cfg.quad_mass
        self.inertia = np.asarray(cfg.quad_inertia, dtype=np.float64)
        self.arm = cfg.quad_arm_length
        self.k_f = cfg.quad_thrust_coeff
        self.k_m = cfg.quad_torque_coeff
        self.kappa = self.k_m / self.k_f
        self.d = self.arm / math.sqrt(2.0)
        self.t_min = cfg.quad_motor_thrust_min
        self.t_max = cfg.quad_motor_thrust_max
        self.tau = cfg.quad_motor_time_constant
        self.drag = cfg.quad_drag
        self.g = cfg.quad_gravity
        self.h = cfg.physics_dt
        self.substeps = cfg.substeps
        wn = np.array([cfg.quad_attitude_freq, cfg.quad_attitude_freq, cfg.quad_yaw_freq])
        zeta = cfg.quad_attitude_damping
        self.k_R = self.inertia * wn**2
        self.k_w = 2.0 * zeta * self.inertia * wn
        self.accel_limit = cfg.quad_accel_limit
        self.tilt_limit = math.radians(cfg.quad_tilt_limit)
        self.yaw = math.radians(cfg.quad_yaw)
        self.crash_tilt = math.radians(cfg.quad_crash_tilt)
        self.ground = -math.inf if cfg.quad_ground_altitude is None else cfg.quad_ground_altitude
        self.hover_thrust = self.mass * self.g / 4.0
        self.hover_speed = math.sqrt(self.hover_thrust / self.k_f)
        alpha = 1.0 if self.tau == 0 else -math.expm1(-self.h / self.tau)
        self.desaturate = cfg.quad_mixer == "desaturate"
        self.vector = QUADROTOR.pack(
            mass=self.mass,
            gravity=self.g,
            inertia_x=self.inertia[0],
            inertia_y=self.inertia[1],
            inertia_z=self.inertia[2],
            rotor_offset=self.d,
            kappa=self.kappa,
            thrust_coeff=self.k_f,
            thrust_min=self.t_min,
            thrust_max=self.t_max,
            motor_alpha=alpha,
            drag=self.drag,
            k_R_x=self.k_R[0],
            k_R_y=self.k_R[1],
            k_R_z=self.k_R[2],
            k_w_x=self.k_w[0],
            k_w_y=self.k_w[1],
            k_w_z=self.k_w[2],
            accel_limit=self.accel_limit,
            tan_tilt_limit=math.tan(self.tilt_limit),
            thrust_floor=0.1 * self.mass * self.g,
            cos_yaw=math.cos(self.yaw),
            sin_yaw=math.sin(self.yaw),
            cos_crash_tilt=math.cos(self.crash_tilt),
            ground_altitude=self.ground,
            desaturate=float(self.desaturate),
        )

    def mix(self, f: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The mixer of the kernel over arrays: rotor thrusts (..., 4) (N) and a saturation
        flag (...,) for collective thrusts f (...,) (N) and body moments M (..., 3) (N m)."""
        f = np.asarray(f, dtype=np.float64)
        M = np.asarray(M, dtype=np.float64)
        if M.shape != (*f.shape, 3):
            raise ValueError(f"M has shape {M.shape}; expected f.shape + (3,) = {(*f.shape, 3)}")
        ff = np.ascontiguousarray(f.reshape(-1))
        T = np.empty((ff.shape[0], 4))
        sat = np.empty(ff.shape[0], np.bool_)
        mix_rows(
            ff,
            np.ascontiguousarray(M.reshape(-1, 3)),
            0.25 / self.d,
            0.25 / self.kappa,
            self.t_min,
            self.t_max,
            self.desaturate,
            T,
            sat,
        )
        return T.reshape((*f.shape, 4)), sat.reshape(f.shape)

    def mixer_matrix(self) -> np.ndarray:
        """A (4, 4): [f, Mx, My, Mz] = A @ [T_0, T_1, T_2, T_3] (N, N m)."""
        ang = np.radians(ROTOR_ANGLES_DEG)
        x, y = self.arm * np.cos(ang), self.arm * np.sin(ang)
        return np.stack([np.ones(4), y, -x, self.kappa * np.asarray(ROTOR_SPIN)])
