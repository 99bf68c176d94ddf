"""The robustness options do what their docs say: sensor noise on y and y', a partner delay in
control steps, and a random acceleration disturbance, each from the swarm's own generator."""

from __future__ import annotations

import numpy as np
import pytest

from pairflock_env import PairFlockCore

STEPS = 60


def _zero(core: PairFlockCore) -> np.ndarray:
    return np.zeros((core.num_envs, core.n_agents, core.config.dim))


def _true_partner(core: PairFlockCore) -> tuple[np.ndarray, np.ndarray]:
    ia, ip = core.agent_uavs, core.partner_uavs
    return core.q[:, ip] - core.q[:, ia], core.p[:, ip] - core.p[:, ia]


def _field(core: PairFlockCore, obs: np.ndarray, name: str) -> np.ndarray:
    return core.layout.get(obs, name).astype(np.float64)


def _residuals(cfg, **robust) -> tuple[np.ndarray, np.ndarray]:
    """Observed minus true partner offset and velocity over a zero-action episode."""
    core = PairFlockCore(cfg.replace(**robust), num_envs=4)
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
    core = PairFlockCore(cfg, num_envs=2)
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
    core = PairFlockCore(small_config.replace(partner_delay=d), num_envs=2)
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
    core = PairFlockCore(cfg, num_envs=3)
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
    big, one = PairFlockCore(cfg, num_envs=3), PairFlockCore(cfg, num_envs=1)
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
