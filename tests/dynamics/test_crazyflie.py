"""``dynamics="crazyflie"``: the model's behaviour, batching, config checks, and every view with
the analytic controllers and the safety filter (no optional package needed; the oracle checks
against drone-models / drone-controllers are in test_crazyflie_oracle.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from view_helpers import VIEWS, make_view, reset_view, step_view

from baselines.controllers import make_pair_policy
from pairflock_env import PairFlockCore, make_config, parallel_env
from pairflock_env.dynamics import VEHICLES, make_vehicle
from pairflock_env.dynamics.crazyflie import CRAZYFLIE_MODELS, CrazyflieModel, quat_xyzw
from pairflock_env.dynamics.crazyflie.section import hover_rotor_time_constant, reaction_time
from pairflock_env.math3d import rotation_zyx
from pairflock_env.safety import SafetyParams

MODELS = tuple(CRAZYFLIE_MODELS)


def _model(B: int, N: int, **kw):
    """A Crazyflie model of B swarms x N UAVs and its state, level at 1 m, at rest."""
    kw = {"n_uavs": max(N, 2), "dt": 0.02, **kw}
    cfg = make_config(None, dynamics="crazyflie", **kw)
    m = make_vehicle(cfg, B)
    q = np.zeros((B, cfg.n_uavs, 3))
    q[..., 0] = np.arange(cfg.n_uavs)
    q[..., 2] = 1.0
    p = np.zeros_like(q)
    m.reset_rows(np.arange(B), q, p)
    return m, q, p


# --------------------------------------------------------------------------- registration
def test_registered_through_the_vehicle_seam_with_its_own_section():
    entry = VEHICLES["crazyflie"]
    assert entry.model is CrazyflieModel and entry.dims == (3,)
    assert set(entry.info_keys) == set(VEHICLES["quadrotor"].info_keys)
    cfg = make_config("paper", dynamics="crazyflie")
    assert cfg.dim == 3 and cfg.substeps == 5  # dt 0.01 s: 5 firmware ticks, plant at 500 Hz
    assert make_config(None, dynamics="crazyflie", dt=0.02).substeps == 10
    sec = cfg.section("crazyflie")
    assert sec.crazyflie_model == "cf2x_L250" and sec.crazyflie_position_rate == 500.0


def test_filter_defaults_follow_the_crazyflie():
    cfg = make_config(None, dynamics="crazyflie", dt=0.02, safety_filter="cbf")
    prm = SafetyParams.from_config(cfg)
    assert prm.brake_accel <= cfg.crazyflie_accel_limit
    assert prm.reaction_time == pytest.approx(1.4 * 0.1359, rel=1e-3) == reaction_time(cfg)
    assert prm.decay == 0.1
    # the reaction time covers the measured 63 % rise of an acceleration step on every set
    for model in MODELS:
        m, q, p = _model(1, 1, crazyflie_model=model, crazyflie_setpoint_rate=500.0)
        a = np.zeros_like(q)
        a[..., 0] = 2.0
        v = []
        for _ in range(25):
            m.advance(q, p, a)
            v.append(p[0, 0, 0])
        t63 = 0.02 * (1 + np.argmax(np.diff(v, prepend=0.0) / 0.02 >= 0.63 * 2.0))
        tau = 1.4 * hover_rotor_time_constant(model)
        assert t63 <= tau + 0.02, (model, t63, tau)


# --------------------------------------------------------------------------- behaviour
@pytest.mark.parametrize(("model", "tol"), [("cf2x_L250", 0.035), ("cf21B_500", 0.1)])
def test_hover_holds_the_reference(model, tol):
    """a_des = 0 for 10 s: the firmware's PID absorbs most of the feed-forward's thrust error
    (0.88x of the weight for cf2x_L250, 1.46x for cf21B_500; its z integral saturates, which
    leaves 1.5 cm and 8 cm)."""
    m, q, p = _model(1, 2, crazyflie_model=model)
    q0 = q.copy()
    worst = 0.0
    for _ in range(500):
        m.advance(q, p, np.zeros_like(q))
        worst = max(worst, float(np.abs(q - q0).max()))
    assert worst < tol and not m.crashed.any()
    np.testing.assert_allclose(m.reference[..., :3], q0, atol=1e-12)


def test_an_acceleration_step_is_tracked_like_the_particle():
    """1.5 s of a = (1, -0.5, 0.3) m/s^2. (Beyond about 2.5 m/s the body drag, which the
    firmware does not feed forward, holds the UAV more than the 0.1 m leash behind.)"""
    m, q, p = _model(1, 2)
    q0 = q.copy()
    a = np.zeros_like(q)
    a[..., :] = (1.0, -0.5, 0.3)
    for _ in range(75):
        m.advance(q, p, a)
    ideal = q0 + 0.5 * a * 1.5**2
    assert np.abs(q - ideal).max() < 0.08
    assert np.abs(p - a * 1.5).max() < 0.15
    assert 0 < m.tilt().max() < 15.0  # 6.5 deg for the acceleration, more against drag
    assert not m.accel_limited.any() and not m.motor_saturated.any()


def test_limits_and_the_leash_report_accel_limited():
    m, q, p = _model(1, 2, crazyflie_accel_limit=2.0)
    a = np.zeros_like(q)
    a[0, 0] = (4.0, 0.0, 0.0)
    m.advance(q, p, a)
    assert m.setpoint[0, 0, 6] == pytest.approx(2.0)  # cut to the limit
    assert m.accel_limited[0].tolist() == [True, False]
    m.reference[0, 1, 0] += 1.0  # the reference got away from UAV 1: the leash pulls it in
    m.advance(q, p, np.zeros_like(q))
    assert m.accel_limited[0].tolist() == [False, True]
    assert abs(m.setpoint[0, 1, 0] - q[0, 1, 0]) <= 0.1 + 0.05


def test_reset_rows_touches_only_its_rows():
    m, q, p = _model(2, 3)
    for _ in range(10):
        m.advance(q, p, np.ones_like(q))
    before = (m.R[1].copy(), m.rotor_speed[1].copy(), m.memory[1].copy())
    m.reset_rows(np.array([0]), q, p)
    np.testing.assert_array_equal(m.R[0], np.broadcast_to(np.eye(3), (3, 3, 3)))
    np.testing.assert_array_equal(m.memory[0], 0.0)
    for now, then in zip((m.R[1], m.rotor_speed[1], m.memory[1]), before, strict=True):
        np.testing.assert_array_equal(now, then)


def test_non_finite_command_and_the_ground_crash_only_that_uav():
    m, q, p = _model(1, 3, crazyflie_ground_altitude=0.5)
    a = np.zeros_like(q)
    a[0, 0, 0] = np.nan
    a[0, 1, 2] = -5.0  # dives into the ground
    for _ in range(50):
        m.advance(q, p, a)
    assert m.crashed[0].tolist() == [True, True, False]
    assert m.info()["vehicle_terminated"].tolist() == [True]
    assert np.isfinite(q).all() and (p[0, :2] == 0).all() and np.isfinite(m.R).all()


def test_flipped_crazyflie_crashes():
    m, q, p = _model(1, 2)
    m.R[0, 0] = rotation_zyx(math.radians(95.0), 0.0, 0.0)  # rolled past 90 degrees
    m.advance(q, p, np.zeros_like(q))
    assert m.crashed[0].tolist() == [True, False]


@pytest.mark.parametrize("model", ["cf2x_L250", "cf21B_500"])
def test_batched_equals_one_by_one(model):
    """(B, N) = (3, 4) in one call gives bit for bit what 12 single-UAV models give."""
    B, N, steps = 3, 4, 60
    rng = np.random.default_rng(3)
    kw = dict(crazyflie_model=model, crazyflie_setpoint_rate=100.0)
    m, q, p = _model(B, N, **kw)
    q0 = q + rng.normal(0, 2, q.shape)
    p0 = rng.normal(0, 0.5, q.shape)
    a = rng.normal(0, 2, (steps, B, N, 3))
    q, p = q0.copy(), p0.copy()
    m.reset_rows(np.arange(B), q, p)
    for k in range(steps):
        m.advance(q, p, a[k])
    for b in range(B):
        for n in range(N):
            cfg = make_config(None, dynamics="crazyflie", n_uavs=2, dt=0.02, **kw)
            one = CrazyflieModel(cfg, 1)
            q1, p1 = q0[b : b + 1, [n, n]], p0[b : b + 1, [n, n]]
            one.reset_rows(np.arange(1), q1, p1)
            for k in range(steps):
                one.advance(q1, p1, a[k, b : b + 1, [n, n]])
            np.testing.assert_array_equal(q1[0, 0], q[b, n])
            np.testing.assert_array_equal(p1[0, 0], p[b, n])
            np.testing.assert_array_equal(one.R[0, 0], m.R[b, n])
            np.testing.assert_array_equal(one.rotor_speed[0, 0], m.rotor_speed[b, n])
            np.testing.assert_array_equal(one.memory[0, 0], m.memory[b, n])


def test_recorded_setpoints_replay_exactly():
    """A flight under a_des, replayed open loop from its recorded cmdFullState rows."""
    steps = 100
    rng = np.random.default_rng(5)
    a = rng.normal(0, 1.5, (steps, 2, 3, 3))
    m, q, p = _model(2, 3, crazyflie_setpoint_rate=250.0)
    q0 = q.copy()
    rec, traj = [], []
    for k in range(steps):
        m.advance(q, p, a[k])
        rec.append(m.setpoint.copy())
        traj.append(q.copy())
    r, q, p = _model(2, 3, crazyflie_setpoint_rate=250.0)
    np.testing.assert_array_equal(q, q0)
    for k in range(steps):
        r.fly_setpoints(q, p, rec[k])
        np.testing.assert_array_equal(q, traj[k])
    with pytest.raises(ValueError, match="cmd has shape"):
        r.fly_setpoints(q, p, np.zeros((2, 3, 9)))


def _rotation_of_xyzw(x: np.ndarray) -> np.ndarray:
    """The rotation matrix of unit quaternions x (..., 4) in xyzw order."""
    x, y, z, w = np.moveaxis(x, -1, 0)
    rows = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    return np.stack([np.stack(r, -1) for r in rows], -2)


def test_quat_xyzw_is_the_scalar_last_unit_quaternion_of_r():
    rng = np.random.default_rng(4)
    angles = rng.uniform(-math.pi, math.pi, (3, 50, 40))
    angles[1] /= 2.0  # pitch in [-pi/2, pi/2]
    R = rotation_zyx(*angles)
    x = quat_xyzw(R)
    assert x.shape == (50, 40, 4) and (x[..., 3] >= 0).all()
    np.testing.assert_allclose(np.linalg.norm(x, axis=-1), 1.0, atol=1e-15)
    np.testing.assert_allclose(_rotation_of_xyzw(x), R, atol=2e-15)
    half_turns = rotation_zyx(np.array([math.pi, 0.0, 0.0]), 0.0, np.array([0.0, 0.0, math.pi]))
    np.testing.assert_allclose(_rotation_of_xyzw(quat_xyzw(half_turns)), half_turns, atol=1e-15)
    np.testing.assert_array_equal(quat_xyzw(np.eye(3)), [0.0, 0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="R has shape"):
        quat_xyzw(np.eye(4))


def test_info_has_the_quadrotor_keys():
    cfg = make_config(None, dynamics="crazyflie", n_uavs=4, pairs=((0, 1),))
    core = PairFlockCore(cfg, num_swarms=2, seed=0)
    core.reset()
    res = core.step(np.zeros((2, 2, 3)))
    for key in ("crashed", "motor_saturated", "accel_limited", "tilt"):
        assert res.info[key].shape == (2, 2)
    for key in ("vehicle_terminated", "crashed_uavs", "motor_saturated_uavs", "accel_limited_uavs"):
        assert res.info[key].shape == (2,)
    assert set(core.vehicle.info()) == set(CrazyflieModel.INFO_KEYS)


# --------------------------------------------------------------------------- config
@pytest.mark.parametrize(
    ("kw", "exc", "field"),
    [
        (dict(crazyflie_model="cf3"), ValueError, "crazyflie_model='cf3'"),
        (dict(crazyflie_model=250), TypeError, "crazyflie_model=250"),
        (dict(dt=0.015), ValueError, "dt=0.015"),
        (dict(substeps=15), ValueError, "substeps=15"),
        (dict(substeps=2.0), TypeError, "substeps=2.0"),
        (dict(crazyflie_position_rate=300.0), ValueError, "crazyflie_position_rate=300.0"),
        (dict(crazyflie_position_rate=0.0), ValueError, "crazyflie_position_rate=0.0"),
        (dict(crazyflie_setpoint_rate=20.0), ValueError, "crazyflie_setpoint_rate=20.0"),
        (dict(crazyflie_reference="free"), ValueError, "crazyflie_reference='free'"),
        (dict(crazyflie_leash=0.0), ValueError, "crazyflie_leash=0.0"),
        (dict(crazyflie_leash_velocity=-1.0), ValueError, "crazyflie_leash_velocity=-1.0"),
        (dict(crazyflie_accel_limit="5"), TypeError, "crazyflie_accel_limit='5'"),
        (dict(crazyflie_accel_limit=math.inf), ValueError, "crazyflie_accel_limit=inf"),
        (dict(crazyflie_yaw=200.0), ValueError, "crazyflie_yaw=200.0"),
        (dict(crazyflie_crash_tilt=0.0), ValueError, "crazyflie_crash_tilt=0.0"),
        (dict(crazyflie_ground_altitude=math.nan), ValueError, "crazyflie_ground_altitude=nan"),
        (dict(dim=2), ValueError, "dim=2"),
    ],
)
def test_bad_values_raise_naming_the_field(kw, exc, field):
    with pytest.raises(exc, match=f"^{field} is invalid"):
        make_config(None, **{"dynamics": "crazyflie", "dt": 0.02, **kw})


def test_the_rates_need_not_divide_dt_for_other_vehicles():
    cfg = make_config(None, dt=0.003, crazyflie_setpoint_rate=250.0)  # particle: unused
    assert cfg.dynamics == "particle" and cfg.crazyflie_setpoint_rate == 250.0


@pytest.mark.parametrize(
    "kw",
    [
        dict(dt=1.0, crazyflie_accel_limit=100.0, crazyflie_leash=1e5),
        dict(crazyflie_leash_velocity=1e4, crazyflie_accel_limit=1e-9),
        dict(dt=0.002, substeps=10, crazyflie_setpoint_rate=500.0, crazyflie_crash_tilt=180.0),
        dict(crazyflie_reference="anchored", crazyflie_yaw=-180.0, crazyflie_position_rate=100.0),
        dict(crazyflie_model="cf21B_500", crazyflie_ground_altitude=-1e7),
    ],
)
def test_accepted_extremes_stay_finite(kw):
    """Configs at the edges of the ranges, under wild commands: every state stays finite."""
    m, q, p = _model(1, 4, **kw)
    a = np.array([[[1e6, 0.0, 0.0], [0.0, 0.0, -1e6], [np.inf, 0.0, 0.0], [3.0, -2.0, 1.0]]])
    for _ in range(5):
        m.advance(q, p, a)
    for arr in (q, p, m.R, m.omega, m.rotor_speed, m.memory, m.reference):
        assert np.isfinite(arr).all()
    assert m.crashed[0, 2]


# --------------------------------------------------------------------------- views
def _core(env):
    return env.core if hasattr(env, "core") else env.unwrapped.core


def _act(env, kind, pol, obs):
    """The action of the pair controller ``pol`` in the view's own format."""
    if kind == "parallel":
        return {a: pol.predict(o)[0] for a, o in obs.items()}
    if kind == "aec":
        return pol.predict(env.observe(env.agent_selection))[0]
    act = pol.predict(obs.reshape(-1, pol.layout.size))[0]
    return act if kind == "sb3" else act.reshape(env.action_space.shape)


@pytest.mark.parametrize("kind", VIEWS)
@pytest.mark.parametrize("controller", ["smc", "proportional", "braking"])
def test_every_view_flies_the_controllers_with_the_filter(kind, controller):
    if kind == "sb3":
        pytest.importorskip("stable_baselines3", reason="the SB3 view needs the train extra")
    kw = dict(dynamics="crazyflie", n_uavs=6, safety_filter="cbf", max_cycles=25)
    if kind in ("gym", "vector", "sb3"):
        kw["interface"] = "world"  # the controllers read the physical observation
    env = make_view(kind, **kw)
    out = reset_view(env, kind, seed=0)
    obs = out[0] if isinstance(out, tuple) else out
    pol = make_pair_policy(controller, env)
    for _ in range(12 if kind == "aec" else 6):
        out = step_view(env, kind, _act(env, kind, pol, obs))
        obs = out[0]
    core = _core(env)
    assert isinstance(core.vehicle, CrazyflieModel) and core.config.safety_filter == "cbf"
    assert np.isfinite(core.q).all() and not core.vehicle.crashed.any()
    assert core.t.max() > 0.05
    env.close()


# --------------------------------------------------------------------------- preset
@pytest.mark.parametrize("controller", ["smc", "proportional", "braking"])
@pytest.mark.parametrize("mode", ["none", "cbf"])
def test_the_crazyflie_preset_flies_every_controller(controller, mode):
    """20 s of the preset, two seeds: nobody crashes, the swarm stays in its 6 m x 6 m x 2.6 m
    arena, the pair closes in on d_m, and with the filter on it keeps safety_distance."""
    cfg = make_config("crazyflie", safety_filter=mode, horizon=20.0)
    core = PairFlockCore(cfg, num_swarms=2)
    pol = make_pair_policy(controller, cfg)
    res = core.reset(seed=[100, 101])
    closest, lo, hi = np.inf, np.full(3, np.inf), np.full(3, -np.inf)
    for _ in range(cfg.episode_steps):
        a, _ = pol.predict(res.obs.reshape(4, -1))
        res = core.step(a.reshape(2, 2, -1))
        d = np.linalg.norm(core.q[:, :2, None] - core.q[:, None], axis=-1)
        d[:, 0, 0] = d[:, 1, 1] = np.inf
        closest = min(closest, float(d.min()))
        lo, hi = np.minimum(lo, core.q.min(axis=(0, 1))), np.maximum(hi, core.q.max(axis=(0, 1)))
    assert not core.vehicle.crashed.any() and core.vehicle.tilt().max() < 30.0
    assert lo[:2].min() >= -3.0 - 1e-9 and hi[:2].max() <= 3.0 + 1e-9
    assert lo[2] > 0.6 and hi[2] < 2.6
    pair = np.linalg.norm(core.q[:, 0] - core.q[:, 1], axis=-1)
    assert np.abs(pair - cfg.d_m[0]).max() < 0.25
    if mode == "cbf":
        assert closest >= cfg.safety_distance


def test_parallel_env_runs_the_preset():
    env = parallel_env(preset="crazyflie", max_cycles=50)
    obs, _ = env.reset(seed=0)
    pol = make_pair_policy("smc", env)
    while env.agents:
        obs, _, _, _, infos = env.step({a: pol.predict(o)[0] for a, o in obs.items()})
    assert env.core.vehicle.name == "crazyflie" and not infos["uav_0"]["crashed"]
