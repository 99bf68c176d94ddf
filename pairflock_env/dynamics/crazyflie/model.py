"""Batched Crazyflies: identified first-principles dynamics under the firmware's Mellinger
control.

Every UAV of every swarm (arrays (B, N, ...), float64) is a Crazyflie 2.x of one of the
identified configurations of :mod:`.data` (``crazyflie_model``), simulated the way the
``crazyflow`` simulator chains the two LSY packages ``drone-controllers`` (the firmware's
Mellinger controller) and ``drone-models`` (the first-principles model), which the test suite
uses as oracles. Frames: world x, y, z with z up, gravity -g e3; body x forward, y left, z up;
R maps body to world (the packages' xyzw quaternion of the same rotation is ``quat``).

Feeding (the protocol's desired acceleration a_des, held over the control period dt, becomes a
Crazyswarm2 ``cmdFullState`` setpoint: position, velocity, acceleration, yaw, body rates 0):

    a_c = a_des * min(1, a_max / ||a_des||)
    integrated reference (default): r, u = the reference position and velocity, a particle
        that follows a_c exactly: at the period start the setpoint is (r, u, a_c, psi); then
        r <- r + u dt + a_c dt^2 / 2, u <- u + a_c dt. It starts at the UAV's state and is
        kept on a leash: at the period start r is pulled onto the sphere of radius
        ``crazyflie_leash`` around q when outside it, u onto the sphere of radius
        ``crazyflie_leash_velocity`` around p.
        (The firmware's PID then works on the error from the ideal particle, which removes
        the identified thrust-scale errors; docs/crazyflie.md, "Feeding the firmware".)
    anchored reference: the setpoint is (q, p, a_c, psi), the UAV's own state at the start.

Between setpoints the firmware holds the last one; with ``crazyflie_setpoint_rate`` above
1 / dt the ground station streams the reference at that rate (r + u t + a_c t^2 / 2, u + a_c t,
a_c).

Firmware (Mellinger, as in ``drone-controllers``), at the firmware tick h = 1/500 s:

1. Position loop, every ``500 / crazyflie_position_rate`` ticks (the firmware: every tick):
       e = r_sp - q, e_v = u_sp - p, I <- clip(I + e h_pos, +-I_max)
       F = m_c (a_sp + g e3) + k_p e + k_d e_v + k_i I          (N, world)
       z_d = F / ||F||, y_d = z_d x (cos psi, sin psi, 0) normalised, x_d = y_d x z_d
       collective thrust T = (massThrust F . R e3) / PWM_max * 4 f_max   (N)
2. Attitude loop, every tick: E = R_d^T R, e_R = vee(E - E^T) (not halved, as the firmware),
       I_m <- clip(I_m - e_R h, +-I_m,max), D = -(w - w_prev) / h with D_z = 0,
       M = clip(-k_R e_R - k_w w + k_i,m I_m + k_d,w D, +-32000)  (PWM units; 0 if T <= 0)
3. Legacy power distribution: PWM_i = T / (4 f_max) PWM_max + mixer row i of (M_x/2, M_y/2,
   M_z), clipped to [7000, 65535] (left at 0 if all four are 0); rotor thrust
   f_i = PWM_i / PWM_max f_max, clipped to [f_min, f_max]; rotor speed command Omega_c,i (RPM)
   from f_i = k0 + k1 Omega + k2 Omega^2 (perfect battery compensation).

Plant (``drone-models`` first principles; Omega in RPM), ``substeps / (500 dt)`` explicit
Euler steps per tick (crazyflow's integrator): thrust and drag torque of each rotor are
quadratic in Omega; Omega' = c1 (Oc - O) + c2 (Oc^2 - O^2) spinning up, c3, c4 spinning down;
m v' = R (0, 0, sum f_i) - m g e3 + R D R^T v; J w' = tau - w x J w, tau = (arm (mixer f)_x,
arm (mixer f)_y, (mixer tau_rotor)_z) + J_p (-w_y H, -w_x H, H') with H = (mixer Omega)_z in
rad/s (the packages' propeller term, kept as they write it); x <- x + h v, R <- R exp(hat(h w)),
v <- v + h v', w <- w + h w', Omega <- Omega + h Omega'.

A UAV that tilts past ``crazyflie_crash_tilt``, drops below the ground or goes non-finite
crashes and stops, as in the quadrotor model; its swarm reports ``vehicle_terminated``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pairflock_env.dynamics.crazyflie.kernels import fly_kernel, setpoint_kernel
from pairflock_env.dynamics.crazyflie.params import CrazyflieParams
from pairflock_env.dynamics.quadrotor.model import QuadrotorModel

__all__ = ["CMD_FIELDS", "CrazyflieModel", "quat_xyzw"]

#: The columns of a setpoint row (B, N, 10): Crazyswarm2's cmdFullState less the body rates
#: (which the firmware model does not use; a recorded stream writes them as 0).
CMD_FIELDS = ("x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az", "yaw")

#: per case of quat_xyzw (the largest of w, x, y, z first): the products that give the
#: other three components, and their places in (w, x, y, z)
_PICK = np.array([[0, 1, 2], [0, 3, 4], [1, 3, 5], [2, 4, 5]])
_SLOT = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])


def quat_xyzw(R: np.ndarray) -> np.ndarray:
    """Unit quaternions (..., 4), scalar last (x, y, z, w) with w >= 0, of rotation matrices
    R (..., 3, 3): from the largest of 4 w^2, 4 x^2, 4 y^2, 4 z^2 (Shepperd's method, full
    precision for every rotation). The order of drone-models and of the firmware's quat."""
    R = np.asarray(R, dtype=np.float64)
    if R.shape[-2:] != (3, 3):
        raise ValueError(f"R has shape {R.shape}; expected (..., 3, 3)")
    r00, r11, r22 = R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]
    d = np.stack(
        [
            1.0 + r00 + r11 + r22,
            1.0 + r00 - r11 - r22,
            1.0 - r00 + r11 - r22,
            1.0 - r00 - r11 + r22,
        ],
        axis=-1,
    )  # 4 w^2, 4 x^2, 4 y^2, 4 z^2
    s = np.stack(
        [
            R[..., 2, 1] - R[..., 1, 2],
            R[..., 0, 2] - R[..., 2, 0],
            R[..., 1, 0] - R[..., 0, 1],
            R[..., 0, 1] + R[..., 1, 0],
            R[..., 0, 2] + R[..., 2, 0],
            R[..., 1, 2] + R[..., 2, 1],
        ],
        axis=-1,
    )  # 4 w x, 4 w y, 4 w z, 4 x y, 4 x z, 4 y z
    k = np.argmax(d, axis=-1)
    big = 0.5 * np.sqrt(np.take_along_axis(d, k[..., None], axis=-1))
    wxyz = np.empty(d.shape)
    np.put_along_axis(wxyz, k[..., None], big, axis=-1)
    np.put_along_axis(wxyz, _SLOT[k], np.take_along_axis(s, _PICK[k], axis=-1) / (4.0 * big), -1)
    wxyz *= np.where(wxyz[..., :1] < 0.0, -1.0, 1.0)
    return np.concatenate([wxyz[..., 1:], wxyz[..., :1]], axis=-1)


class CrazyflieModel:
    """B x N Crazyflies behind the desired-acceleration interface (module docstring).

    Attributes (read-only views; the core owns q and p):
        R: attitude, body to world (B, N, 3, 3); ``quat`` gives it as xyzw quaternions.
        omega: body rates (B, N, 3), rad/s.  rotor_speed: (B, N, 4), RPM (motors M1..M4).
        setpoint: the cmdFullState rows of the last period (B, N, 10), ``CMD_FIELDS``.
        reference: the integrated reference (B, N, 6): position (m), velocity (m/s).
        memory: the firmware's memory (B, N, 9): position integral (m s), attitude integral
            (rad s), last body rates (rad/s).
        crashed: (B, N) bool, sticky until the swarm is reset.
        motor_saturated, accel_limited: (B, N) bool flags of the last control period.
    """

    name = "crazyflie"
    #: the keys of :meth:`info`: those of the quadrotor model
    INFO_KEYS = QuadrotorModel.INFO_KEYS

    def __init__(self, config: Any, num_swarms: int) -> None:
        if config.dim != 3:
            raise ValueError(f"dim={config.dim!r} is invalid: the crazyflie model needs dim=3")
        self.params = prm = CrazyflieParams(config)
        B, N = int(num_swarms), int(config.n_uavs)
        self.agent_uavs = np.asarray(config.pairs, dtype=np.int64).reshape(-1)
        self.R = np.zeros((B, N, 3, 3))
        self.omega = np.zeros((B, N, 3))
        self.rotor_speed = np.zeros((B, N, 4))
        self.setpoint = np.zeros((B, N, 10))
        self.reference = np.zeros((B, N, 6))
        self.memory = np.zeros((B, N, 9))
        self._flags = np.zeros((B, N, 2), np.bool_)  # crashed, saturated
        self.accel_limited = np.zeros((B, N), np.bool_)
        c, s = np.cos(prm.yaw), np.sin(prm.yaw)
        self._R0 = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    @property
    def crashed(self) -> np.ndarray:
        return self._flags[..., 0]

    @property
    def motor_saturated(self) -> np.ndarray:
        return self._flags[..., 1]

    @property
    def quat(self) -> np.ndarray:
        """Attitude as unit quaternions (B, N, 4), xyzw (drone-models, the firmware)."""
        return quat_xyzw(self.R)

    def reset_rows(self, rows: np.ndarray, q: np.ndarray, p: np.ndarray) -> None:
        """Swarms ``rows`` start level at the heading ``crazyflie_yaw``, body rates zero, rotors
        at the airframe's hover speed, firmware memory cleared, the reference at the UAVs' own
        positions q and velocities p."""
        self.R[rows] = self._R0
        self.omega[rows] = 0.0
        self.rotor_speed[rows] = self.params.hover_rpm
        self.memory[rows] = 0.0
        self.setpoint[rows] = 0.0
        self.reference[rows, :, 0:3] = q[rows]
        self.reference[rows, :, 3:6] = p[rows]
        self._flags[rows] = False
        self.accel_limited[rows] = False

    def advance(self, q: np.ndarray, p: np.ndarray, a_des: np.ndarray) -> None:
        """Fly one control period under the held desired acceleration a_des (B, N, 3)."""
        vec = self.params.vector
        a = np.ascontiguousarray(a_des, dtype=np.float64)
        setpoint_kernel(q, p, a, self.reference, self.setpoint, self.accel_limited, vec)
        self._fly(q, p)

    def fly_setpoints(self, q: np.ndarray, p: np.ndarray, cmd: np.ndarray) -> None:
        """Fly one control period under given cmdFullState rows cmd (B, N, 10) (``CMD_FIELDS``;
        yaw in rad), e.g. a recorded stream, instead of a_des; the reference is not used."""
        cmd = np.asarray(cmd, dtype=np.float64)
        if cmd.shape != self.setpoint.shape:
            raise ValueError(f"cmd has shape {cmd.shape}; expected {self.setpoint.shape}")
        self.setpoint[...] = cmd
        self.accel_limited[...] = False
        self._fly(q, p)

    def _fly(self, q: np.ndarray, p: np.ndarray) -> None:
        fly_kernel(
            q,
            p,
            self.setpoint,
            self.R,
            self.omega,
            self.rotor_speed,
            self.memory,
            self._flags,
            self.params.vector,
        )

    def tilt(self) -> np.ndarray:
        """Angle between each body z axis and the vertical, (B, N), degrees."""
        return np.degrees(np.arccos(np.clip(self.R[..., 2, 2], -1.0, 1.0)))

    def info(self) -> dict[str, np.ndarray]:
        """Diagnostics of the last control period, with the quadrotor model's keys: swarm level
        (B,) ``vehicle_terminated``, ``crashed_uavs``, ``motor_saturated_uavs`` (a PWM or a
        torque was clamped), ``accel_limited_uavs`` (a_des cut to the limit or the reference
        pulled in by the leash); per agent (B, M) ``crashed``, ``motor_saturated``,
        ``accel_limited``, ``tilt`` (deg)."""
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
            "tilt": self.tilt()[:, ia],
        }
