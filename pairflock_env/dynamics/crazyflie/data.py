"""Identified Crazyflie parameter sets of ``dynamics="crazyflie"``, as data (no package needed).

The numbers are those of two MIT-licensed packages by the Learning Systems and Robotics Lab
(M. Rath, M. Schuck): ``drone-models`` 0.1.0 (``drone_models/data/params.toml``: airframe,
rotors, drag) and ``drone-controllers`` 0.1.0 (``drone_controllers/mellinger/params.toml``:
the firmware's Mellinger gains and the controller's mass). They are copied here as data so
that the core install needs neither package (``drone-models`` pulls in casadi); the test suite
checks every value against the installed packages (the ``crazyflie`` extra,
``tests/dynamics/test_crazyflie_oracle.py``).

Units: the rotor speed Omega is in revolutions per minute (RPM) throughout, as in the
packages; forces in N, torques in N m, lengths in m, masses in kg, inertia in kg m^2.

Per configuration:

* ``mass``: the airframe's mass; ``inertia``: diagonal of the inertia matrix (body axes);
* ``arm``: the rotor's distance from each body axis, i.e. the arm length / sqrt(2) (the
  packages' ``L``; roll torque = arm * sum of signed rotor thrusts);
* ``prop_inertia``: one propeller's moment of inertia about its spin axis;
* ``rpm2thrust`` (k0, k1, k2): rotor thrust f = k0 + k1 Omega + k2 Omega^2;
* ``rpm2torque`` (m0, m1, m2): rotor drag torque tau = m0 + m1 Omega + m2 Omega^2;
* ``rotor_dyn`` (c1, c2, c3, c4): Omega' = c1 (Oc - O) + c2 (Oc^2 - O^2) while spinning up
  (command Oc > O), c3 (Oc - O) + c4 (Oc^2 - O^2) while spinning down;
* ``drag``: diagonal of the body-frame linear drag matrix (N s/m, negative: a force
  R diag(drag) R^T v opposes the velocity v);
* ``thrust_min``, ``thrust_max``: one rotor's thrust at PWM 7000 and at PWM 65535 (the
  firmware's linear PWM scale: f = PWM / 65535 * thrust_max);
* ``thrust2torque``: the controller's yaw-torque-per-thrust ratio (m);
* ``ctrl_mass``: the mass the firmware's controller assumes (deliberately not the airframe's,
  as in the package: the Crazyflie firmware's default CF_MASS, not the flown vehicle's).
"""

from __future__ import annotations

__all__ = ["CRAZYFLIE_MODELS", "FIRMWARE", "FIRMWARE_RATE", "MELLINGER_GAINS", "MIXER"]

#: The firmware's control rate (ATTITUDE_RATE, Hz): the Mellinger controller runs its position
#: and attitude parts on every 500 Hz tick (``controller_mellinger.c``, ``stabilizer_types.h``).
FIRMWARE_RATE = 500.0

#: Motor layout of every configuration (Crazyflie convention, body x forward, y left, z up):
#: M1 front-right (+x, -y), M2 back-right, M3 back-left, M4 front-left. Rows: the sign of each
#: rotor's thrust in the roll torque, in the pitch torque, and of its drag torque in the yaw
#: torque (the packages' ``mixing_matrix``).
MIXER = (
    (-1.0, -1.0, 1.0, 1.0),
    (-1.0, 1.0, 1.0, -1.0),
    (-1.0, 1.0, -1.0, 1.0),
)

#: Firmware constants shared by all configurations: PWM range, thrust-to-PWM factor
#: (``massThrust``, PWM per newton of collective thrust), torque-PWM clamp, gravity.
FIRMWARE = {
    "pwm_min": 7000.0,
    "pwm_max": 65535.0,
    "mass_thrust": 132000.0,
    "torque_pwm_max": (32000.0, 32000.0, 32000.0),
    "gravity": 9.81,
}

#: The Mellinger gains of ``drone-controllers`` (identical for the four configurations).
#: Position loop (N/m, N s/m, N/(m s)), integral ranges (m s); attitude loop in PWM units:
#: kR per unit of the (unhalved) rotation error, kw per rad/s, ki_m per rad s, kd_omega per
#: rad/s^2; attitude integral ranges (rad s).
MELLINGER_GAINS = {
    "kp": (0.4, 0.4, 1.25),
    "kd": (0.2, 0.2, 0.5),
    "ki": (0.05, 0.05, 0.05),
    "i_range": (2.0, 2.0, 0.4),
    "kR": (70000.0, 70000.0, 60000.0),
    "kw": (20000.0, 20000.0, 12000.0),
    "ki_m": (0.0, 0.0, 500.0),
    "kd_omega": (200.0, 200.0, 0.0),
    "i_range_m": (1.0, 1.0, 1500.0),
}

_CF2X_INERTIA = (16.8e-6, 16.8e-6, 29.8e-6)

CRAZYFLIE_MODELS: dict[str, dict[str, object]] = {
    # Crazyflie 2.x, L250 propellers (the stock Crazyflie 2.1)
    "cf2x_L250": {
        "mass": 0.0319,
        "inertia": _CF2X_INERTIA,
        "arm": 0.03253,
        "prop_inertia": 34.52e-9,
        "rpm2thrust": (0.0, -5.382196214637237e-7, 2.4582929831265485e-10),
        "rpm2torque": (0.0, 1.410454111996297e-9, 1.4592584373980652e-12),
        "rotor_dyn": (7.355623702172756, 0.0, 0.0, 0.00024443862952110715),
        "drag": (-0.01471782, -0.01471782, -0.01277641),
        "thrust_min": 0.012817578393224994,
        "thrust_max": 0.12,
        "thrust2torque": 0.007350862856566459,
        "ctrl_mass": 0.029,
    },
    # Crazyflie 2.x, P250 propellers
    "cf2x_P250": {
        "mass": 0.0318,
        "inertia": _CF2X_INERTIA,
        "arm": 0.03253,
        "prop_inertia": 26.97e-9,
        "rpm2thrust": (0.0, -3.6200226530383495e-7, 1.6060924304100328e-10),
        "rpm2torque": (0.0, -2.2665265829562245e-9, 1.1149485566919186e-12),
        "rotor_dyn": (5.172596691828673, 8.14774234381285e-5, 0.0, 0.0002095253491455741),
        "drag": (-0.01351483, -0.01351483, -0.01677452),
        "thrust_min": 0.012817578393224994,
        "thrust_max": 0.12,
        "thrust2torque": 0.0069928948992470565,
        "ctrl_mass": 0.029,
    },
    # Crazyflie 2.x, T350 propellers (thrust upgrade kit)
    "cf2x_T350": {
        "mass": 0.0379,
        "inertia": _CF2X_INERTIA,
        "arm": 0.03253,
        "prop_inertia": 38.93e-9,
        "rpm2thrust": (0.0, -7.167227176573658e-7, 2.9401303690194613e-10),
        "rpm2torque": (0.0, 5.815894847811497e-10, 1.331813874166509e-12),
        "rotor_dyn": (11.374753209400291, 0.0, 0.0, 0.00037867688499079635),
        "drag": (-0.01556697, -0.01556697, -0.02191672),
        "thrust_min": 0.01922636758983749,
        "thrust_max": 0.18,
        "thrust2torque": 0.005355990836477486,
        "ctrl_mass": 0.0325,
    },
    # Crazyflie 2.1 Brushless, 500 propellers
    "cf21B_500": {
        "mass": 0.04338,
        "inertia": (25e-6, 28e-6, 49e-6),
        "arm": 0.035355,
        "prop_inertia": 38.93e-9,
        "rpm2thrust": (0.0, -3.133427287299859e-7, 4.407354891648379e-10),
        "rpm2torque": (0.0, 1.65886356219615e-9, 2.4693477924534137e-12),
        "rotor_dyn": (
            13.996001897562685,
            0.00011093207920685363,
            5.933168530682111,
            0.00031951312393561264,
        ),
        "drag": (-0.02149163, -0.02149163, -0.02359736),
        "thrust_min": 0.02136263065537499,
        "thrust_max": 0.2,
        "thrust2torque": 0.00593893393599368,
        "ctrl_mass": 0.0393,
    },
}
