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

from pairflock_env.dynamics.quadrotor.model import QuadrotorModel
from pairflock_env.dynamics.quadrotor.params import ROTOR_ANGLES_DEG, ROTOR_SPIN, QuadrotorParams

__all__ = ["ROTOR_ANGLES_DEG", "ROTOR_SPIN", "QuadrotorModel", "QuadrotorParams"]
