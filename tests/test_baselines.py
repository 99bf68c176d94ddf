"""Analytic pair controllers: eq. 28 / eq. 44 algebra, the predict contract, short runs."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from baselines import make_pair_policy
from baselines.evaluation.rollout import rollout, trace_metrics
from pairflock_env import PairFlockCore, make_config, parallel_env


def test_predict_has_sb3_signature_and_batches(small_kwargs):
    env = parallel_env(**small_kwargs)
    obs, _ = env.reset(seed=0)
    for name in ("smc", "proportional", "zero"):
        pol = make_pair_policy(name, env)
        single = {a: pol.predict(o)[0] for a, o in obs.items()}
        batch, state = pol.predict(
            np.stack(list(obs.values())),
            state=None,
            episode_start=np.ones(2, bool),
            deterministic=True,
        )
        assert state is None and batch.dtype == np.float32 and batch.shape == (2, env.config.dim)
        np.testing.assert_array_equal(batch, np.stack(list(single.values())))
        assert all(env.action_space(a).shape == single[a].shape for a in env.agents)
        env.step(single)


def test_sliding_mode_cancels_what_eq_28_says_it_cancels():
    """s' = 2c y.y' + 2 y'.y' + 2 y.y'' with y'' = (flocking difference) + 2 f^x must equal
    -2 k ||y||_1 sign(s) + 2 y.delta, delta = flocking difference + a N y + b N y'."""
    cfg = make_config(
        "paper",
        n_uavs=30,
        init="random",
        pair_corner=8.0,
        swarm_half_width=8.0,
        min_init_spacing=1.0,
    )
    core = PairFlockCore(cfg)
    res = core.reset(seed=4)
    for _ in range(20):  # move a little so that y' != 0
        res = core.step(np.zeros((1, 2, 2)))
    smc = make_pair_policy("smc", core)
    L = core.layout
    y = core.q[0, 1] - core.q[0, 0]
    yd = core.p[0, 1] - core.p[0, 0]
    n = L.get(res.obs[0, 0], "shared_neighbors")[0]
    assert n > 0  # the test is only meaningful with shared neighbours
    fx = smc.pair_term(y, yd, np.array([n]), np.array(5.0))
    acc = core.flock_accel[0]
    dflock = acc[1] - acc[0]
    ydd = dflock + 2.0 * fx
    c, k, a, b = 4.0, 300.0, cfg.attraction, cfg.consensus
    s = c * (y @ y - 25.0) + 2 * y @ yd
    sdot = 2 * c * y @ yd + 2 * yd @ yd + 2 * y @ ydd
    delta = dflock + a * n * y + b * n * yd
    np.testing.assert_allclose(
        sdot, -2 * k * np.abs(y).sum() * np.sign(s) + 2 * y @ delta, rtol=1e-9
    )
    # and each UAV applies -f^x(own view): A gets -f^x, B gets +f^x
    act, _ = smc.predict(res.obs[0])
    np.testing.assert_allclose(act[0] * cfg.pair_accel_limit, -fx, rtol=1e-4, atol=1e-3)
    np.testing.assert_allclose(act[1] * cfg.pair_accel_limit, fx, rtol=1e-4, atol=1e-3)


def test_proportional_is_eq_44():
    env = parallel_env(preset="paper", n_uavs=12)
    obs, _infos = env.reset(seed=0)
    pol = make_pair_policy("proportional", env, k_p=2.0)
    y = env.core.q[0, 1] - env.core.q[0, 0]  # q_B - q_A
    dist = np.linalg.norm(y)
    u_a = pol.predict(obs["uav_0"])[0] * env.config.pair_accel_limit
    # f_A = k_p (d_m - ||q_A - q_B||) sign(q_A - q_B)
    np.testing.assert_allclose(u_a, 2.0 * (5.0 - dist) * np.sign(-y), rtol=1e-5)


def test_boundary_layer_removes_chattering():
    cfg = make_config("paper", n_uavs=20, horizon=15.0)
    rows = {}
    for label, gains in (("sign", {}), ("sat", {"boundary_layer": 20.0})):
        tr = rollout(cfg, make_pair_policy("smc", cfg, **gains), [0])
        rows[label] = trace_metrics(tr, steady_window=5.0)[0]
    assert rows["sat"]["chattering"] < 0.1 * rows["sign"]["chattering"]
    assert rows["sat"]["ss_mean_error"] < 0.2 and rows["sign"]["ss_mean_error"] < 0.2


#: a short run per vehicle model, long enough for the pair to meet (quadrotor: ~7 s)
SHORT_RUNS = {
    "particle": dict(preset="paper", n_uavs=20, horizon=8.0),
    "quadrotor": dict(preset="paper-quadrotor", horizon=12.0),
}


@pytest.mark.parametrize("name", ["smc", "proportional", "braking"])
def test_each_baseline_beats_zero_on_a_short_run(name, dynamics):
    kw = dict(SHORT_RUNS[dynamics])
    cfg = make_config(kw.pop("preset"), **kw)
    seeds = [0, 1]
    zero = trace_metrics(rollout(cfg, make_pair_policy("zero", cfg), seeds), steady_window=2.0)
    # the braking law's defaults are for the particle's instant acceleration; the quadrotor
    # realises at most quad_accel_limit = 6 m/s^2 through its attitude loop: gentler gains
    gains = {"a_b": 1.0, "k": 2.0} if (name, dynamics) == ("braking", "quadrotor") else {}
    ctrl = rollout(cfg, make_pair_policy(name, cfg, **gains), seeds)
    ctrl = trace_metrics(ctrl, steady_window=2.0)
    for z, c in zip(zero, ctrl, strict=False):
        assert c["ss_mean_error"] < 0.2 * z["ss_mean_error"]


def test_make_pair_policy_rejects_bad_names_and_gains():
    cfg = make_config("paper", n_uavs=12)
    with pytest.raises(ValueError, match="'smc'"):
        make_pair_policy("smcc", cfg)
    with pytest.raises(TypeError, match=r"unknown gain.*did you mean 'k'"):
        make_pair_policy("smc", cfg, kk=3)
    with pytest.raises(ValueError, match="k="):
        make_pair_policy("smc", cfg, k=-1.0)
    with pytest.raises(ValueError, match="k_p"):
        make_pair_policy("proportional", cfg, k_p=0.0)
    with pytest.raises(TypeError, match="env="):
        make_pair_policy("smc", object())
    pol = make_pair_policy("smc", cfg)
    with pytest.raises(ValueError, match="observation has shape"):
        pol.predict(np.zeros(3))


@pytest.mark.parametrize(
    "name, gain",
    [("smc", g) for g in ("c", "k", "a", "b", "boundary_layer")]
    + [("proportional", "k_p")]
    + [("braking", g) for g in ("a_b", "k", "accel_limit", "detour", "detour_near")],
)
def test_every_gain_is_checked_and_named(name, gain):
    cfg = make_config("paper", n_uavs=12)
    for bad, error in (
        ("a", TypeError),
        ([1.0], TypeError),
        (True, TypeError),
        (np.nan, ValueError),
        (np.inf, ValueError),
        (-1.0, ValueError),
    ):
        with pytest.raises(error, match=f"{gain}="):
            make_pair_policy(name, cfg, **{gain: bad})
    pol = make_pair_policy(name, cfg, **{gain: 2})  # an int is a number
    assert isinstance(pol.gains[gain], float)


def _controllers(env):
    """The analytic controllers and, where SB3 is installed, the committed learned one."""
    yield from (make_pair_policy(n, env) for n in ("smc", "proportional", "braking", "zero"))
    if importlib.util.find_spec("stable_baselines3") is not None:
        model = Path(__file__).resolve().parents[1] / "models" / "pair_n20_a50.zip"
        yield make_pair_policy(f"sb3:{model}", env)


def test_predict_rejects_non_finite_and_non_numeric_observations():
    """Every controller, analytic or learned: NaN/inf raises ValueError (never a NaN
    action), strings a TypeError, both naming the observation."""
    env = parallel_env(preset="paper", n_uavs=20, obs_neighbors=12)  # the learned one's task
    obs, _ = env.reset(seed=0)
    batch = np.stack(list(obs.values()))
    for pol in _controllers(env):
        assert np.isfinite(pol.predict(batch)[0]).all()
        for bad in (np.nan, np.inf, -np.inf):
            x = batch.copy()
            x[1, 3] = bad
            with pytest.raises(ValueError, match=r"observation holds NaN or inf \(rows \[1\]\)"):
                pol.predict(x)
            with pytest.raises(ValueError, match="NaN or inf"):
                pol.predict(x[1])
        with pytest.raises(TypeError, match="observation is invalid"):
            pol.predict(np.full(batch.shape[-1], "a"))


def test_braking_law_stays_in_its_ball_and_holds_the_distance():
    """The braking-curve law: ||u|| <= the bound on every step (the env's or its own), no NaN
    with the partners on top of each other, and the pair held at d_m at 50 m/s^2."""
    cfg = make_config("paper", n_uavs=20, pair_accel_limit=50.0, horizon=12.0)
    tr = rollout(cfg, make_pair_policy("braking", cfg), [0, 1])
    assert np.linalg.norm(tr.u, axis=-1).max() <= 50.0
    for m in trace_metrics(tr, steady_window=4.0):
        assert m["ss_max_error"] < 0.01 and m["band_time"] < 6.0
    own = make_pair_policy("braking", cfg, accel_limit=20.0, a_b=10.0)
    obs = np.random.default_rng(0).normal(0.0, 30.0, (64, own.layout.size))
    assert np.linalg.norm(own.accel(obs), axis=-1).max() <= 20.0
    same = obs.copy()
    same[:, own.layout.slice("partner_offset")] = 0.0  # partners at one point: no direction
    assert np.isfinite(own.accel(same)).all()


def _partner_view(layout, obs):
    """The partner's observation of the same state, for the fields the detour reads."""
    get = layout.get
    z, v = get(obs, "partner_offset"), get(obs, "partner_velocity")
    out = obs.copy()
    for name, value in (
        ("partner_offset", -z),
        ("partner_velocity", -v),
        ("leader_offset", get(obs, "leader_offset") - z),
        ("leader_velocity", get(obs, "leader_velocity") - v),
    ):
        out[:, layout.slice(name)] = value
    return out


@pytest.mark.parametrize("dim", [2, 3])
def test_braking_detour_is_one_common_mode_for_both_members(dim):
    """Both members compute the same detour acceleration from their own observations (it
    moves the midpoint, not the pair's relative motion), also with the midpoint on the
    axis through the leader, where the tie is broken by who is farther from it."""
    kw = dict(preset="paper", n_uavs=12) if dim == 2 else dict(preset="paper-quadrotor")
    law = make_pair_policy("braking", make_config(**kw), detour=80.0)
    rng = np.random.default_rng(1)
    obs = rng.normal(0.0, 60.0, (256, law.layout.size))
    z = law.layout.get(obs, "partner_offset")
    on_axis = obs.copy()  # leader on the pair's axis: c_perp = 0
    on_axis[:, law.layout.slice("leader_offset")] = z * rng.uniform(-1.0, 2.0, (256, 1))
    for x in (obs, on_axis):
        get = law.layout.get
        y = _partner_view(law.layout, x)
        dist = np.linalg.norm(z, axis=-1, keepdims=True)
        mine = law._detour(x, get(x, "partner_offset"), get(x, "partner_velocity"), dist)
        theirs = law._detour(y, get(y, "partner_offset"), get(y, "partner_velocity"), dist)
        np.testing.assert_allclose(mine, theirs, atol=1e-9)
        assert np.linalg.norm(mine, axis=-1).max() > 1.0  # it does push somewhere
    with pytest.raises(ValueError, match=r"detour_far=30\.0 is invalid"):
        make_pair_policy("braking", make_config(**kw), detour_near=40.0, detour_far=30.0)


def test_braking_detour_meets_beside_the_flock():
    """From the paper's corners at N = 100 and 50 m/s^2, with the filter: the straight law
    meets in the flock, the detour beside it, sooner and farther from the other UAVs."""
    cfg = make_config(
        "paper", n_uavs=100, init="corners", pair_accel_limit=50.0, obs_neighbors=12,
        safety_filter="cbf", safety_brake_accel=40.0, safety_other_accel=20.0, horizon=10.0,
    )  # fmt: skip
    runs = {
        d: trace_metrics(rollout(cfg, make_pair_policy("braking", cfg, detour=d), [3]))[0]
        for d in (0.0, 80.0)
    }
    assert runs[80.0]["band_time"] < 4.5 < runs[0.0]["band_time"]
    assert runs[80.0]["min_pair_separation"] > runs[0.0]["min_pair_separation"] >= 0.99
