"""A batched 6-DOF quadrotor that tracks the swarm protocol's desired acceleration.

Every UAV of every swarm (arrays (B, N, ...)) is a rigid body with four rotors in an X
configuration, flown by a geometric SO(3) controller (Lee, Leok & McClamroch, "Geometric
tracking control of a quadrotor UAV on SE(3)", CDC 2010) whose input is the desired
acceleration a_des (m/s^2, world frame, z up) that the flocking protocol and the pair term
produce once per control period ``dt``. Controller, mixer, motors and rigid body run together
at the physics rate ``dt / substeps`` (500 Hz in the paper-quadrotor preset) with a_des held.

State per UAV: position q (m) and velocity p (m/s) (the core's arrays), attitude R in SO(3)
(body -> world), body rates w (rad/s), rotor speeds W_i (rad/s, i = 0..3).

Parameters (``PairFlockConfig.quad_*``, see ``docs/quadrotor.md`` for values and sources):
mass m (kg), inertia J = diag(Jx, Jy, Jz) (kg m^2), arm length L (m), thrust and drag-torque
coefficients k_f (N s^2/rad^2), k_m (N m s^2/rad^2), per-rotor thrust limits [T_min, T_max]
(N), motor time constant tau (s), linear drag k_d (kg/s), gravity g (m/s^2), attitude-loop
natural frequencies wn (roll/pitch) and wn_z (yaw) (rad/s) and damping zeta, acceleration
limit a_max (m/s^2), tilt limit theta_max, fixed heading psi, crash tilt, ground altitude.

Per physics step of length h, for each UAV:

1. Command (once per control period, a_des is held):
       a_c = a_des * min(1, a_max / ||a_des||)                      acceleration limit
2. Desired force (world frame, N), drag compensated:
       F = m (a_c + g e3) + k_d p
   tilt cone: F_z >= m g / 10 and ||F_xy|| <= F_z tan(theta_max) (the horizontal part is
   scaled down; vertical takes priority, so altitude holds while a lateral command is cut).
3. Desired attitude with a fixed heading psi (Lee et al. build b1d from b1c; here the
   heading enters through the body y axis so that the ZYX yaw of R_d is exactly psi, the
   usual Euler convention of the attitude plots):
       b3d = F / ||F||,  b2c = (-sin psi, cos psi, 0),
       b1d = b2c x b3d / ||b2c x b3d||,  b2d = b3d x b1d,  R_d = [b1d b2d b3d]
   (well defined while the tilt stays below 90 degrees, which the tilt cone ensures).
4. Collective thrust and moments (Lee et al., eqs. 15-16, desired body rates 0):
       f = F . R e3
       e_R = 1/2 vee(R_d^T R - R^T R_d),   e_w = w
       M = -K_R e_R - K_w e_w + w x J w,   K_R = J wn^2,  K_w = 2 zeta J wn   (per axis)
   so that each axis behaves as theta'' + 2 zeta wn theta' + wn^2 theta = 0 near hover.
5. Mixer (X frame, rotor i at angle 45 + 90 i degrees, d = L / sqrt(2), spin sigma = +,-,+,-):
       [f, Mx, My, Mz] = A [T_0..T_3],  A = [[1, 1, 1, 1], d [1, 1, -1, -1],
                                            d [-1, 1, 1, -1], kappa [1, -1, 1, -1]]
   with kappa = k_m / k_f (m). The rows are orthogonal, so T = A^T diag(1/4, 1/4d^2, 1/4d^2,
   1/4kappa^2) [f, M] = f/4 + delta(M). When a rotor would leave [T_min, T_max] the mixer
   desaturates, giving up thrust before attitude (reported as ``motor_saturated``): if the
   spread max(delta) - min(delta) exceeds T_max - T_min, the moments are scaled down together
   (their direction is kept); then the collective f/4 is shifted by the least amount that
   brings every rotor into range. (Plain per-rotor clipping distorts the moments just when
   the attitude loop needs them, which lengthens the sliding-mode limit cycle of the pair;
   ``quad_mixer="clip"`` selects it for comparison.)
6. Motors: first-order lag on rotor speed towards W_c = sqrt(T_i / k_f), solved exactly
   over the step: W <- W + (W_c - W)(1 - exp(-h / tau)); the rotors then produce
   T_i = k_f W_i^2 and, through A, the moments (Mx, My, Mz) acting on the body.
7. Rigid body (semi-implicit Euler, like the particle model; rotation by the exponential map):
       p <- p + h (R e3 sum(T_i) / m - g e3 - k_d p / m),   q <- q + h p
       w <- w + h J^-1 (M - w x J w),                       R <- R exp(hat(h w))
8. Crash check: a UAV whose tilt exceeds the crash tilt (flipped), whose altitude is below
   the ground (when one is set), or whose command or state is non-finite is *crashed*: it
   stops where it is (velocity, rates and rotors set to zero) and is no longer integrated.
   Its swarm reports ``vehicle_terminated``, which ends that swarm's episode in every view.

The whole loop runs in one numba kernel, single-threaded, one UAV at a time over all its
substeps (UAVs are independent within a control period, since a_des is held). Each numbered
stage above is a small scalar ``@njit(inline="always")`` function of tuples (command limit,
desired force, desired attitude, attitude moments, mixer, motor lag, rotor wrench,
translation, rotation), which numba inlines into the kernel, so the split costs nothing and
the floating-point operations are the same, in the same order.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pairflock_env.config import PairFlockConfig
from pairflock_env.math3d import so3_exp_scalar

__all__ = ["ROTOR_ANGLES_DEG", "ROTOR_SPIN", "QuadrotorModel", "QuadrotorParams"]

#: rotor positions: angle from the body x axis (deg), X configuration
ROTOR_ANGLES_DEG = (45.0, 135.0, 225.0, 315.0)
#: sign of each rotor's reaction torque about body z (Mz = kappa * sum(spin_i T_i))
ROTOR_SPIN = (1.0, -1.0, 1.0, -1.0)

# indices into the kernel's parameter vector
_M, _G, _JX, _JY, _JZ, _D, _KAPPA, _KF, _TMIN, _TMAX = range(10)
_ALPHA, _KD, _KRX, _KRY, _KRZ, _KWX, _KWY, _KWZ, _AMAX, _TANTILT = range(10, 20)
_FZMIN, _CPSI, _SPSI, _COSCRASH, _GROUND, _DESAT, _NPARAM = range(20, 27)


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
        v = np.empty(_NPARAM)
        v[_M], v[_G] = self.mass, self.g
        v[_JX], v[_JY], v[_JZ] = self.inertia
        v[_D], v[_KAPPA], v[_KF] = self.d, self.kappa, self.k_f
        v[_TMIN], v[_TMAX], v[_ALPHA], v[_KD] = self.t_min, self.t_max, alpha, self.drag
        v[_KRX], v[_KRY], v[_KRZ] = self.k_R
        v[_KWX], v[_KWY], v[_KWZ] = self.k_w
        v[_AMAX], v[_TANTILT] = self.accel_limit, math.tan(self.tilt_limit)
        v[_FZMIN] = 0.1 * self.mass * self.g
        v[_CPSI], v[_SPSI] = math.cos(self.yaw), math.sin(self.yaw)
        v[_COSCRASH], v[_GROUND] = math.cos(self.crash_tilt), self.ground
        self.desaturate = cfg.quad_mixer == "desaturate"
        v[_DESAT] = float(self.desaturate)
        self.vector = v

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
        _mix_rows(
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


@njit(cache=True, inline="always")
def _mix(f, mx, my, mz, inv4d, inv4k, tmin, tmax, desaturate):
    """Rotor thrusts (t0, t1, t2, t3, saturated) for collective thrust f and moments M."""
    d0 = inv4d * (mx - my) + inv4k * mz
    d1 = inv4d * (mx + my) - inv4k * mz
    d2 = inv4d * (my - mx) + inv4k * mz
    d3 = -inv4d * (mx + my) - inv4k * mz
    base = 0.25 * f
    hi = max(max(d0, d1), max(d2, d3))
    lo = min(min(d0, d1), min(d2, d3))
    if base + lo >= tmin and base + hi <= tmax:
        return base + d0, base + d1, base + d2, base + d3, False
    if not desaturate:
        return (
            min(max(base + d0, tmin), tmax),
            min(max(base + d1, tmin), tmax),
            min(max(base + d2, tmin), tmax),
            min(max(base + d3, tmin), tmax),
            True,
        )
    span = hi - lo
    if span > tmax - tmin:  # not even the moments fit: scale them, keep their direction
        sc = (tmax - tmin) / span
        d0 *= sc
        d1 *= sc
        d2 *= sc
        d3 *= sc
        hi *= sc
        lo *= sc
    base = min(max(base, tmin - lo), tmax - hi)  # least change of the collective thrust
    return (
        min(max(base + d0, tmin), tmax),
        min(max(base + d1, tmin), tmax),
        min(max(base + d2, tmin), tmax),
        min(max(base + d3, tmin), tmax),
        True,
    )


@njit(cache=True)
def _mix_rows(f, M, inv4d, inv4k, tmin, tmax, desaturate, T, sat):
    for i in range(f.shape[0]):
        t0, t1, t2, t3, s = _mix(
            f[i], M[i, 0], M[i, 1], M[i, 2], inv4d, inv4k, tmin, tmax, desaturate
        )
        T[i, 0], T[i, 1], T[i, 2], T[i, 3] = t0, t1, t2, t3
        sat[i] = s


@njit(cache=True, inline="always")
def _limit_command(ax, ay, az, amax):
    """1. The held command a_des cut to ||a|| <= a_max: (a, cut, finite)."""
    an = math.sqrt(ax * ax + ay * ay + az * az)
    if not math.isfinite(an):
        return (ax, ay, az), False, False
    if an > amax:
        sc = amax / an
        return (ax * sc, ay * sc, az * sc), True, True
    return (ax, ay, az), False, True


@njit(cache=True, inline="always")
def _desired_force(a, v, m, g, kd, fzmin, tant):
    """2. Desired force F (N) with drag compensation, cut to the tilt cone: (F, cut)."""
    fx = m * a[0] + kd * v[0]
    fy = m * a[1] + kd * v[1]
    fz = m * (a[2] + g) + kd * v[2]
    cut = False
    if fz < fzmin:
        fz = fzmin
        cut = True
    fh = math.sqrt(fx * fx + fy * fy)
    if fh > fz * tant:
        sc = fz * tant / fh
        fx *= sc
        fy *= sc
        cut = True
    return (fx, fy, fz), cut


@njit(cache=True, inline="always")
def _desired_attitude(F, cpsi, spsi):
    """3. The columns b1, b2, b3 of R_d for the force F and the fixed heading psi."""
    fx, fy, fz = F
    fn = math.sqrt(fx * fx + fy * fy + fz * fz)
    b30, b31, b32 = fx / fn, fy / fn, fz / fn
    c0 = cpsi * b32  # (-sin psi, cos psi, 0) x b3
    c1 = spsi * b32
    c2 = -spsi * b31 - cpsi * b30
    cn = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    b10, b11, b12 = c0 / cn, c1 / cn, c2 / cn
    b20 = b31 * b12 - b32 * b11  # b3 x b1
    b21 = b32 * b10 - b30 * b12
    b22 = b30 * b11 - b31 * b10
    return (b10, b11, b12), (b20, b21, b22), (b30, b31, b32)


@njit(cache=True, inline="always")
def _attitude_moments(R, Rd, w, J, KR, KW):
    """4. Body moments M = -K_R e_R - K_w w + w x J w (N m) and the gyroscopic term w x J w,
    for the attitude R (row-major 9-tuple), the desired columns Rd and the body rates w."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = R
    (b10, b11, b12), (b20, b21, b22), (b30, b31, b32) = Rd
    wx, wy, wz = w
    # E = R_d^T R, e_R = vee(E - E^T) / 2
    e01 = b10 * r01 + b11 * r11 + b12 * r21
    e02 = b10 * r02 + b11 * r12 + b12 * r22
    e10 = b20 * r00 + b21 * r10 + b22 * r20
    e12 = b20 * r02 + b21 * r12 + b22 * r22
    e20 = b30 * r00 + b31 * r10 + b32 * r20
    e21 = b30 * r01 + b31 * r11 + b32 * r21
    erx = 0.5 * (e21 - e12)
    ery = 0.5 * (e02 - e20)
    erz = 0.5 * (e10 - e01)
    hx, hy, hz = J[0] * wx, J[1] * wy, J[2] * wz  # angular momentum J w
    gx = wy * hz - wz * hy  # w x J w
    gy = wz * hx - wx * hz
    gz = wx * hy - wy * hx
    mx = -KR[0] * erx - KW[0] * wx + gx
    my = -KR[1] * ery - KW[1] * wy + gy
    mz = -KR[2] * erz - KW[2] * wz + gz
    return (mx, my, mz), (gx, gy, gz)


@njit(cache=True, inline="always")
def _motor_lag(o, T, alpha, kf):
    """6. Rotor speeds after one physics step of the exact first-order lag towards
    sqrt(T_i / k_f)."""
    o0, o1, o2, o3 = o
    o0 += alpha * (math.sqrt(T[0] / kf) - o0)
    o1 += alpha * (math.sqrt(T[1] / kf) - o1)
    o2 += alpha * (math.sqrt(T[2] / kf) - o2)
    o3 += alpha * (math.sqrt(T[3] / kf) - o3)
    return o0, o1, o2, o3


@njit(cache=True, inline="always")
def _rotor_wrench(o, kf, d, kappa):
    """The rotors' total thrust (N) and body moments (N m) at rotor speeds o (mixer A)."""
    o0, o1, o2, o3 = o
    t0, t1, t2, t3 = kf * o0 * o0, kf * o1 * o1, kf * o2 * o2, kf * o3 * o3
    ft = (t0 + t1) + (t2 + t3)
    tx = d * ((t0 + t1) - (t2 + t3))
    ty = d * ((t1 + t2) - (t0 + t3))
    tz = kappa * ((t0 + t2) - (t1 + t3))
    return ft, (tx, ty, tz)


@njit(cache=True, inline="always")
def _translate(x, v, R, ft, h, g, kd, inv_m):
    """7a. Semi-implicit Euler step of position x and velocity v under thrust ft along R e3,
    gravity and linear drag."""
    acc = ft * inv_m
    vx = v[0] + h * (R[2] * acc - kd * inv_m * v[0])
    vy = v[1] + h * (R[5] * acc - kd * inv_m * v[1])
    vz = v[2] + h * (R[8] * acc - g - kd * inv_m * v[2])
    return (x[0] + h * vx, x[1] + h * vy, x[2] + h * vz), (vx, vy, vz)


@njit(cache=True, inline="always")
def _rotate(R, w, tau, gyro, h, J):
    """7b. Body rates w <- w + h J^-1 (tau - w x J w), then R <- R exp(hat(h w))."""
    wx = w[0] + h * (tau[0] - gyro[0]) / J[0]
    wy = w[1] + h * (tau[1] - gyro[1]) / J[1]
    wz = w[2] + h * (tau[2] - gyro[2]) / J[2]
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = R
    e = so3_exp_scalar(h * wx, h * wy, h * wz)
    n00 = r00 * e[0] + r01 * e[3] + r02 * e[6]
    n01 = r00 * e[1] + r01 * e[4] + r02 * e[7]
    n02 = r00 * e[2] + r01 * e[5] + r02 * e[8]
    n10 = r10 * e[0] + r11 * e[3] + r12 * e[6]
    n11 = r10 * e[1] + r11 * e[4] + r12 * e[7]
    n12 = r10 * e[2] + r11 * e[5] + r12 * e[8]
    n20 = r20 * e[0] + r21 * e[3] + r22 * e[6]
    n21 = r20 * e[1] + r21 * e[4] + r22 * e[7]
    n22 = r20 * e[2] + r21 * e[5] + r22 * e[8]
    return (n00, n01, n02, n10, n11, n12, n20, n21, n22), (wx, wy, wz)


@njit(cache=True, inline="always")
def _constants(prm):
    """The kernel's constants, unpacked once per call from the parameter vector."""
    J = (prm[_JX], prm[_JY], prm[_JZ])
    KR = (prm[_KRX], prm[_KRY], prm[_KRZ])
    KW = (prm[_KWX], prm[_KWY], prm[_KWZ])
    body = (prm[_M], prm[_G], prm[_KD], 1.0 / prm[_M], J, KR, KW)
    rotors = (prm[_D], prm[_KAPPA], prm[_KF], prm[_ALPHA], 0.25 / prm[_D], 0.25 / prm[_KAPPA])
    limits = (prm[_TMIN], prm[_TMAX], prm[_DESAT] != 0.0, prm[_FZMIN], prm[_TANTILT])
    heading_crash = (prm[_CPSI], prm[_SPSI], prm[_COSCRASH], prm[_GROUND])
    return body, rotors, limits, heading_crash


@njit(cache=True, inline="always")
def _fly_period(x, v, R, w, o, a, substeps, h, consts):
    """Steps 2-8 of the module docstring over one control period for one UAV under the
    (limited) command a. Returns the new (x, v, R, w, o), the last R_d, whether the command
    was cut, a rotor saturated, the UAV crashed, and whether its state stayed finite."""
    (m, g, kd, inv_m, J, KR, KW), rotors, limits, heading_crash = consts
    d, kappa, kf, alpha, inv4d, inv4k = rotors
    tmin, tmax, desaturate, fzmin, tant = limits
    cpsi, spsi, coscrash, ground = heading_crash
    zero = (0.0, 0.0, 0.0)
    Rd = (zero, zero, zero)
    cut = sat = crash = False
    fin = True
    for _s in range(substeps):
        F, c = _desired_force(a, v, m, g, kd, fzmin, tant)
        Rd = _desired_attitude(F, cpsi, spsi)
        f = F[0] * R[2] + F[1] * R[5] + F[2] * R[8]  # collective thrust F . R e3
        M, gyro = _attitude_moments(R, Rd, w, J, KR, KW)
        t0, t1, t2, t3, s = _mix(f, M[0], M[1], M[2], inv4d, inv4k, tmin, tmax, desaturate)
        cut |= c
        sat |= s
        o = _motor_lag(o, (t0, t1, t2, t3), alpha, kf)
        ft, tau = _rotor_wrench(o, kf, d, kappa)
        x, v = _translate(x, v, R, ft, h, g, kd, inv_m)
        R, w = _rotate(R, w, tau, gyro, h, J)
        # 8. crash check
        fin = math.isfinite(x[0] + x[1] + x[2] + v[0] + v[1] + v[2] + w[0] + w[1] + w[2] + R[8])
        if not fin or R[8] < coscrash or x[2] < ground:
            crash = True
            break
    return x, v, R, w, o, Rd, cut, sat, crash, fin


@njit(cache=True, inline="always")
def _stop(b, n, p, w, rotor, crashed, crashed_now):
    """A crashed UAV stops where it is: velocity, rates and rotors zero, flagged."""
    crashed[b, n] = True
    crashed_now[b, n] = True
    for k in range(3):
        p[b, n, k] = 0.0
        w[b, n, k] = 0.0
    for k in range(4):
        rotor[b, n, k] = 0.0


@njit(cache=True, nogil=True)
def _quadrotor_kernel(
    q, p, a_des, R, w, rotor, crashed, R_des, saturated, limited, crashed_now, substeps, h, prm
):
    B, N, _ = q.shape
    consts = _constants(prm)
    for b in range(B):
        for n in range(N):
            saturated[b, n] = False
            limited[b, n] = False
            crashed_now[b, n] = False
            if crashed[b, n]:
                continue
            a, cut, ok = _limit_command(a_des[b, n, 0], a_des[b, n, 1], a_des[b, n, 2], prm[_AMAX])
            if not ok:  # a non-finite command crashes the UAV
                _stop(b, n, p, w, rotor, crashed, crashed_now)
                continue
            # the state is read and written here, not in helpers: arrays passed to inlined
            # functions cost a reference count update per UAV
            x0 = (q[b, n, 0], q[b, n, 1], q[b, n, 2])
            v0 = (p[b, n, 0], p[b, n, 1], p[b, n, 2])
            Rr = (R[b, n, 0, 0], R[b, n, 0, 1], R[b, n, 0, 2], R[b, n, 1, 0], R[b, n, 1, 1])
            # numba compiles tuple concatenation, not unpacking in a tuple display
            R0 = Rr + (R[b, n, 1, 2], R[b, n, 2, 0], R[b, n, 2, 1], R[b, n, 2, 2])  # noqa: RUF005
            w0 = (w[b, n, 0], w[b, n, 1], w[b, n, 2])
            o0 = (rotor[b, n, 0], rotor[b, n, 1], rotor[b, n, 2], rotor[b, n, 3])
            x, v, Rn, wn, o, Rd, cut2, sat, crash, fin = _fly_period(
                x0, v0, R0, w0, o0, a, substeps, h, consts
            )
            limited[b, n] = cut or cut2
            saturated[b, n] = sat
            if crash:
                crashed[b, n] = True
                crashed_now[b, n] = True
                v, wn, o = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0)
                if not fin:  # keep the last finite state (q is written below)
                    x = (q[b, n, 0], q[b, n, 1], q[b, n, 2])
            q[b, n, 0], q[b, n, 1], q[b, n, 2] = x
            p[b, n, 0], p[b, n, 1], p[b, n, 2] = v
            r00, r01, r02, r10, r11, r12, r20, r21, r22 = Rn
            # an attitude is only written while finite
            if math.isfinite(r00 + r01 + r02 + r10 + r11 + r12 + r20 + r21 + r22):
                R[b, n, 0, 0], R[b, n, 0, 1], R[b, n, 0, 2] = r00, r01, r02
                R[b, n, 1, 0], R[b, n, 1, 1], R[b, n, 1, 2] = r10, r11, r12
                R[b, n, 2, 0], R[b, n, 2, 1], R[b, n, 2, 2] = r20, r21, r22
            w[b, n, 0], w[b, n, 1], w[b, n, 2] = wn
            rotor[b, n, 0], rotor[b, n, 1], rotor[b, n, 2], rotor[b, n, 3] = o
            (b10, b11, b12), (b20, b21, b22), (b30, b31, b32) = Rd  # R_d = [b1 b2 b3]
            R_des[b, n, 0, 0], R_des[b, n, 0, 1], R_des[b, n, 0, 2] = b10, b20, b30
            R_des[b, n, 1, 0], R_des[b, n, 1, 1], R_des[b, n, 1, 2] = b11, b21, b31
            R_des[b, n, 2, 0], R_des[b, n, 2, 1], R_des[b, n, 2, 2] = b12, b22, b32


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
        _quadrotor_kernel(
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
