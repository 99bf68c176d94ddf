"""The numba kernels of the Crazyflie vehicle (the equations: :mod:`.model`).

Each stage is a small scalar inlined function of tuples (position loop, attitude loop and
power distribution, rotor command, plant derivatives, Euler step), called from two kernels
over arrays (B, N, ...): :func:`setpoint_kernel` (a_des -> cmdFullState row) and
:func:`fly_kernel` (cmdFullState row -> one control period of firmware and plant per UAV).
Parameters arrive as one vector laid out by :data:`CRAZYFLIE_KERNEL`.
"""

from __future__ import annotations

import math

from pairflock_env.kernels import KernelParams, jit_inline, jit_kernel
from pairflock_env.math3d import so3_exp_scalar

__all__ = [
    "CRAZYFLIE_KERNEL",
    "axis_names",
    "derivatives",
    "fly_kernel",
    "kernel_constants",
    "rotor_speed_for_thrust",
    "setpoint_kernel",
]

_RPM2RAD = 2.0 * math.pi / 60.0


def axis_names(name: str) -> tuple[str, str, str]:
    """The three per-axis parameter names of ``name``: name_x, name_y, name_z."""
    return (f"{name}_x", f"{name}_y", f"{name}_z")


_AXES = ("inertia", "inv_inertia", "drag", "kp", "kd", "ki", "i_range")
_ATT_AXES = ("kR", "kw", "ki_m", "kd_omega", "i_range_m", "torque_pwm_max")

#: the kernel's parameters: airframe (SI; rotor speeds in RPM), firmware gains per axis,
#: rates (as whole numbers) and feeding
CRAZYFLIE_KERNEL = KernelParams(
    "Crazyflie",
    (
        *("mass", "gravity", "arm", "prop_inertia", "thrust_k0", "thrust_k1", "thrust_k2"),
        *("torque_k0", "torque_k1", "torque_k2", "spin_up_linear", "spin_up_quadratic"),
        *("spin_down_linear", "spin_down_quadratic", "ctrl_mass", "position_h", "thrust_scale"),
        *(n for a in _AXES + _ATT_AXES for n in axis_names(a)),
        *("tick", "pwm_min", "pwm_max", "thrust_min", "thrust_max", "physics_h"),
        *("cos_crash_tilt", "ground_altitude", "accel_limit", "leash", "leash_velocity", "dt"),
        *("yaw", "anchored", "ticks", "position_every", "setpoint_every", "physics_substeps"),
    ),
)
_P = CRAZYFLIE_KERNEL.index


@jit_inline
def _dot3(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@jit_inline
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@jit_inline
def _position_control(x, v, R, sp, yaw, i_pos, ctl):
    """Firmware step 1: desired axes (x_d, y_d, z_d), collective thrust (N), new integral."""
    mc, g, kp, kd, ki, imax, h_pos, thrust_scale = ctl
    ex, ey, ez = sp[0] - x[0], sp[1] - x[1], sp[2] - x[2]
    evx, evy, evz = sp[3] - v[0], sp[4] - v[1], sp[5] - v[2]
    ix = min(max(i_pos[0] + ex * h_pos, -imax[0]), imax[0])
    iy = min(max(i_pos[1] + ey * h_pos, -imax[1]), imax[1])
    iz = min(max(i_pos[2] + ez * h_pos, -imax[2]), imax[2])
    fx = mc * sp[6] + kp[0] * ex + kd[0] * evx + ki[0] * ix
    fy = mc * sp[7] + kp[1] * ey + kd[1] * evy + ki[1] * iy
    fz = mc * (sp[8] + g) + kp[2] * ez + kd[2] * evz + ki[2] * iz
    thrust = thrust_scale * (fx * R[2] + fy * R[5] + fz * R[8])
    fn = math.sqrt(fx * fx + fy * fy + fz * fz)
    zd = (fx / fn, fy / fn, fz / fn)
    y0, y1, y2 = _cross(zd, (math.cos(yaw), math.sin(yaw), 0.0))
    yn = math.sqrt(y0 * y0 + y1 * y1 + y2 * y2)
    yd = (y0 / yn, y1 / yn, y2 / yn)
    return (_cross(yd, zd), yd, zd), thrust, (ix, iy, iz)


@jit_inline
def _axis_moment(e, w, i, d, kR, kw, kim, kdw, tmax):
    """One axis of the Mellinger moment (PWM units), clamped: (moment, clamped)."""
    mk = -kR * e - kw * w + kim * i + kdw * d
    if abs(mk) > tmax:
        return math.copysign(tmax, mk), True
    return mk, False


@jit_inline
def _rotor_thrust(pwm, off, pwm_min, pwm_max, f_min, f_max):
    """One rotor's thrust (N) for its PWM (0 while the motors are off): (thrust, clipped)."""
    if off:
        return 0.0, False
    p = min(max(pwm, pwm_min), pwm_max)
    return min(max(p / pwm_max * f_max, f_min), f_max), p != pwm


@jit_inline
def _attitude_control(R, w, Rd, thrust, w_prev, i_att, att):
    """Firmware steps 2-3: rotor thrusts (N), new attitude integral, saturation flag."""
    kR, kw, kim, kdw, imax, tmax, h, pwm_min, pwm_max, f_min, f_max = att
    xd, yd, zd = Rd
    c0, c1, c2 = (R[0], R[3], R[6]), (R[1], R[4], R[7]), (R[2], R[5], R[8])
    e = (
        _dot3(zd, c1) - _dot3(yd, c2),
        _dot3(xd, c2) - _dot3(zd, c0),
        _dot3(yd, c0) - _dot3(xd, c1),
    )  # vee(E - E^T), E = R_d^T R
    i_new = (
        min(max(i_att[0] - e[0] * h, -imax[0]), imax[0]),
        min(max(i_att[1] - e[1] * h, -imax[1]), imax[1]),
        min(max(i_att[2] - e[2] * h, -imax[2]), imax[2]),
    )
    dx, dy = -(w[0] - w_prev[0]) / h, -(w[1] - w_prev[1]) / h
    mx, sx = _axis_moment(e[0], w[0], i_new[0], dx, kR[0], kw[0], kim[0], kdw[0], tmax[0])
    my, sy = _axis_moment(e[1], w[1], i_new[1], dy, kR[1], kw[1], kim[1], kdw[1], tmax[1])
    mz, sz = _axis_moment(e[2], w[2], i_new[2], 0.0, kR[2], kw[2], kim[2], kdw[2], tmax[2])
    if not thrust > 0.0:
        mx = my = mz = 0.0
    base = thrust / 4.0 / f_max * pwm_max
    hx, hy = 0.5 * mx, 0.5 * my
    p0, p1 = base - hx - hy - mz, base - hx + hy + mz
    p2, p3 = base + hx + hy - mz, base + hx - hy + mz
    off = p0 == 0.0 and p1 == 0.0 and p2 == 0.0 and p3 == 0.0
    f0, s0 = _rotor_thrust(p0, off, pwm_min, pwm_max, f_min, f_max)
    f1, s1 = _rotor_thrust(p1, off, pwm_min, pwm_max, f_min, f_max)
    f2, s2 = _rotor_thrust(p2, off, pwm_min, pwm_max, f_min, f_max)
    f3, s3 = _rotor_thrust(p3, off, pwm_min, pwm_max, f_min, f_max)
    sat = sx or sy or sz or s0 or s1 or s2 or s3
    return (f0, f1, f2, f3), i_new, sat


@jit_inline
def rotor_speed_for_thrust(f, k0, k1, k2):
    """Rotor speed (RPM) at which a rotor gives thrust f: the root of k0 + k1 O + k2 O^2 = f
    (the firmware's "perfect battery compensation")."""
    return (-k1 + math.sqrt(k1 * k1 - 4.0 * k2 * (k0 - f))) / (2.0 * k2)


@jit_inline
def _rotor_rate(oc, o, cd):
    """Omega' of one rotor (RPM/s): the spin-up or spin-down law."""
    if oc > o:
        return cd[0] * (oc - o) + cd[1] * (oc * oc - o * o)
    return cd[2] * (oc - o) + cd[3] * (oc * oc - o * o)


@jit_inline
def _curve4(k, o):
    """k0 + k1 O + k2 O^2 for the four rotor speeds O (RPM)."""
    return (
        k[0] + k[1] * o[0] + k[2] * o[0] * o[0],
        k[0] + k[1] * o[1] + k[2] * o[1] * o[1],
        k[0] + k[1] * o[2] + k[2] * o[2] * o[2],
        k[0] + k[1] * o[3] + k[2] * o[3] * o[3],
    )


@jit_inline
def derivatives(R, v, w, o, oc, phys):
    """v' (3), w' (3) and Omega' (4) of the first-principles model (R row-major 9-tuple)."""
    m, g, arm, jp, J, Jinv, kt, kq, cd, drag = phys
    od = (
        _rotor_rate(oc[0], o[0], cd),
        _rotor_rate(oc[1], o[1], cd),
        _rotor_rate(oc[2], o[2], cd),
        _rotor_rate(oc[3], o[3], cd),
    )
    f = _curve4(kt, o)  # rotor thrusts (N)
    q = _curve4(kq, o)  # rotor drag torques (N m)
    ft = f[0] + f[1] + f[2] + f[3]
    vb0 = R[0] * v[0] + R[3] * v[1] + R[6] * v[2]  # body velocity R^T v
    vb1 = R[1] * v[0] + R[4] * v[1] + R[7] * v[2]
    vb2 = R[2] * v[0] + R[5] * v[1] + R[8] * v[2]
    d0, d1, d2 = drag[0] * vb0, drag[1] * vb1, drag[2] * vb2  # body drag, then R (...)
    fd0 = R[0] * d0 + R[1] * d1 + R[2] * d2
    fd1 = R[3] * d0 + R[4] * d1 + R[5] * d2
    fd2 = R[6] * d0 + R[7] * d1 + R[8] * d2
    acc = ((R[2] * ft + fd0) / m, (R[5] * ft + fd1) / m, (R[8] * ft - m * g + fd2) / m)
    hz = _RPM2RAD * (-o[0] + o[1] - o[2] + o[3])
    hzd = _RPM2RAD * (-od[0] + od[1] - od[2] + od[3])
    tq = (
        arm * (-f[0] - f[1] + f[2] + f[3]) - jp * w[1] * hz,
        arm * (-f[0] + f[1] + f[2] - f[3]) - jp * w[0] * hz,
        (-q[0] + q[1] - q[2] + q[3]) + jp * hzd,
    )
    gyro = _cross(w, (J[0] * w[0], J[1] * w[1], J[2] * w[2]))
    wd = (
        Jinv[0] * (tq[0] - gyro[0]),
        Jinv[1] * (tq[1] - gyro[1]),
        Jinv[2] * (tq[2] - gyro[2]),
    )
    return acc, wd, od


@jit_inline
def _euler_step(x, v, R, w, o, oc, h, phys):
    """One explicit Euler step of the plant (crazyflow's integrator); R <- R exp(hat(h w))."""
    acc, wd, od = derivatives(R, v, w, o, oc, phys)
    e = so3_exp_scalar(h * w[0], h * w[1], h * w[2])
    Rn = (
        R[0] * e[0] + R[1] * e[3] + R[2] * e[6],
        R[0] * e[1] + R[1] * e[4] + R[2] * e[7],
        R[0] * e[2] + R[1] * e[5] + R[2] * e[8],
        R[3] * e[0] + R[4] * e[3] + R[5] * e[6],
        R[3] * e[1] + R[4] * e[4] + R[5] * e[7],
        R[3] * e[2] + R[4] * e[5] + R[5] * e[8],
        R[6] * e[0] + R[7] * e[3] + R[8] * e[6],
        R[6] * e[1] + R[7] * e[4] + R[8] * e[7],
        R[6] * e[2] + R[7] * e[5] + R[8] * e[8],
    )
    xn = (x[0] + h * v[0], x[1] + h * v[1], x[2] + h * v[2])
    vn = (v[0] + h * acc[0], v[1] + h * acc[1], v[2] + h * acc[2])
    wn = (w[0] + h * wd[0], w[1] + h * wd[1], w[2] + h * wd[2])
    on = (o[0] + h * od[0], o[1] + h * od[1], o[2] + h * od[2], o[3] + h * od[3])
    return xn, vn, Rn, wn, on


@jit_inline
def _xyz(prm, ix, iy, iz):
    return (prm[ix], prm[iy], prm[iz])


@jit_inline
def kernel_constants(prm):
    """The kernel's constants as tuples (plant, position loop, attitude loop, rest)."""
    kt = (prm[_P.thrust_k0], prm[_P.thrust_k1], prm[_P.thrust_k2])
    kq = (prm[_P.torque_k0], prm[_P.torque_k1], prm[_P.torque_k2])
    cd = (
        prm[_P.spin_up_linear],
        prm[_P.spin_up_quadratic],
        prm[_P.spin_down_linear],
        prm[_P.spin_down_quadratic],
    )
    J = _xyz(prm, _P.inertia_x, _P.inertia_y, _P.inertia_z)
    Jinv = _xyz(prm, _P.inv_inertia_x, _P.inv_inertia_y, _P.inv_inertia_z)
    drag = _xyz(prm, _P.drag_x, _P.drag_y, _P.drag_z)
    g = prm[_P.gravity]
    phys = (prm[_P.mass], g, prm[_P.arm], prm[_P.prop_inertia], J, Jinv, kt, kq, cd, drag)
    ctl = (
        prm[_P.ctrl_mass],
        g,
        _xyz(prm, _P.kp_x, _P.kp_y, _P.kp_z),
        _xyz(prm, _P.kd_x, _P.kd_y, _P.kd_z),
        _xyz(prm, _P.ki_x, _P.ki_y, _P.ki_z),
        _xyz(prm, _P.i_range_x, _P.i_range_y, _P.i_range_z),
        prm[_P.position_h],
        prm[_P.thrust_scale],
    )
    att = (
        _xyz(prm, _P.kR_x, _P.kR_y, _P.kR_z),
        _xyz(prm, _P.kw_x, _P.kw_y, _P.kw_z),
        _xyz(prm, _P.ki_m_x, _P.ki_m_y, _P.ki_m_z),
        _xyz(prm, _P.kd_omega_x, _P.kd_omega_y, _P.kd_omega_z),
        _xyz(prm, _P.i_range_m_x, _P.i_range_m_y, _P.i_range_m_z),
        _xyz(prm, _P.torque_pwm_max_x, _P.torque_pwm_max_y, _P.torque_pwm_max_z),
        prm[_P.tick],
        prm[_P.pwm_min],
        prm[_P.pwm_max],
        prm[_P.thrust_min],
        prm[_P.thrust_max],
    )
    rates = (
        int(prm[_P.ticks]),
        int(prm[_P.position_every]),
        int(prm[_P.setpoint_every]),
        int(prm[_P.physics_substeps]),
    )
    rest = (kt, prm[_P.physics_h], prm[_P.cos_crash_tilt], prm[_P.ground_altitude], rates)
    return phys, ctl, att, rest


@jit_inline
def _setpoint(c, t):
    """The streamed setpoint at time t into the period: the reference extrapolated by t."""
    hh = 0.5 * t * t
    return (
        c[0] + c[3] * t + c[6] * hh,
        c[1] + c[4] * t + c[7] * hh,
        c[2] + c[5] * t + c[8] * hh,
        c[3] + c[6] * t,
        c[4] + c[7] * t,
        c[5] + c[8] * t,
        c[6],
        c[7],
        c[8],
    )


@jit_inline
def _fly_period(x, v, R, w, o, ctrl, c, consts):
    """Firmware and plant over one control period for one UAV under the setpoint row c.
    Returns the new state, controller memory, and whether a PWM or torque saturated, it
    crashed, and its state stayed finite."""
    phys, ctl, att, (kt, hp, coscrash, ground, rates) = consts
    ticks, pos_every, sp_every, nsub = rates
    i_pos, i_att, w_prev = ctrl
    sp = _setpoint(c, 0.0)
    Rd = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    thrust = 0.0
    sat = crash = False
    fin = True
    for k in range(ticks):
        if k % sp_every == 0:
            sp = _setpoint(c, k * att[6])
        if k % pos_every == 0:
            Rd, thrust, i_pos = _position_control(x, v, R, sp, c[9], i_pos, ctl)
        f, i_att, s = _attitude_control(R, w, Rd, thrust, w_prev, i_att, att)
        sat |= s
        w_prev = w
        oc = (
            rotor_speed_for_thrust(f[0], kt[0], kt[1], kt[2]),
            rotor_speed_for_thrust(f[1], kt[0], kt[1], kt[2]),
            rotor_speed_for_thrust(f[2], kt[0], kt[1], kt[2]),
            rotor_speed_for_thrust(f[3], kt[0], kt[1], kt[2]),
        )
        for _s in range(nsub):
            x, v, R, w, o = _euler_step(x, v, R, w, o, oc, hp, phys)
        fin = math.isfinite(x[0] + x[1] + x[2] + v[0] + v[1] + v[2] + w[0] + w[1] + w[2] + R[8])
        if not fin or R[8] < coscrash or x[2] < ground:
            crash = True
            break
    return x, v, R, w, o, (i_pos, i_att, w_prev), sat, crash, fin


@jit_kernel
def fly_kernel(q, p, cmd, R, w, rotor, memory, flags, prm):
    """Fly every UAV one control period under its setpoint row cmd (B, N, 10). memory
    (B, N, 9): position integral, attitude integral, last body rates. flags (B, N, 2): crashed
    (sticky), PWM saturated during this period. A crashed UAV (or one given a non-finite
    setpoint) stops: velocity, rates and rotors 0, at its last finite position and attitude."""
    consts = kernel_constants(prm)
    zero3, zero4 = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0)
    for b in range(q.shape[0]):
        for n in range(q.shape[1]):
            flags[b, n, 1] = False
            if flags[b, n, 0]:
                continue
            c5 = (cmd[b, n, 0], cmd[b, n, 1], cmd[b, n, 2], cmd[b, n, 3], cmd[b, n, 4])
            c = c5 + (cmd[b, n, 5], cmd[b, n, 6], cmd[b, n, 7], cmd[b, n, 8], cmd[b, n, 9])  # noqa: RUF005
            # the state is read and written here, not in helpers taking arrays (which cost
            # reference-count updates per UAV); numba compiles tuple concatenation
            x0 = (q[b, n, 0], q[b, n, 1], q[b, n, 2])
            v0 = (p[b, n, 0], p[b, n, 1], p[b, n, 2])
            Ra = (R[b, n, 0, 0], R[b, n, 0, 1], R[b, n, 0, 2], R[b, n, 1, 0], R[b, n, 1, 1])
            R0 = Ra + (R[b, n, 1, 2], R[b, n, 2, 0], R[b, n, 2, 1], R[b, n, 2, 2])  # noqa: RUF005
            w0 = (w[b, n, 0], w[b, n, 1], w[b, n, 2])
            o0 = (rotor[b, n, 0], rotor[b, n, 1], rotor[b, n, 2], rotor[b, n, 3])
            m = memory
            ctrl0 = (
                (m[b, n, 0], m[b, n, 1], m[b, n, 2]),
                (m[b, n, 3], m[b, n, 4], m[b, n, 5]),
                (m[b, n, 6], m[b, n, 7], m[b, n, 8]),
            )
            if math.isfinite(c[0] + c[1] + c[2] + c[3] + c[4] + c[5] + c[6] + c[7] + c[8] + c[9]):
                x, v, Rn, wn, o, ctrl, sat, crash, fin = _fly_period(
                    x0, v0, R0, w0, o0, ctrl0, c, consts
                )
                if not fin:  # keep the last finite position and attitude
                    x, Rn = x0, R0
            else:
                x, v, Rn, wn, o, ctrl, sat, crash = x0, v0, R0, w0, o0, ctrl0, False, True
            if crash:
                flags[b, n, 0] = True
                v, wn, o = zero3, zero3, zero4
            flags[b, n, 1] = sat
            q[b, n, 0], q[b, n, 1], q[b, n, 2] = x
            p[b, n, 0], p[b, n, 1], p[b, n, 2] = v
            R[b, n, 0, 0], R[b, n, 0, 1], R[b, n, 0, 2] = Rn[0], Rn[1], Rn[2]
            R[b, n, 1, 0], R[b, n, 1, 1], R[b, n, 1, 2] = Rn[3], Rn[4], Rn[5]
            R[b, n, 2, 0], R[b, n, 2, 1], R[b, n, 2, 2] = Rn[6], Rn[7], Rn[8]
            w[b, n, 0], w[b, n, 1], w[b, n, 2] = wn
            rotor[b, n, 0], rotor[b, n, 1], rotor[b, n, 2], rotor[b, n, 3] = o
            ip, ia, wp = ctrl
            m[b, n, 0], m[b, n, 1], m[b, n, 2] = ip
            m[b, n, 3], m[b, n, 4], m[b, n, 5] = ia
            m[b, n, 6], m[b, n, 7], m[b, n, 8] = wp


@jit_inline
def _leash(r, x, radius):
    """r pulled onto the sphere of the given radius around x if it lies outside: (r, pulled)."""
    dx, dy, dz = r[0] - x[0], r[1] - x[1], r[2] - x[2]
    dn = math.sqrt(dx * dx + dy * dy + dz * dz)
    if dn > radius:
        s = radius / dn
        return (x[0] + dx * s, x[1] + dy * s, x[2] + dz * s), True
    return r, False


@jit_kernel
def setpoint_kernel(q, p, a_des, ref, cmd, limited, prm):
    """The cmdFullState row (B, N, 10) of each UAV for this period from its held a_des, and
    its reference ref (B, N, 6: position, velocity) advanced to the end of the period."""
    amax, leash, leash_v, dt = (
        prm[_P.accel_limit],
        prm[_P.leash],
        prm[_P.leash_velocity],
        prm[_P.dt],
    )
    anchored, yaw = prm[_P.anchored] != 0.0, prm[_P.yaw]
    for b in range(q.shape[0]):
        for n in range(q.shape[1]):
            ax, ay, az = a_des[b, n, 0], a_des[b, n, 1], a_des[b, n, 2]
            an = math.sqrt(ax * ax + ay * ay + az * az)
            cut = an > amax  # False for a non-finite command, which crashes the UAV
            if cut:
                ax, ay, az = ax * (amax / an), ay * (amax / an), az * (amax / an)
            x = (q[b, n, 0], q[b, n, 1], q[b, n, 2])
            v = (p[b, n, 0], p[b, n, 1], p[b, n, 2])
            if anchored:
                r, u = x, v
            else:
                r, c1 = _leash((ref[b, n, 0], ref[b, n, 1], ref[b, n, 2]), x, leash)
                u, c2 = _leash((ref[b, n, 3], ref[b, n, 4], ref[b, n, 5]), v, leash_v)
                cut = cut or c1 or c2
            limited[b, n] = cut
            cmd[b, n, 0], cmd[b, n, 1], cmd[b, n, 2] = r
            cmd[b, n, 3], cmd[b, n, 4], cmd[b, n, 5] = u
            cmd[b, n, 6], cmd[b, n, 7], cmd[b, n, 8], cmd[b, n, 9] = ax, ay, az, yaw
            if not math.isfinite(an):  # the UAV crashes; its reference stays finite
                continue
            c = _setpoint((r[0], r[1], r[2], u[0], u[1], u[2], ax, ay, az), dt)
            for k in range(6):
                ref[b, n, k] = c[k]
