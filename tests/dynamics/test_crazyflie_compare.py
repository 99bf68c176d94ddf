"""The project's quadrotor model against drone-models' first-principles model (issue 32, item
2); needs the ``crazyflie`` extra like test_crazyflie_oracle.py, whose imports it shares.

Part 1 (same vehicle): the "paper-quadrotor" parameters (m = 0.455 kg, J, arm 0.225 m, k_f,
k_m, motor lag 0.03 s, no drag) in both models, one desired-acceleration program, and one
controller (the project's geometric controller and mixer, its own numba functions) driving

    A    the project's QuadrotorModel (semi-implicit Euler, exact motor lag, 500 Hz);
    B    drone-models' plant, crazyflow's explicit Euler at 500 Hz;
    C    drone-models' plant, explicit Euler at 5 kHz (controller at 500 Hz): the
         continuous-time model, so A - C and B - C are the two discretisation errors;
    D    C plus a propeller inertia of 5e-5 kg m^2 (drone-models' gyroscopic term, which the
         project has not; an assumed value for a 10-inch propeller);
    A5k, B5k  A and B with controller and plant at 5 kHz: the two implementations of the same
         equations converge to each other.

Part 2 (the Crazyflie cf2x_L250): the project's quadrotor at its parameters (k_f fitted at
hover, tau = 1/c1 of the spin-up law, isotropic drag 0.0147 kg/s, attitude damping raised to
1.5; A0 keeps the default 0.9) against E, the project's controller on drone-models' identified
plant (5 kHz Euler), E' that plant with the project's assumptions and E' with one identified
effect put back at a time, and F, the Crazyflie vehicle (Mellinger firmware, cmdFullState).

    python tests/dynamics/test_crazyflie_compare.py     # prints both tables (about 2 min)
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit
from test_crazyflie_oracle import Rotation, dynamics, model_parametrize

from pairflock_env import make_config
from pairflock_env.dynamics import make_vehicle
from pairflock_env.dynamics.crazyflie import CRAZYFLIE_MODELS
from pairflock_env.dynamics.crazyflie.params import hover_rpm
from pairflock_env.dynamics.quadrotor import QuadrotorModel
from pairflock_env.dynamics.quadrotor.kernels import (
    QUADROTOR,
    _attitude_moments,
    _constants,
    _desired_attitude,
    _desired_force,
    _limit_command,
    _mix,
)

RPM = 60.0 / (2.0 * math.pi)  # rad/s -> RPM
#: project rotor i (at 45 + 90 i deg) drives Crazyflie motor PERM[i]
PERM = [3, 2, 1, 0]
_AMAX = QUADROTOR.index.accel_limit
T = 5.0


@njit(cache=True)
def project_thrusts(x, v, R, w, a, prm):
    """The project's controller (the quadrotor kernel's stages 1-5) for one physics step."""
    (m, g, kd, _, J, KR, KW), rotors, limits, heading = _constants(prm)
    tmin, tmax, desaturate, fzmin, tant = limits
    ac, _, _ = _limit_command(a[0], a[1], a[2], prm[_AMAX])
    F, _ = _desired_force(ac, (v[0], v[1], v[2]), m, g, kd, fzmin, tant)
    Rd = _desired_attitude(F, heading[0], heading[1])
    Rt = (R[0, 0], R[0, 1], R[0, 2], R[1, 0], R[1, 1], R[1, 2], R[2, 0], R[2, 1], R[2, 2])
    f = F[0] * Rt[2] + F[1] * Rt[5] + F[2] * Rt[8]
    M, _ = _attitude_moments(Rt, Rd, (w[0], w[1], w[2]), J, KR, KW)
    t = _mix(f, M[0], M[1], M[2], rotors[4], rotors[5], tmin, tmax, desaturate)
    return np.array([t[0], t[1], t[2], t[3]])


def a_program(t: float, scale: float) -> np.ndarray:
    """The commanded acceleration (m/s^2): hover, accelerate, brake, hover."""
    if 0.5 <= t < 2.0:
        return scale * np.array([1.0, 0.5, 0.3])
    if 2.0 <= t < 3.5:
        return scale * np.array([-1.0, 0.0, -0.3])
    return np.zeros(3)


def particle(dt: float, scale: float) -> np.ndarray:
    """The ideal particle under the program, at the end of each control period."""
    x, v, out = np.zeros(3), np.zeros(3), []
    for k in range(round(T / dt)):
        a = a_program(k * dt, scale)
        x = x + v * dt + 0.5 * a * dt * dt
        v = v + a * dt
        out.append(x.copy())
    return np.array(out)


def run_vehicle(cfg, scale: float) -> np.ndarray:
    """The project's own vehicle model of ``cfg`` (quadrotor or crazyflie) under the program."""
    m = make_vehicle(cfg, 1)
    q, p = np.zeros((1, cfg.n_uavs, 3)), np.zeros((1, cfg.n_uavs, 3))
    m.reset_rows(np.arange(1), q, p)
    out = []
    for k in range(round(T / cfg.dt)):
        m.advance(q, p, np.broadcast_to(a_program(k * cfg.dt, scale), q.shape).copy())
        assert not m.crashed.any()
        out.append(q[0, 0].copy())
    return np.array(out)


def run_hybrid(cfg, plant, scale: float, nsub: int) -> np.ndarray:
    """The project's controller at its physics rate on drone-models' plant ``plant`` =
    (derivatives, thrust -> RPM), nsub Euler steps per physics step."""
    dm, thrust2rpm = plant
    prm = QuadrotorModel(cfg, 1).params
    h = prm.h / nsub
    x, v, w = np.zeros(3), np.zeros(3), np.zeros(3)
    quat = np.array([0.0, 0.0, 0.0, 1.0])
    rotor = np.full(4, thrust2rpm(np.full(4, prm.hover_thrust)))
    out = []
    for k in range(round(T / cfg.dt)):
        a = a_program(k * cfg.dt, scale)
        for _ in range(prm.substeps):
            R = Rotation.from_quat(quat).as_matrix()
            cmd = np.empty(4)
            cmd[PERM] = thrust2rpm(np.maximum(project_thrusts(x, v, R, w, a, prm.vector), 0.0))
            for _ in range(nsub):
                _, _, acc, wd, od = dm(x, quat, v, w, cmd, rotor)
                x, v = x + v * h, v + acc * h
                quat = (Rotation.from_quat(quat) * Rotation.from_rotvec(w * h)).as_quat()
                w, rotor = w + wd * h, rotor + od * h
        out.append(x.copy())
    return np.array(out)


def plant(cfg, model: str = "cf2x_L250", identified: tuple[str, ...] = (), jp: float = 0.0):
    """drone-models' plant with ``model``'s parameters, where every effect not named in
    ``identified`` ("mass", "rotor_law", "curves", "body_drag", "prop") is replaced by the
    project quadrotor's assumption from ``cfg``; jp: an assumed propeller inertia otherwise."""
    dm = model_parametrize(dynamics, model)
    kw = dict(dm.keywords)
    kf, km = cfg.quad_thrust_coeff / RPM**2, cfg.quad_torque_coeff / RPM**2
    if "mass" not in identified:
        J = np.diag(cfg.quad_inertia)
        kw.update(mass=cfg.quad_mass, L=cfg.quad_arm_length / math.sqrt(2.0), J=J)
        kw.update(J_inv=np.linalg.inv(J), gravity_vec=np.array([0.0, 0.0, -cfg.quad_gravity]))
    if "rotor_law" not in identified:
        kw["rotor_dyn_coef"] = np.array([1.0, 0.0, 1.0, 0.0]) / cfg.quad_motor_time_constant
    if "curves" not in identified:
        kw.update(rpm2thrust=np.array([0.0, 0.0, kf]), rpm2torque=np.array([0.0, 0.0, km]))
    if "body_drag" not in identified:
        kw["drag_matrix"] = -cfg.quad_drag * np.eye(3)
    if "prop" not in identified:
        kw["prop_inertia"] = jp * np.ones_like(kw["prop_inertia"])
    k0, k1, k2 = kw["rpm2thrust"]

    def f(*args):
        return dm.func(*args, **kw)

    def thrust2rpm(t):
        return (-k1 + np.sqrt(k1 * k1 - 4.0 * k2 * (k0 - t))) / (2.0 * k2)

    return f, thrust2rpm


def crazyflie_quad_config(damping: float):
    """The project's quadrotor at the cf2x_L250 parameters (module docstring)."""
    cf = CRAZYFLIE_MODELS["cf2x_L250"]
    w_h = hover_rpm("cf2x_L250") / RPM  # rad/s
    m0, m1, m2 = cf["rpm2torque"]
    om = w_h * RPM
    kw = dict(quad_mass=cf["mass"], quad_inertia=cf["inertia"])
    kw.update(quad_arm_length=cf["arm"] * math.sqrt(2.0), quad_accel_limit=5.0)
    kw.update(quad_thrust_coeff=cf["mass"] * 9.81 / 4.0 / w_h**2)
    kw.update(quad_torque_coeff=(m0 + m1 * om + m2 * om * om) / w_h**2)
    kw.update(quad_motor_thrust_min=cf["thrust_min"], quad_motor_thrust_max=cf["thrust_max"])
    kw.update(quad_motor_time_constant=1.0 / cf["rotor_dyn"][0], quad_drag=-cf["drag"][0])
    kw.update(quad_attitude_damping=damping, quad_ground_altitude=None)
    return make_config("paper-quadrotor", **kw)


#: part 2: the identified effects put back one at a time into the plant E'
E_VARIANTS = {
    "E  project controller, identified cf2x_L250 plant": (
        "rotor_law",
        "curves",
        "body_drag",
        "prop",
    ),
    "E' plant with the project's assumptions": (),
    "E' + identified rotor law (asymmetric, quadratic)": ("rotor_law",),
    "E' + identified thrust/torque curves (linear term)": ("curves",),
    "E' + body-frame drag (z 0.0128)": ("body_drag",),
    "E' + propeller inertia 34.5e-9": ("prop",),
}


def part1(fast: bool = False) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Part 1's runs (``fast``: A, B, A5k, B5k only) and the ideal particle."""
    cfg = make_config("paper-quadrotor", n_uavs=2, quad_ground_altitude=None)
    cfg5k = cfg.replace(substeps=100)
    runs = {
        "A project QuadrotorModel": run_vehicle(cfg, 2.0),
        "B drone-models plant, Euler 500 Hz": run_hybrid(cfg, plant(cfg), 2.0, 1),
        "A5k project QuadrotorModel, 5 kHz": run_vehicle(cfg5k, 2.0),
        "B5k drone-models plant, controller and Euler at 5 kHz": run_hybrid(
            cfg5k, plant(cfg5k), 2.0, 1
        ),
    }
    if not fast:
        runs["C drone-models plant, Euler 5 kHz"] = run_hybrid(cfg, plant(cfg), 2.0, 10)
        runs["D = C + propeller inertia 5e-5"] = run_hybrid(cfg, plant(cfg, jp=5e-5), 2.0, 10)
    return runs, particle(cfg.dt, 2.0)


def part2() -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Part 2's runs and the ideal particle."""
    cfg = crazyflie_quad_config(1.5)
    runs = {
        "A project QuadrotorModel at cf2x_L250, zeta 1.5": run_vehicle(cfg, 1.0),
        "A0 the same with the default zeta 0.9": run_vehicle(crazyflie_quad_config(0.9), 1.0),
    }
    for name, effects in E_VARIANTS.items():
        runs[name] = run_hybrid(cfg, plant(cfg, identified=("mass", *effects)), 1.0, 10)
    cf = make_config(None, dynamics="crazyflie", n_uavs=2, dt=cfg.dt)
    runs["F Crazyflie vehicle (Mellinger, integrated reference)"] = run_vehicle(cf, 1.0)
    return runs, particle(cfg.dt, 1.0)


def distance(a: np.ndarray, b: np.ndarray) -> float:
    """The largest distance (m) between two trajectories."""
    return float(np.linalg.norm(a - b, axis=1).max())


@pytest.mark.slow
def test_the_two_implementations_converge_with_the_step():
    """Same equations: the distance between the project's quadrotor and drone-models' plant
    under the same controller is first-order in the step (17.7 mm at 500 Hz, 1.8 mm at 5 kHz)."""
    runs, ideal = part1(fast=True)
    r = list(runs.values())
    d500, d5k = distance(r[0], r[1]), distance(r[2], r[3])
    assert 0.01 < d500 < 0.025 and d5k < 0.0025 and d500 / d5k > 7.0, (d500, d5k)
    assert 0.35 < distance(r[0], ideal) < 0.45  # both lag the particle the same way


def table(title: str, runs: dict[str, np.ndarray], ideal: np.ndarray) -> None:
    ref = next(iter(runs.values()))
    print(f"\n{title}\n")
    print("| run | max distance to the first run (m) | max distance to the particle (m) |")
    print("|---|---|---|")
    for name, traj in runs.items():
        print(f"| {name} | {distance(traj, ref):.2e} | {distance(traj, ideal):.3f} |")


def main() -> None:
    runs, ideal = part1()
    table("Part 1: paper-quadrotor parameters, a = 2 x the program", runs, ideal)
    r = {name.split()[0]: traj for name, traj in runs.items()}
    print("\n| pair | max distance (m) |\n|---|---|")
    for a, b in (("A", "B"), ("A", "C"), ("B", "C"), ("A5k", "B5k"), ("A5k", "C"), ("B5k", "C")):
        print(f"| {a} - {b} | {distance(r[a], r[b]):.2e} |")
    runs, ideal = part2()
    table("Part 2: Crazyflie cf2x_L250, a = 1 x the program", runs, ideal)


if __name__ == "__main__":
    main()
