"""The Crazyflie port against drone-models and drone-controllers as oracles (the ``crazyflie``
extra: ``pip install 'pairflock-env[crazyflie]'``, Python >= 3.11); skipped without them.

The oracle chains the packages as the crazyflow simulator does: drone-controllers' Mellinger
controller (state2attitude -> attitude2force_torque -> force_torque2rotor_vel) at the firmware
tick, drone-models' first-principles derivatives integrated by crazyflow's explicit Euler step
(the quaternion composed with the rotation vector h w). Both packages refuse to import once
scipy is loaded unless SCIPY_ARRAY_API=1, and numba (so the project) loads scipy first. The
flag acts when scipy is imported (it switches scipy to its array-API code paths, which give
the same numbers for numpy input), so setting it now changes nothing but that check: it is set
around the import and restored (the errors below are the same to the last digit when the
suite runs with SCIPY_ARRAY_API=1 from the start).
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

_EXTRA = "needs the crazyflie extra: pip install 'pairflock-env[crazyflie]' (Python >= 3.11)"
_FLAG = os.environ.get("SCIPY_ARRAY_API")
os.environ["SCIPY_ARRAY_API"] = "1"  # for the packages' import-time check only
try:
    drone_models = pytest.importorskip("drone_models", reason=_EXTRA)
    drone_controllers = pytest.importorskip("drone_controllers", reason=_EXTRA)
finally:  # later processes (the suite starts some) keep the environment they had
    if _FLAG is None:
        del os.environ["SCIPY_ARRAY_API"]
    else:
        os.environ["SCIPY_ARRAY_API"] = _FLAG

from drone_controllers import parametrize as controller_parametrize  # noqa: E402
from drone_controllers.mellinger import (  # noqa: E402
    attitude2force_torque,
    force_torque2rotor_vel,
    state2attitude,
)
from drone_controllers.mellinger.params import AttitudeParams, StateParams  # noqa: E402
from drone_models import parametrize as model_parametrize  # noqa: E402
from drone_models.core import load_params  # noqa: E402
from drone_models.first_principles import dynamics  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

from pairflock_env import make_config  # noqa: E402
from pairflock_env.dynamics import make_vehicle  # noqa: E402
from pairflock_env.dynamics.crazyflie.data import (  # noqa: E402
    CRAZYFLIE_MODELS,
    FIRMWARE,
    FIRMWARE_RATE,
    MELLINGER_GAINS,
    MIXER,
)
from pairflock_env.dynamics.crazyflie.kernels import derivatives, kernel_constants  # noqa: E402

MODELS = tuple(CRAZYFLIE_MODELS)
_STATE = ("pos", "quat", "vel", "ang_vel", "rotor", "i_pos", "i_att", "prev_ang_vel")


class PackageCrazyflie:
    """Firmware and plant of the packages, one firmware tick at a time, on a state dict with
    the keys ``_STATE`` (arrays (..., k); quat xyzw, rotor speeds in RPM)."""

    def __init__(self, model: str, position_every: int = 1, physics_substeps: int = 1):
        self.dyn = model_parametrize(dynamics, model)
        self.s2a = controller_parametrize(state2attitude, model)
        self.a2ft = controller_parametrize(attitude2force_torque, model)
        self.ft2r = controller_parametrize(force_torque2rotor_vel, model)
        self.position_every = position_every
        self.nsub = physics_substeps
        self.rpyt = None

    def tick(self, st: dict, cmd13: np.ndarray, k: int) -> None:
        """Firmware tick k (counted from the start) under the setpoint cmd13 (..., 13)."""
        kin = (st["pos"], st["quat"], st["vel"], st["ang_vel"])
        if k % self.position_every == 0:
            rate = FIRMWARE_RATE / self.position_every
            self.rpyt, st["i_pos"] = self.s2a(
                *kin, cmd13, ctrl_errors=(st["i_pos"],), ctrl_freq=rate
            )
        force, torque, st["i_att"] = self.a2ft(
            *kin,
            self.rpyt,
            prev_ang_vel=st["prev_ang_vel"],
            ctrl_errors=(st["i_att"],),
            ctrl_freq=FIRMWARE_RATE,
        )
        st["prev_ang_vel"] = st["ang_vel"].copy()
        rpm_cmd = self.ft2r(force, torque)
        h = 1.0 / (FIRMWARE_RATE * self.nsub)
        for _ in range(self.nsub):
            _, _, acc, ang_acc, rotor_acc = self.dyn(
                st["pos"], st["quat"], st["vel"], st["ang_vel"], rpm_cmd, st["rotor"]
            )
            st["pos"] = st["pos"] + st["vel"] * h
            turn = Rotation.from_rotvec(st["ang_vel"] * h)
            st["quat"] = (Rotation.from_quat(st["quat"]) * turn).as_quat()
            st["vel"] = st["vel"] + acc * h
            st["ang_vel"] = st["ang_vel"] + ang_acc * h
            st["rotor"] = st["rotor"] + rotor_acc * h


def setpoint_at(cmd10: np.ndarray, t: float) -> np.ndarray:
    """cmdFullState (..., 13) streamed t seconds into a period whose row is cmd10: the
    reference r + u t + a t^2 / 2, u + a t, a, yaw, body rates 0."""
    r, u, a = cmd10[..., 0:3], cmd10[..., 3:6], cmd10[..., 6:9]
    out = np.zeros((*cmd10.shape[:-1], 13))
    out[..., 0:3] = r + u * t + a * (0.5 * t * t)
    out[..., 3:6] = u + a * t
    out[..., 6:9] = a
    out[..., 9] = cmd10[..., 9]
    return out


def _model(B: int, N: int, **kw):
    cfg = make_config(None, **{"dynamics": "crazyflie", "n_uavs": N, "dt": 0.02, **kw})
    return make_vehicle(cfg, B)


def _oracle_state(m, q: np.ndarray, p: np.ndarray) -> dict:
    """The model's state (B, N, ...) as the oracle's (quaternion xyzw from R)."""
    mem = m.memory
    values = (q, m.quat, p, m.omega, m.rotor_speed, mem[..., 0:3], mem[..., 3:6], mem[..., 6:9])
    return {k: np.array(v, copy=True) for k, v in zip(_STATE, values, strict=True)}


def _errors(m, q, p, st) -> dict[str, float]:
    """Largest absolute differences between the model's state and the oracle's."""
    Rq = Rotation.from_quat(st["quat"].reshape(-1, 4)).as_matrix().reshape(m.R.shape)
    mem = np.concatenate([st["i_pos"], st["i_att"], st["prev_ang_vel"]], axis=-1)
    return {
        "position": float(np.abs(q - st["pos"]).max()),
        "velocity": float(np.abs(p - st["vel"]).max()),
        "attitude": float(np.abs(m.R - Rq).max()),
        "rates": float(np.abs(m.omega - st["ang_vel"]).max()),
        "rotors": float(np.abs(m.rotor_speed - st["rotor"]).max()),
        "memory": float(np.abs(m.memory - mem).max()),
    }


@pytest.mark.parametrize("model", MODELS)
def test_parameters_equal_the_packages(model):
    phys = load_params("first_principles", model)
    own = CRAZYFLIE_MODELS[model]
    assert phys["mass"] == own["mass"] and phys["L"] == own["arm"]
    assert phys["prop_inertia"] == own["prop_inertia"]
    np.testing.assert_array_equal(phys["J"], np.diag(own["inertia"]))
    for key, pkg in (("rpm2thrust",) * 2, ("rpm2torque",) * 2, ("rotor_dyn", "rotor_dyn_coef")):
        np.testing.assert_array_equal(phys[pkg], own[key])
    np.testing.assert_array_equal(phys["drag_matrix"], np.diag(own["drag"]))
    np.testing.assert_array_equal(phys["mixing_matrix"], MIXER)
    np.testing.assert_array_equal(phys["gravity_vec"], (0.0, 0.0, -FIRMWARE["gravity"]))
    for key in ("thrust_min", "thrust_max", "pwm_min", "pwm_max"):
        assert phys[key] == own.get(key, FIRMWARE.get(key))
    s, a = StateParams.load(model), AttitudeParams.load(model)
    assert s.mass == own["ctrl_mass"] and s.mass_thrust == FIRMWARE["mass_thrust"]
    assert own["arm"] == a.L and a.thrust2torque == own["thrust2torque"]
    assert a.thrust_max == own["thrust_max"] == s.thrust_max
    np.testing.assert_array_equal(a.torque_pwm_max, FIRMWARE["torque_pwm_max"])
    np.testing.assert_array_equal(a.mixing_matrix, MIXER)
    ours = dict(MELLINGER_GAINS)
    theirs = dict(kp=s.kp, kd=s.kd, ki=s.ki, i_range=s.int_err_max, kR=a.kR, kw=a.kw)
    theirs.update(ki_m=a.ki_m, kd_omega=a.kd_omega, i_range_m=a.int_err_max)
    for key, val in theirs.items():
        np.testing.assert_array_equal(val, ours[key], err_msg=key)


@pytest.mark.parametrize("model", MODELS)
def test_derivatives_equal_first_principles(model):
    rng = np.random.default_rng(1)
    dyn = model_parametrize(dynamics, model)
    m = _model(1, 2, crazyflie_model=model)
    phys = kernel_constants(m.params.vector)[0]
    hover = m.params.hover_rpm
    for _ in range(50):
        quat = Rotation.random(random_state=rng).as_quat()
        R = tuple(Rotation.from_quat(quat).as_matrix().reshape(-1))
        v, w = rng.normal(0, 2, 3), rng.normal(0, 3, 3)
        o, oc = hover * rng.uniform(0.5, 1.5, 4), hover * rng.uniform(0.5, 1.5, 4)
        _, _, acc, wd, od = dyn(np.zeros(3), quat, v, w, oc, o)
        acc2, wd2, od2 = derivatives(R, tuple(v), tuple(w), tuple(o), tuple(oc), phys)
        np.testing.assert_allclose(acc2, acc, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(wd2, wd, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(od2, od, rtol=1e-12, atol=1e-9)


def random_flight_state(m, rng, B: int, N: int):
    """Random attitudes within 40 deg of level, rates, rotor speeds 0.7-1.3 x hover, firmware
    memory, and setpoints near the state; returns (q, p, cmd)."""
    q, p = rng.normal(0, 1, (B, N, 3)), rng.normal(0, 1, (B, N, 3))
    rv = rng.normal(0, 1, (B, N, 3))
    rv *= np.radians(rng.uniform(0, 40, (B, N, 1))) / np.linalg.norm(rv, axis=-1, keepdims=True)
    m.R[...] = Rotation.from_rotvec(rv.reshape(-1, 3)).as_matrix().reshape(B, N, 3, 3)
    m.omega[...] = rng.normal(0, 2, (B, N, 3))
    m.rotor_speed[...] = m.params.hover_rpm * rng.uniform(0.7, 1.3, (B, N, 4))
    m.memory[..., 0:3] = rng.uniform(-0.3, 0.3, (B, N, 3))
    m.memory[..., 3:6] = rng.uniform(-0.5, 0.5, (B, N, 3))
    m.memory[..., 6:9] = m.omega + rng.normal(0, 0.05, (B, N, 3))
    parts = [q + rng.normal(0, 0.2, (B, N, 3)), p + rng.normal(0, 0.5, (B, N, 3))]
    parts += [rng.normal(0, 2, (B, N, 3)), rng.uniform(-math.pi, math.pi, (B, N, 1))]
    return q, p, np.concatenate(parts, axis=-1)


def one_tick_errors(model: str, nsub: int) -> dict[str, float]:
    """One firmware tick (dt = 2 ms) from 64 random flight states and setpoints."""
    rng = np.random.default_rng(2)
    m = _model(4, 16, dt=0.002, substeps=nsub, crazyflie_model=model)
    q, p, cmd = random_flight_state(m, rng, 4, 16)
    st = _oracle_state(m, q, p)
    PackageCrazyflie(model, physics_substeps=nsub).tick(st, setpoint_at(cmd, 0.0), 0)
    m.fly_setpoints(q, p, cmd)
    assert not m.crashed.any()
    return _errors(m, q, p, st)


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("nsub", [1, 2])
def test_one_tick_within_1e6(model, nsub):
    err = one_tick_errors(model, nsub)
    assert max(err.values()) < 1e-6, err


def a_program(t: float, N: int) -> np.ndarray:
    """A varied acceleration program for N UAVs: sinusoids, steps, a climb past the limit."""
    k = np.arange(N)
    a = np.zeros((N, 3))
    a[:, 0] = 1.5 * np.sin(0.8 * t * (1 + 0.3 * k))
    a[:, 1] = np.where(t < 2.0, 0.8 * (k % 3 - 1), -0.4 * (k % 3 - 1))
    a[:, 2] = 0.6 * np.cos(1.3 * t + k)
    if N > 3:
        a[3] = (0.0, 0.0, 8.0) if 1.0 < t < 1.5 else (0.0, 0.0, -2.0) if 1.5 <= t < 2.0 else 0.0
    return a


#: settings of the closed-loop check: the default, crazyflow's rates, a 1 kHz plant anchored
SETTINGS = {
    "default": {},
    "stream500_pos100": dict(crazyflie_setpoint_rate=500.0, crazyflie_position_rate=100.0),
    "physics1000_anchored": dict(substeps=20, crazyflie_reference="anchored"),
}


def flight_errors(model: str, setting: str, T: float = 5.0) -> dict[str, float]:
    """T seconds of 6 UAVs under a_program: the model's setpoint stream replayed through the
    packages tick by tick; the largest differences over the flight."""
    m = _model(1, 6, crazyflie_model=model, **SETTINGS[setting])
    prm = m.params
    q = np.zeros((1, 6, 3))
    q[..., 0], q[..., 2] = np.arange(6), 1.0
    p = np.zeros((1, 6, 3))
    m.reset_rows(np.arange(1), q, p)
    st = _oracle_state(m, q, p)
    oracle = PackageCrazyflie(model, prm.position_every, prm.physics_substeps)
    worst: dict[str, float] = {}
    for step in range(round(T / prm.dt)):
        m.advance(q, p, a_program(step * prm.dt, 6)[None])
        cmd = m.setpoint.copy()
        for k in range(prm.ticks):
            t = (k - k % prm.setpoint_every) / FIRMWARE_RATE
            oracle.tick(st, setpoint_at(cmd, t), step * prm.ticks + k)
        for key, val in _errors(m, q, p, st).items():
            worst[key] = max(worst.get(key, 0.0), val)
    assert not m.crashed.any()
    return worst


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("setting", list(SETTINGS))
def test_closed_loop_5s_within_1mm(model, setting):
    err = flight_errors(model, setting)
    assert err["position"] < 1e-3 and max(err.values()) < 1e-3, err


def main() -> None:
    """Print the measured errors (the tables of docs/crazyflie.md, "Oracle checks")."""
    head = "| position (m) | velocity (m/s) | attitude | rates (rad/s) | rotors (RPM) | memory |"
    print("One firmware tick from 64 random flight states (largest absolute error):\n")
    print("| model | plant steps per tick " + head + "\n" + "|---" * 8 + "|")
    for model in MODELS:
        for nsub in (1, 2):
            e = one_tick_errors(model, nsub)
            print(f"| {model} | {nsub} | " + " | ".join(f"{v:.1e}" for v in e.values()) + " |")
    print("\n5 s closed-loop flight of 6 UAVs (largest absolute error over the flight):\n")
    print("| model | setting " + head + "\n" + "|---" * 8 + "|")
    for model in MODELS:
        for setting in SETTINGS:
            e = flight_errors(model, setting)
            print(f"| {model} | {setting} | " + " | ".join(f"{v:.1e}" for v in e.values()) + " |")


if __name__ == "__main__":
    main()
