"""PettingZoo conformance (official checkers) and the bad-input matrix of the parallel env."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from pettingzoo.test import (
    api_test,
    max_cycles_test,
    parallel_api_test,
    parallel_seed_test,
    render_test,
)
from pettingzoo.test.state_test import state_test
from view_helpers import snapshot

import pairflock_env
from pairflock_env import env as aec_env
from pairflock_env import parallel_env


def test_parallel_api(small_kwargs):
    parallel_api_test(parallel_env(**small_kwargs, max_cycles=60), num_cycles=200)


def test_parallel_seed(small_kwargs):
    parallel_seed_test(lambda: parallel_env(**small_kwargs, max_cycles=60), num_cycles=100)


def test_aec_api(small_kwargs):
    api_test(aec_env(**small_kwargs, max_cycles=60), num_cycles=200)


def test_max_cycles():
    max_cycles_test(pairflock_env)


def test_render_rgb_array_headless(small_kwargs):
    def make(render_mode=None):
        return aec_env(**small_kwargs, max_cycles=60, render_mode=render_mode)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "human" on a headless backend warns and shows nothing
        render_test(make)
    env = parallel_env(**small_kwargs, render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    assert frame.std() > 5  # something is drawn
    env.close()


def test_module_entry_points_and_docs():
    env = parallel_env(preset="paper", n_uavs=20)
    assert env.config.n_uavs == 20 and env.possible_agents == ["uav_0", "uav_1"]
    doc = type(env).__doc__
    for field in env.layout.names:
        assert field in doc  # the observation table is generated from the layout
    assert "Action space" in doc and "Observation space" in doc
    assert callable(pairflock_env.raw_env)


def _snapshot(env):
    c = env.core
    return (
        c.q.copy(),
        c.p.copy(),
        c.t.copy(),
        c.steps.copy(),
        list(env.agents),
        c.rngs[0].bit_generator.state,
    )


def _same(a, b):
    return all(
        (np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y)
        for x, y in zip(a, b, strict=False)
    )


@pytest.mark.parametrize(
    "make_actions, exc, needle",
    [
        (lambda ok, D: {**ok, "uav_0": np.r_[np.nan, np.zeros(D - 1)]}, ValueError, "uav_0"),
        (lambda ok, D: {**ok, "uav_1": np.r_[np.zeros(D - 1), np.inf]}, ValueError, "uav_1"),
        (lambda ok, D: {**ok, "uav_0": np.zeros(D + 1)}, ValueError, "uav_0"),
        (lambda ok, D: {**ok, "uav_0": np.zeros((1, D))}, ValueError, "shape"),
        (lambda ok, D: {**ok, "uav_1": np.array(["a"] * D)}, TypeError, "uav_1"),
        (lambda ok, D: {**ok, "uav_1": np.arange(D) % 2 == 0}, TypeError, "dtype"),
        (lambda ok, D: {"uav_0": ok["uav_0"]}, ValueError, "uav_1"),
        (lambda ok, D: {**ok, "uav_7": np.zeros(D)}, ValueError, "uav_7"),
        (lambda ok, D: [ok["uav_0"], ok["uav_1"]], TypeError, "dict"),
        (lambda ok, D: {**ok, "uav_0": None}, TypeError, "uav_0"),
    ],
)
def test_bad_actions_raise_and_leave_the_env_unchanged(make_actions, exc, needle, small_kwargs):
    env = parallel_env(**small_kwargs)
    env.reset(seed=0)
    D = env.config.dim
    ok = {a: np.zeros(D, np.float32) for a in env.agents}
    env.step(ok)
    before = _snapshot(env)
    with pytest.raises(exc, match=needle):
        env.step(make_actions(ok, D))
    assert _same(before, _snapshot(env))
    env.step(ok)  # still usable


def test_clipping_is_documented_behaviour():
    env = parallel_env(preset="paper", n_uavs=12, pair_accel_limit=20.0)
    env.reset(seed=0)
    _, _, _, _, infos = env.step({"uav_0": np.array([3.0, -0.5]), "uav_1": np.zeros(2)})
    assert infos["uav_0"]["action_clipped"] and not infos["uav_1"]["action_clipped"]
    assert infos["uav_0"]["pair_accel"] == pytest.approx(np.hypot(20.0, 10.0))


def test_step_before_reset_and_after_the_end_raise(small_kwargs):
    env = parallel_env(**small_kwargs, max_cycles=2)
    D = env.config.dim
    with pytest.raises(RuntimeError, match="reset"):
        env.step({"uav_0": np.zeros(D), "uav_1": np.zeros(D)})
    env.reset(seed=1)
    for _ in range(2):
        *_, truncs, _ = env.step({a: np.zeros(D) for a in env.agents})
    assert all(truncs.values()) and env.agents == []
    with pytest.raises(RuntimeError, match="reset"):
        env.step({})


def test_infos_hold_the_documented_keys(small_kwargs):
    env = parallel_env(**small_kwargs)
    cfg = env.config
    _, infos = env.reset(seed=0)
    required = {
        "pair_distance",
        "pair_error",
        "sliding_surface",
        "min_separation",
        "sim_time",
        "collisions",
        "velocity_mismatch",
        "largest_component",
    }
    for a in env.agents:
        assert required <= set(infos[a])
    i0 = infos["uav_0"]
    d_m = cfg.d_m[0]
    dist = 2 * np.linalg.norm(np.broadcast_to(cfg.vector("pair_corner"), (cfg.dim,)))
    assert i0["pair_error"] == pytest.approx(i0["pair_distance"] - d_m)
    assert i0["pair_distance"] == pytest.approx(dist)  # paper: 180 sqrt(2)
    # s = c (||y||^2 - d_m^2) + 2 y.y' with y' = 0 at rest
    assert i0["sliding_surface"] == pytest.approx(cfg.surface_slope * (dist**2 - d_m**2))
    assert i0["sim_time"] == 0.0
    obs, *_, infos = env.step({a: np.zeros(cfg.dim) for a in env.agents})
    assert infos["uav_1"]["sim_time"] == pytest.approx(cfg.dt)
    np.testing.assert_allclose(
        env.layout.get(obs["uav_0"], "partner_offset"),
        -env.layout.get(obs["uav_1"], "partner_offset"),
    )


def test_invalid_render_mode():
    with pytest.raises(ValueError, match="render_mode"):
        parallel_env(render_mode="ascii")


# ------------------------------------------------------------------ state, spaces, clients
def test_state_and_state_space_follow_pettingzoo_state_test(small_kwargs):

    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)  # no "infinite state space" warning
        state_test(aec_env(**small_kwargs, max_cycles=30), parallel_env(**small_kwargs))
    env = parallel_env(**small_kwargs)
    with pytest.raises(RuntimeError, match="reset"):
        env.state()
    env.reset(seed=0)
    s = env.state()
    lay = env.state_layout
    assert s.dtype == np.float32 and s.shape == env.state_space.shape == (lay.size,)
    assert np.isfinite(env.state_space.low).all() and np.isfinite(env.state_space.high).all()
    lq, lp = env.core.leader_state()
    np.testing.assert_allclose(lay.get(s, "positions"), env.core.q[0] - lq[0], rtol=1e-6)
    np.testing.assert_allclose(lay.get(s, "velocities"), env.core.p[0] - lp[0], rtol=1e-6)
    assert lay.get(s, "time_fraction")[0] == 0.0
    assert "positions" in type(env).__doc__ and "time_fraction" in type(env).__doc__


@pytest.mark.parametrize(
    "extra",
    [
        {},
        {"obs_noise_position": 0.5, "obs_noise_velocity": 0.2, "partner_delay": 3},
        {"leader": "climb_and_turn", "leader_turns": ((0.1, 0.2, 90.0),), "pinning": 2},
        {"divergence_limit": 120.0, "pair_accel_limit": 2000.0},  # some swarms diverge
    ],
)
def test_observations_and_states_lie_in_their_bounded_spaces(extra, small_kwargs):
    """The physical observation space is finite and derived from the config; every emitted
    observation and state lies in it, also under noise, delay, a turning leader and
    divergence (full-throttle actions)."""
    env = parallel_env(**small_kwargs, max_cycles=40, **extra)
    space = env.observation_space("uav_0")
    assert np.isfinite(space.low).all() and np.isfinite(space.high).all()
    rng = np.random.default_rng(0)
    ended = 0
    for seed in range(3):
        obs, _ = env.reset(seed=seed)
        while env.agents:
            for a in env.agents:
                assert env.observation_space(a).contains(obs[a]), a
            assert env.state_space.contains(env.state())
            act = {a: rng.choice([-3.0, 3.0], env.config.dim) for a in env.agents}
            obs, rew, term, _, _ = env.step(act)
            assert all(env.reward_range[0] <= r <= 0 for r in rew.values())
            ended += any(term.values())
        for a in obs:
            assert env.observation_space(a).contains(obs[a])
    if "divergence_limit" in extra and env.config.dynamics == "particle":
        assert ended  # the bounds hold across divergence (last finite observation kept)


def test_raw_reward_scale_and_the_bounded_pair_interface():
    """The raw reward is metres of pair error per step (about -250 at the paper's start); the
    pair interface's reward is normalised and lies in its documented, finite range."""
    raw = parallel_env(n_uavs=12)
    raw.reset(seed=0)
    _, r_raw, *_ = raw.step({a: np.zeros(2) for a in raw.agents})
    assert r_raw["uav_0"] < -200
    env = parallel_env(n_uavs=12, interface="pair", max_cycles=60)
    low, high = env.reward_range
    assert np.isfinite(low) and high == 0.0
    obs, _ = env.reset(seed=0)
    assert env.observation_space("uav_0").shape == (env.interface.observation_size,)
    rng = np.random.default_rng(1)
    rewards = []
    while env.agents:
        for a in env.agents:
            assert env.observation_space(a).contains(obs[a])
            assert np.abs(obs[a]).max() <= 5.0
        obs, rew, _, _, infos = env.step({a: rng.uniform(-1, 1, 2) for a in env.agents})
        rewards += list(rew.values())
    assert all(low <= r <= high for r in rewards)
    assert max(abs(r) for r in rewards) < 10  # of order one, not hundreds
    assert infos["uav_0"]["sim_time"] == pytest.approx(0.6)  # 12 decisions of 5 control steps


def test_pair_interface_on_the_pettingzoo_api(small_kwargs):
    parallel_api_test(parallel_env(**small_kwargs, max_cycles=30, interface="pair"), 40)
    api_test(aec_env(**small_kwargs, max_cycles=30, interface="pair"), num_cycles=40)


def test_infos_hold_numbers_only_and_partners_are_an_env_property():
    env = parallel_env(n_uavs=12, pairs=((0, 1), (2, 3)))
    _, infos = env.reset(seed=0)
    for info in infos.values():
        for k, v in info.items():
            assert isinstance(v, (int, float, bool)), (k, v)
    assert infos["uav_2"]["partner_index"] == 3 and infos["uav_3"]["uav_index"] == 3
    assert env.partners == {"uav_0": "uav_1", "uav_1": "uav_0", "uav_2": "uav_3", "uav_3": "uav_2"}


# ------------------------------------------------------------------ AEC: per-step validation
def _aec_snapshot(e):

    return snapshot(e.env)  # the AEC env: its stored actions, selection and the parallel env


@pytest.mark.parametrize(
    "bad, exc",
    [
        (np.array([np.nan, 0.0]), ValueError),
        (np.array([0.0, np.inf]), ValueError),
        (np.zeros(3), ValueError),
        (np.array(["a", "b"]), TypeError),
        ("go", TypeError),
        (None, TypeError),
    ],
)
def test_aec_validates_each_action_at_its_own_step(bad, exc):
    e = aec_env(n_uavs=12)
    e.reset(seed=0)
    e.step(np.zeros(2))  # uav_0 acted; uav_1 is next
    before = _aec_snapshot(e)
    with pytest.raises(exc, match="uav_1"):
        e.step(bad)
    assert _aec_snapshot(e) == before
    e.step(np.zeros(2))  # the cycle completes normally
    assert e.agent_selection == "uav_0" and e.unwrapped.core.steps[0] == 1


def test_aec_lifecycle_errors_are_clear():
    e = aec_env(n_uavs=12, max_cycles=1)
    for call in (lambda: e.step(np.zeros(2)), e.state, lambda: e.observe("uav_0")):
        with pytest.raises(RuntimeError, match="reset"):
            call()
    with pytest.warns(UserWarning, match="render_mode"):  # as in every view (bad-input.md)
        assert e.render() is None
    e.reset(seed=0)
    e.step(np.zeros(2))
    e.step(np.zeros(2))  # the episode is truncated after one control step
    assert e.truncations["uav_0"]
    with pytest.raises(RuntimeError, match="ended"):
        e.step(np.zeros(2))  # a done agent is stepped with None
    e.step(None)
    e.step(None)
    assert e.agents == []
    with pytest.raises(RuntimeError, match="ended"):
        e.step(None)
    e.reset(seed=1)
    assert e.agents == ["uav_0", "uav_1"]
