"""The robustness options do what their docs say: sensor noise on y and y', a partner delay in
control steps, and a random acceleration disturbance, each from the swarm's own generator."""

from __future__ import annotations

import numpy as np
import pytest

from pairflock_env import AGENT_INFO_KEYS, SWARM_INFO_KEYS, PairFlockCore, parallel_env
from pairflock_env.task.infos import LIVE_INFO_KEYS
from pairflock_env.task.observations import add_sensor_noise
from pairflock_env.task.rewards import REWARD_TERMS

STEPS = 60


def _zero(core: PairFlockCore) -> np.ndarray:
    return np.zeros((core.num_swarms, core.n_agents, core.config.dim))


def _true_partner(core: PairFlockCore) -> tuple[np.ndarray, np.ndarray]:
    ia, ip = core.agent_uavs, core.partner_uavs
    return core.q[:, ip] - core.q[:, ia], core.p[:, ip] - core.p[:, ia]


def _field(core: PairFlockCore, obs: np.ndarray, name: str) -> np.ndarray:
    return core.layout.get(obs, name).astype(np.float64)


def _residuals(cfg, **robust) -> tuple[np.ndarray, np.ndarray]:
    """Observed minus true partner offset and velocity over a zero-action episode."""
    core = PairFlockCore(cfg.replace(**robust), num_swarms=4)
    res = core.reset(seed=[11, 12, 13, 14])
    dy, dv = [], []
    for _ in range(STEPS):
        off, vel = _true_partner(core)
        dy.append(_field(core, res.obs, "partner_offset") - off)
        dv.append(_field(core, res.obs, "partner_velocity") - vel)
        res = core.step(_zero(core))
    return np.stack(dy), np.stack(dv)


def _check_std(x: np.ndarray, sigma: float) -> None:
    """Zero mean and std sigma, within 5 standard errors of the estimates."""
    n = x.size
    assert abs(x.mean()) < 5 * sigma / np.sqrt(n)
    assert abs(x.std() - sigma) < 5 * sigma / np.sqrt(2 * n)


def _float32_exact(x: np.ndarray, scale: np.ndarray) -> None:
    # observations are float32: equal up to its rounding
    np.testing.assert_allclose(x, 0.0, atol=float(np.max(np.abs(scale))) * 2e-7 + 1e-7)


def test_without_options_agents_see_the_true_partner_state(small_config):
    dy, dv = _residuals(small_config)
    _float32_exact(dy, np.asarray(small_config.pair_corner) * 3)
    _float32_exact(dv, np.asarray(1e3))


@pytest.mark.parametrize("field, sigma", [("obs_noise_position", 0.7), ("obs_noise_velocity", 0.3)])
def test_observation_noise_has_the_stated_std_on_its_field_only(small_config, field, sigma):
    dy, dv = _residuals(small_config, **{field: sigma})
    noisy, clean = (dy, dv) if field == "obs_noise_position" else (dv, dy)
    _check_std(noisy, sigma)
    _float32_exact(clean, np.asarray(1e3))
    # independent across agents and axes: the two members of a pair see different noise
    assert np.corrcoef(noisy[:, :, 0, 0].ravel(), noisy[:, :, 1, 0].ravel())[0, 1] < 0.5


def _trajectory(cfg, steps: int = STEPS) -> np.ndarray:
    core = PairFlockCore(cfg, num_swarms=2)
    core.reset(seed=[5, 6])
    qs = [core.q.copy()]
    for _ in range(steps):
        core.step(_zero(core))
        qs.append(core.q.copy())
    return np.stack(qs)


@pytest.mark.parametrize(
    "robust", [dict(obs_noise_position=1.0, obs_noise_velocity=1.0), dict(partner_delay=4)]
)
def test_noise_and_delay_change_what_agents_see_not_the_physics(small_config, robust):
    np.testing.assert_array_equal(
        _trajectory(small_config.replace(**robust)), _trajectory(small_config)
    )


def test_partner_delay_shows_the_partner_state_of_d_steps_ago(small_config):
    d = 3
    core = PairFlockCore(small_config.replace(partner_delay=d), num_swarms=2)
    res = core.reset(seed=[1, 2])
    ia, ip = core.agent_uavs, core.partner_uavs
    hq, hp, ha = [], [], []
    for k in range(STEPS):
        hq.append(core.q.copy())
        hp.append(core.p.copy())
        ha.append(core.flock_accel.copy())
        old = max(k - d, 0)  # before d steps exist, the reset state is the latest known
        want_off = hq[old][:, ip] - core.q[:, ia]
        want_vel = hp[old][:, ip] - core.p[:, ia]
        np.testing.assert_allclose(
            _field(core, res.obs, "partner_offset"), want_off, rtol=1e-6, atol=1e-4
        )
        np.testing.assert_allclose(
            _field(core, res.obs, "partner_velocity"), want_vel, rtol=1e-6, atol=1e-4
        )
        np.testing.assert_allclose(
            _field(core, res.obs, "partner_flock_accel"), ha[old][:, ip], rtol=1e-6, atol=1e-4
        )
        # the agent's own state is never delayed
        np.testing.assert_allclose(
            _field(core, res.obs, "flock_accel"), ha[k][:, ia], rtol=1e-6, atol=1e-4
        )
        res = core.step(_zero(core))
    assert 2 * d < STEPS  # the check covered delayed samples, not only the reset fill


def test_disturbance_is_an_extra_acceleration_of_the_stated_std(small_config, dynamics):
    if dynamics != "particle":
        pytest.skip("the velocity increment equals the command only for the particle model")
    sigma = 2.5
    cfg = small_config.replace(disturbance_std=sigma)
    core = PairFlockCore(cfg, num_swarms=3)
    core.reset(seed=[7, 8, 9])
    w = []
    for _ in range(STEPS):
        p0, a0 = core.p.copy(), core.flock_accel.copy()
        core.step(_zero(core))
        w.append((core.p - p0) / cfg.dt - a0)  # what was added to every UAV's command
    w = np.stack(w)
    _check_std(w, sigma)
    assert np.all(np.abs(w).max(axis=(0, 1, 3)) > 0)  # every UAV, paired or not, is pushed
    # the same seed gives the same disturbance; another seed another one
    np.testing.assert_array_equal(_trajectory(cfg)[-1], _trajectory(cfg)[-1])
    assert not np.array_equal(_trajectory(cfg)[-1], _trajectory(small_config)[-1])


def test_random_options_use_each_swarms_own_generator(small_config):
    """Swarm b of a batch sees the same noise, delay and disturbance as a 1-swarm core with
    the same seed (so results do not depend on how runs are batched)."""
    cfg = small_config.replace(
        obs_noise_position=0.5, obs_noise_velocity=0.5, partner_delay=2, disturbance_std=1.0
    )
    big, one = PairFlockCore(cfg, num_swarms=3), PairFlockCore(cfg, num_swarms=1)
    rb, r1 = big.reset(seed=[4, 9, 2]), one.reset(seed=[9])
    rng = np.random.default_rng(0)
    for _ in range(STEPS):
        np.testing.assert_array_equal(rb.obs[1], r1.obs[0])
        a = rng.uniform(-0.2, 0.2, (3, big.n_agents, cfg.dim))
        rb, r1 = big.step(a), one.step(a[1:2])
    np.testing.assert_array_equal(big.q[1], one.q[0])


@pytest.mark.parametrize(
    "field, value, exc",
    [
        ("obs_noise_position", -0.1, ValueError),
        ("obs_noise_velocity", float("nan"), ValueError),
        ("disturbance_std", -1.0, ValueError),
        ("partner_delay", -1, ValueError),
        ("partner_delay", 1.5, TypeError),
    ],
)
def test_bad_robustness_values_name_the_field(small_config, field, value, exc):
    with pytest.raises(exc, match=field):
        small_config.replace(**{field: value})


# --------------------------------------------------------------------------- divergence
#: the core's infos that describe the state (the vehicle model's own are always current)
STATE_INFO_KEYS = [
    k
    for k in (*AGENT_INFO_KEYS, *SWARM_INFO_KEYS, *(f"reward_{t}" for t in REWARD_TERMS))
    if k not in LIVE_INFO_KEYS
]


def _all_finite(info) -> bool:
    return all(np.isfinite(np.asarray(v, dtype=np.float64)).all() for v in info.values())


@pytest.mark.parametrize("blowup", [np.nan, 1e300])
def test_a_diverged_swarm_keeps_its_last_finite_infos(small_config, blowup):
    """A swarm that diverges (NaN, or a runaway beyond float32) repeats the observation and
    the state infos of its last finite step; the other swarm is unaffected."""
    core = PairFlockCore(small_config, num_swarms=2)
    ref = PairFlockCore(small_config, num_swarms=2)
    core.reset(seed=[0, 1])
    ref.reset(seed=[0, 1])
    zero = _zero(core)
    last = core.step(zero)
    ref.step(zero)
    a = core.agent_uavs[0]
    core.q[1, a] = blowup  # a numerical blow-up of a paired UAV in swarm 1
    for k in range(3):
        res, want = core.step(zero), ref.step(zero)
        assert res.info["diverged"].tolist() == [False, True]
        assert res.terminated.tolist() == [False, True]
        assert _all_finite(res.info) and np.isfinite(res.obs).all()
        assert np.isfinite(res.reward).all() and np.all(res.reward[1] < 0)
        np.testing.assert_array_equal(res.obs[1], last.obs[1])
        for key in res.info:
            np.testing.assert_array_equal(res.info[key][0], want.info[key][0], err_msg=key)
        for key in STATE_INFO_KEYS:
            np.testing.assert_array_equal(res.info[key][1], last.info[key][1], err_msg=key)
        assert res.info["sim_time"][1] == pytest.approx((k + 2) * small_config.dt)
    # results already returned are not rewritten by later steps or resets
    flags = res.info["diverged"].copy()
    core.reset_rows([1], seed=[5])
    assert res.info["diverged"].tolist() == flags.tolist()


def test_a_diverged_swarm_has_finite_infos_in_the_pettingzoo_view(small_kwargs):
    env = parallel_env(**small_kwargs)
    env.reset(seed=0)
    act = {a: np.zeros(env.config.dim, np.float32) for a in env.agents}
    env.step(act)
    env.core.q[0, env.core.agent_uavs[1]] = np.inf
    _, rewards, terms, _, infos = env.step(act)
    assert all(terms.values())
    for info in infos.values():
        assert info["diverged"]
        for k, v in info.items():
            if isinstance(v, (int, float, np.number)):
                assert np.isfinite(v), k
    assert all(np.isfinite(r) for r in rewards.values())


def test_observation_noise_saturates_instead_of_overflowing():
    big = np.finfo(np.float32).max
    clean = np.array([0.0, 1.0, -2.0, 1e39, np.nan, np.inf])
    noise = np.array([1e300, -1e300, 1.0, 1.0, 1.0, -1e300])
    got = add_sensor_noise(clean, noise)
    np.testing.assert_array_equal(got[:3], [big, -big, -1.0])
    # a true value beyond what an observation can hold stays so: that is a divergence
    assert got[3] == 1e39 and np.isnan(got[4]) and got[5] == np.inf
    small = np.array([0.5, -0.25])
    np.testing.assert_array_equal(add_sensor_noise(small, small), small + small)


@pytest.mark.parametrize("field", ["obs_noise_position", "obs_noise_velocity"])
def test_huge_observation_noise_never_flags_divergence(small_config, field):
    """Either the config refuses a noise this large (a ValueError naming the field), or the
    swarm flies on with finite observations, never flagged as diverged, on the physics of a
    noise-free run."""
    try:
        cfg = small_config.replace(**{field: 1e300})
    except ValueError as err:
        assert field in str(err)
        return
    np.testing.assert_array_equal(_trajectory(cfg, 10), _trajectory(small_config, 10))
    core = PairFlockCore(cfg, num_swarms=2)
    res = core.reset(seed=[1, 2])
    for _ in range(10):
        assert np.isfinite(res.obs).all() and not res.info["diverged"].any()
        res = core.step(_zero(core))


@pytest.mark.parametrize("overrides", [dict(surface_slope=1e308), dict(reward_error_weight=1e308)])
def test_extreme_configs_give_finite_results_or_a_clear_error(small_config, overrides):
    """What the state check cannot see (a surface or reward that overflows) still gives
    finite rewards and infos, flagged as a divergence; or the config refuses the value."""
    try:
        cfg = small_config.replace(**overrides)
    except ValueError as err:
        assert next(iter(overrides)) in str(err)
        return
    core = PairFlockCore(cfg, num_swarms=2)
    res = core.reset(seed=[1, 2])
    for _ in range(3):
        assert np.isfinite(res.obs).all() and np.isfinite(res.reward).all()
        assert _all_finite(res.info)
        res = core.step(_zero(core))
    assert res.info["diverged"].all()
