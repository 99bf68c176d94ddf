"""The quadrotor's numba kernels: controller, mixer, motors and rigid body over one control
period per UAV (the equations: :mod:`pairflock_env.dynamics.quadrotor`).

The kernel parameters' layout (:data:`QUADROTOR`) is defined here, beside the kernels that
read it, because numba's on-disk cache keys a compiled function on its own source file: an
index defined in another file could change without recompiling its readers.
"""

from __future__ import annotations

import math

from numba import njit

from pairflock_env.kernels import KernelParams
from pairflock_env.math3d import so3_exp_scalar

__all__ = ["QUADROTOR", "mix_rows", "quadrotor_kernel"]

#: the quadrotor kernel's parameters (pairflock_env.kernels)
QUADROTOR = KernelParams(
    "Quadrotor",
    (
        "mass",
        "gravity",
        "inertia_x",
        "inertia_y",
        "inertia_z",
        "rotor_offset",
        "kappa",
        "thrust_coeff",
        "thrust_min",
        "thrust_max",
        "motor_alpha",
        "drag",
        "k_R_x",
        "k_R_y",
        "k_R_z",
        "k_w_x",
        "k_w_y",
        "k_w_z",
        "accel_limit",
        "tan_tilt_limit",
        "thrust_floor",
        "cos_yaw",
        "sin_yaw",
        "cos_crash_tilt",
        "ground_altitude",
        "desaturate",
    ),
)
_Q = QUADROTOR.index


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
def mix_rows(f, M, inv4d, inv4k, tmin, tmax, desaturate, T, sat):
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
    J = (prm[_Q.inertia_x], prm[_Q.inertia_y], prm[_Q.inertia_z])
    KR = (prm[_Q.k_R_x], prm[_Q.k_R_y], prm[_Q.k_R_z])
    KW = (prm[_Q.k_w_x], prm[_Q.k_w_y], prm[_Q.k_w_z])
    body = (prm[_Q.mass], prm[_Q.gravity], prm[_Q.drag], 1.0 / prm[_Q.mass], J, KR, KW)
    rotors = (
        prm[_Q.rotor_offset],
        prm[_Q.kappa],
        prm[_Q.thrust_coeff],
        prm[_Q.motor_alpha],
        0.25 / prm[_Q.rotor_offset],
        0.25 / prm[_Q.kappa],
    )
    limits = (
        prm[_Q.thrust_min],
        prm[_Q.thrust_max],
        prm[_Q.desaturate] != 0.0,
        prm[_Q.thrust_floor],
        prm[_Q.tan_tilt_limit],
    )
    heading_crash = (
        prm[_Q.cos_yaw],
        prm[_Q.sin_yaw],
        prm[_Q.cos_crash_tilt],
        prm[_Q.ground_altitude],
    )
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
def quadrotor_kernel(
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
            a, cut, ok = _limit_command(
                a_des[b, n, 0], a_des[b, n, 1], a_des[b, n, 2], prm[_Q.accel_limit]
            )
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
