"""The batched core: batched == sequential, seeding, resets, divergence, robustness hooks."""

from __future__ import annotations

import numpy as np
import pytest

from pairflock_env import PairFlockCore, make_config, parallel_env
from pairflock_env.task.spaces import separation_bound


def _run(core: PairFlockCore, actions: np.ndarray):
    """Step through a (T, B, M, dim) action sequence; returns stacked obs, rewards, infos."""
    obs, rew, infos = [], [], []
    for a in actions:
        r = core.step(a)
        obs.append(r.obs.copy())
        rew.append(r.reward.copy())
        infos.append({k: v.copy() for k, v in r.info.items()})
    return np.stack(obs), np.stack(rew), infos


def _actions(rng, T, B, M, D):
    return rng.uniform(-0.3, 0.3, (T, B, M, D))


def test_batched_equals_sequential(small_config):
    seeds = [11, 22, 33, 44]
    B, T = len(seeds), 40
    batched = PairFlockCore(small_config, num_swarms=B)
    batched.reset(seed=seeds)
    M, D = batched.n_agents, small_config.dim
    acts = _actions(np.random.default_rng(0), T, B, M, D)
    ob, rb, ib = _run(batched, acts)
    for b, s in enumerate(seeds):
        single = PairFlockCore(small_config, num_swarms=1)
        single.reset(seed=[s])
        os_, rs, is_ = _run(single, acts[:, b : b + 1])
        assert np.array_equal(ob[:, b], os_[:, 0])
        assert np.array_equal(rb[:, b], rs[:, 0])
        for k in ib[0]:
            assert np.array_equal(
                np.stack([i[k][b] for i in ib]), np.stack([i[k][0] for i in is_]), equal_nan=True
            ), k
        assert np.array_equal(batched.q[b], single.q[0])


def test_int_seed_spawns_one_child_per_swarm(small_config):
    batched = PairFlockCore(small_config, num_swarms=3)
    batched.reset(seed=7)
    children = np.random.SeedSequence(7).spawn(3)
    for b in range(3):
        single = PairFlockCore(small_config)
        single.reset(seed=[children[b]])
        assert np.array_equal(single.q[0], batched.q[b])
    assert not np.array_equal(batched.q[0], batched.q[1])


def test_same_seed_bitwise_identical_different_seeds_differ(small_config):
    acts = _actions(np.random.default_rng(5), 30, 1, 2, small_config.dim)
    runs = []
    for seed in (3, 3, 4):
        core = PairFlockCore(small_config)
        core.reset(seed=seed)
        runs.append(_run(core, acts)[0])
    assert np.array_equal(runs[0], runs[1])
    assert not np.array_equal(runs[0], runs[2])


def test_reset_without_seed_continues_the_stream(small_config):
    core = PairFlockCore(small_config, seed=1)
    core.reset()
    first = core.q.copy()
    core.reset()
    assert not np.array_equal(first, core.q)
    again = PairFlockCore(small_config, seed=1)
    again.reset()
    assert np.array_equal(first, again.q)


def test_reset_rows_touches_only_those_rows(small_config):
    core = PairFlockCore(small_config, num_swarms=3)
    core.reset(seed=[1, 2, 3])
    for _ in range(5):
        core.step(np.zeros((3, core.n_agents, small_config.dim)))
    q_before, t_before = core.q.copy(), core.t.copy()
    core.reset_rows([1], seed=[9])
    assert np.array_equal(core.q[[0, 2]], q_before[[0, 2]])
    assert core.t[1] == 0.0 and np.array_equal(core.t[[0, 2]], t_before[[0, 2]])
    fresh = PairFlockCore(small_config)
    fresh.reset(seed=[9])
    assert np.array_equal(core.q[1], fresh.q[0])


def test_initial_state_respects_placement(small_config):
    cfg = small_config
    core = PairFlockCore(cfg, num_swarms=5)
    core.reset(seed=0)
    a, b = cfg.pairs[0]
    # the start box: centre and half-widths may differ per axis (paper-quadrotor: z = 20 m)
    center, corner = cfg.vector("swarm_center"), cfg.vector("pair_corner")
    shape = core.q[:, a].shape
    np.testing.assert_array_equal(core.q[:, a], np.broadcast_to(center - corner, shape))
    np.testing.assert_array_equal(core.q[:, b], np.broadcast_to(center + corner, shape))
    others = np.setdiff1d(np.arange(cfg.n_uavs), [a, b])
    assert np.all(np.abs(core.q[:, others] - center) <= cfg.vector("swarm_half_width"))
    d = np.linalg.norm(core.q[:, :, None] - core.q[:, None], axis=-1)
    d[:, np.arange(cfg.n_uavs), np.arange(cfg.n_uavs)] = np.inf
    assert d.min() >= cfg.min_init_spacing
    assert np.all(core.p == 0.0)


def test_reset_options_set_the_state_and_are_validated(small_config):
    cfg = small_config
    N, D = cfg.n_uavs, cfg.dim
    core = PairFlockCore(cfg)
    pos = np.arange(N * D, dtype=float).reshape(N, D) * 3.0
    core.reset(seed=0, options={"positions": pos, "velocities": np.ones((N, D))})
    assert np.array_equal(core.q[0], pos) and np.all(core.p[0] == 1.0)
    before = core.q.copy()
    with pytest.raises(ValueError, match="positions"):
        core.reset(options={"positions": np.ones((N + 1, D))})
    with pytest.raises(ValueError, match="NaN"):
        core.reset(options={"velocities": np.full((N, D), np.nan)})
    assert np.array_equal(core.q, before)


def test_a_config_of_the_wrong_type_is_named_with_or_without_overrides():
    for overrides in ({}, {"n_uavs": 20}):  # a preset name given as the config
        with pytest.raises(TypeError, match=r"^config='paper' is invalid: .*preset='paper'"):
            PairFlockCore("paper", **overrides)
    with pytest.raises(TypeError, match=r"^config=3 is invalid: must be a PairFlockConfig"):
        PairFlockCore(3, n_uavs=20)


def test_step_before_reset_and_bad_actions_leave_state_unchanged(small_config):
    core = PairFlockCore(small_config)
    M, D = core.n_agents, small_config.dim
    with pytest.raises(RuntimeError, match="reset"):
        core.step(np.zeros((1, M, D)))
    core.reset(seed=0)
    core.step(np.zeros((1, M, D)))
    snapshot = (
        core.q.copy(),
        core.p.copy(),
        core.t.copy(),
        core.observe(),
        core.rngs[0].bit_generator.state,
    )
    bad = np.zeros((1, M, D))
    bad[0, 1, 0] = np.nan
    for a, exc in [
        (bad, ValueError),
        (np.zeros((1, M, D + 1)), ValueError),
        (np.zeros((1, M, D), dtype=bool), TypeError),
        (np.full((1, M, D), "x"), TypeError),
        (np.full((1, M, D), np.inf), ValueError),
    ]:
        with pytest.raises(exc):
            core.step(a)
    assert np.array_equal(core.q, snapshot[0]) and np.array_equal(core.p, snapshot[1])
    assert np.array_equal(core.t, snapshot[2]) and np.array_equal(core.observe(), snapshot[3])
    assert core.rngs[0].bit_generator.state == snapshot[4]


def test_out_of_range_actions_are_clipped_and_reported(small_config):
    cfg = small_config.replace(pair_accel_limit=10.0)
    a, b = PairFlockCore(cfg), PairFlockCore(cfg)
    a.reset(seed=1)
    b.reset(seed=1)
    M, D = a.n_agents, cfg.dim
    big = np.full((1, M, D), 5.0)
    ra = a.step(big)
    rb = b.step(np.ones((1, M, D)))
    assert np.array_equal(a.q, b.q)
    assert ra.info["action_clipped"].all() and not rb.info["action_clipped"].any()
    np.testing.assert_allclose(ra.info["pair_accel"], 10.0 * np.sqrt(D))


def test_divergence_ends_the_episode_without_nan_observations(small_config):
    core = PairFlockCore(small_config, num_swarms=2)
    res = core.reset(seed=[0, 1])
    M, D = core.n_agents, small_config.dim
    res = core.step(np.zeros((2, M, D)))
    last_obs = res.obs.copy()
    core.q[1, 3, 0] = np.nan  # a numerical blow-up in swarm 1
    res = core.step(np.zeros((2, M, D)))
    assert res.terminated.tolist() == [False, True]
    assert res.info["diverged"].tolist() == [False, True]
    assert np.all(np.isfinite(res.obs)) and np.all(np.isfinite(res.reward))
    assert np.array_equal(res.obs[1], last_obs[1])
    # runaway values count as divergence too
    cfg = small_config.replace(divergence_limit=200.0)
    core = PairFlockCore(cfg)
    core.reset(seed=0)
    core.q[0, 2] = 195.0  # flying outward fast, just inside the limit
    core.p[0, 2] = 50.0
    ended = False
    for _ in range(50):
        res = core.step(np.zeros((1, M, D)))
        if res.terminated[0]:
            ended = True
            break
    assert ended and res.info["diverged"][0] and np.isfinite(res.obs).all()


def test_truncation_after_the_episode_length(small_config):
    cfg = small_config.replace(max_cycles=5)
    core = PairFlockCore(cfg)
    core.reset(seed=0)
    flags = [bool(core.step(np.zeros((1, core.n_agents, cfg.dim))).truncated[0]) for _ in range(5)]
    assert flags == [False] * 4 + [True]
    assert core.t[0] == pytest.approx(5 * cfg.dt)


def test_partner_delay_shows_the_partners_old_state():
    cfg = make_config("paper", n_uavs=10, partner_delay=3)
    delayed = PairFlockCore(cfg)
    live = PairFlockCore(cfg.replace(partner_delay=0))
    delayed.reset(seed=2)
    live.reset(seed=2)
    L = delayed.layout
    history = [live.q[0, 1].copy()]
    push = np.full((1, 2, 2), 0.05)  # open loop: the delay changes what is seen, not physics
    for k in range(1, 8):
        rd, rl = delayed.step(push), live.step(push)
        assert np.array_equal(delayed.q, live.q)
        history.append(live.q[0, 1].copy())
        seen = L.get(rd.obs[0, 0], "partner_offset")
        expect = history[max(k - 3, 0)] - live.q[0, 0]
        np.testing.assert_allclose(seen, expect, rtol=1e-6, atol=1e-4)
        if k >= 2:  # the partner moves enough that live and delayed views differ
            assert np.abs(L.get(rl.obs[0, 0], "partner_offset") - seen).max() > 1e-3


def test_observation_noise_has_the_configured_spread():
    cfg = make_config("paper", n_uavs=6, obs_noise_position=0.2, obs_noise_velocity=0.05)
    noisy, clean = (
        PairFlockCore(cfg, num_swarms=64),
        PairFlockCore(cfg.replace(obs_noise_position=0.0, obs_noise_velocity=0.0), num_swarms=64),
    )
    rn, rc = noisy.reset(seed=3), clean.reset(seed=3)
    L = noisy.layout
    dq = L.get(rn.obs, "partner_offset") - L.get(rc.obs, "partner_offset")
    dv = L.get(rn.obs, "partner_velocity") - L.get(rc.obs, "partner_velocity")
    assert np.std(dq) == pytest.approx(0.2, rel=0.15)
    assert np.std(dv) == pytest.approx(0.05, rel=0.15)
    assert np.array_equal(rn.info["pair_distance"], rc.info["pair_distance"])  # infos are true


def test_disturbance_changes_the_flight_deterministically():
    cfg = make_config("paper", n_uavs=8, disturbance_std=2.0)
    runs = []
    for _ in range(2):
        core = PairFlockCore(cfg)
        core.reset(seed=5)
        for _ in range(10):
            core.step(np.zeros((1, 2, 2)))
        runs.append(core.q.copy())
    calm = PairFlockCore(cfg.replace(disturbance_std=0.0))
    calm.reset(seed=5)
    for _ in range(10):
        calm.step(np.zeros((1, 2, 2)))
    assert np.array_equal(runs[0], runs[1])
    assert not np.allclose(runs[0], calm.q)


def test_two_uavs_report_finite_infos_at_every_step():
    """Issue 28, 8(d): with no non-partner UAV (n_uavs = 2) min_separation is the largest
    finite separation, not inf, in the core and every view's infos."""

    cfg = make_config("paper", n_uavs=2)
    core = PairFlockCore(cfg, num_swarms=2)
    res = core.reset(seed=0)
    for _ in range(20):
        for v in res.info.values():
            assert np.all(np.isfinite(v))
        assert np.all(res.info["min_separation"] == separation_bound(cfg))
        res = core.step(np.zeros((2, 2, 2)))
    env = parallel_env(n_uavs=2, interface="pair")
    env.reset(seed=0)
    _, rew, *_, infos = env.step({a: np.zeros(2) for a in env.agents})
    assert all(np.isfinite(infos[a]["min_separation"]) for a in env.agents)
    assert all(np.isfinite(r) and r > -10 for r in rew.values())
