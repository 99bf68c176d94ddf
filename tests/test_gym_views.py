"""Gymnasium views (single env and native vector env) and the learning interfaces."""

from __future__ import annotations

import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.env_checker import check_env as sb3_check

import pairflock_env
from pairflock_env import ENV_ID, make_config, parallel_env
from pairflock_env.core import PairFlockCore
from pairflock_env.envs.vector import PairFlockGymVectorEnv
from pairflock_env.interfaces import interface_from_dict, make_interface, pair_basis

SMALL = dict(n_uavs=12, pair_accel_limit=50.0)


def _check(env):
    with warnings.catch_warnings():
        # check_env builds a render_mode="human" copy: headless matplotlib warns, as it should
        warnings.filterwarnings("ignore", message=".*interactive matplotlib backend.*")
        check_env(env)


@pytest.mark.parametrize("interface", ["pair", "world"])
def test_registered_env_passes_gymnasium_check_env(interface):
    env = gym.make(ENV_ID, interface=interface, **SMALL)
    _check(env.unwrapped)
    assert np.isfinite(env.observation_space.low).all()
    assert np.isfinite(env.observation_space.high).all()
    obs, info = env.reset(seed=3)
    assert obs.shape == env.observation_space.shape and obs.dtype == np.float32
    assert env.action_space.shape == (2 * 2,)
    assert info["sim_time"] == 0.0 and info["pair_error"].shape == (2,)


def test_pair_frame_env_passes_sb3_check_env():

    env = gym.make(ENV_ID, **SMALL).unwrapped
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no SB3 warning either (flat obs, bounded box)
        sb3_check(env, warn=True)


def test_world_frame_single_env_matches_pettingzoo():
    """interface="world": the same physics, observation and (mean) reward as the PettingZoo
    env."""
    g = gym.make(ENV_ID, interface="world", **SMALL).unwrapped
    p = parallel_env(**SMALL)
    og, _ = g.reset(seed=7)
    op, _ = p.reset(seed=7)
    rng = np.random.default_rng(0)
    for _ in range(5):
        a = rng.uniform(-1, 1, (2, 2))
        og, rg, *_ = g.step(a.reshape(-1))
        op, rp, *_ = p.step({ag: a[m] for m, ag in enumerate(p.possible_agents)})
        np.testing.assert_array_equal(og.reshape(2, -1)[0], op["uav_0"])
        np.testing.assert_array_equal(og.reshape(2, -1)[1], op["uav_1"])
        assert rg == pytest.approx(np.mean(list(rp.values())))


def _rollout(env, actions, steps):
    out = []
    for t in range(steps):
        out.append(env.step(actions[t]))
    return out


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
def test_vector_entry_point_equals_sync_vector_env(mode):
    """make_vec through the native vector_entry_point == SyncVectorEnv of single envs, across
    episode ends (auto-reset) in both autoreset modes."""
    kw = dict(SMALL, max_cycles=12)  # 12 control steps = 3 decisions of 5 (last one cut short)
    native = gym.make_vec(
        ENV_ID, num_envs=3, vectorization_mode="vector_entry_point", autoreset_mode=mode, **kw
    )
    assert isinstance(native.unwrapped, PairFlockGymVectorEnv)
    sync = gym.make_vec(
        ENV_ID, num_envs=3, vectorization_mode="sync", vector_kwargs={"autoreset_mode": mode}, **kw
    )
    on, _ = native.reset(seed=11)
    os_, _ = sync.reset(seed=11)
    np.testing.assert_array_equal(on, os_)
    rng = np.random.default_rng(1)
    acts = rng.uniform(-1, 1, (9, *native.action_space.shape)).astype(np.float32)
    ended = 0
    for a in acts:
        rn = native.step(a)
        rs = sync.step(a)
        for x, y in zip(rn[:4], rs[:4], strict=False):
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-6)
        np.testing.assert_allclose(rn[4]["pair_error"], rs[4]["pair_error"], atol=1e-9)
        if mode == AutoresetMode.SAME_STEP and rn[3].any():
            for b in np.flatnonzero(rn[3]):
                np.testing.assert_allclose(rn[4]["final_obs"][b], rs[4]["final_obs"][b], atol=1e-6)
        ended += int(rn[3].sum())
    assert ended >= 3  # every sub-env went through at least one auto-reset


def test_vector_env_reset_mask_and_bad_actions_leave_state_unchanged():
    v = PairFlockGymVectorEnv(num_envs=2, **SMALL)
    _obs, _ = v.reset(seed=[4, 5])
    q0 = v.core.q.copy()
    for bad, exc in [
        (np.full((2, 4), np.nan), ValueError),
        (np.zeros((2, 3)), ValueError),
        (np.array([["a"] * 4] * 2), TypeError),
    ]:
        with pytest.raises(exc, match="actions"):
            v.step(bad)
        np.testing.assert_array_equal(v.core.q, q0)
    v.step(np.zeros((2, 4)))
    obs2, _ = v.reset(seed=[9, 9], options={"reset_mask": np.array([False, True])})
    single = gym.make(ENV_ID, **SMALL).unwrapped
    o_single, _ = single.reset(seed=9)
    np.testing.assert_array_equal(obs2[1], o_single)
    assert v.core.steps.tolist() == [5, 0]
    with pytest.raises(ValueError, match="reset_mask"):
        v.reset(options={"reset_mask": np.zeros(2, bool)})


def test_single_env_rejects_bad_input():
    env = gym.make(ENV_ID, **SMALL).unwrapped
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(4))
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(2, 2\), expected \(4,\)"):
        env.step(np.zeros((2, 2)))
    with pytest.raises(ValueError, match="seed"):
        env.reset(seed=-1)
    with pytest.raises(ValueError, match="interface"):
        gym.make(ENV_ID, interface="polar")
    with pytest.raises(TypeError, match="'frame'"):
        gym.make(ENV_ID, frame="pair")  # the old name of interface= is gone
    with pytest.raises(ValueError, match="w_error"):
        gym.make(ENV_ID, interface_params={"w_error": -1.0})
    with pytest.raises(ValueError, match=r"did you mean|Did you mean"):
        gym.make(ENV_ID, n_uav=20)


def test_single_env_episode_end_and_render():
    env = gym.make(ENV_ID, render_mode="rgb_array", max_cycles=7, **SMALL).unwrapped
    env.reset(seed=1)
    frame = env.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8
    _, _, term, trunc, info = env.step(np.zeros(4))
    assert not trunc and info["sim_time"] == pytest.approx(0.05)  # one decision = 5 x 0.01 s
    _, _, term, trunc, info = env.step(np.zeros(4))
    assert trunc and not term and info["sim_time"] == pytest.approx(0.07)  # cut at max_cycles
    with pytest.raises(RuntimeError, match="ended"):
        env.step(np.zeros(4))


# ------------------------------------------------------------------ learning interface
def test_pair_basis_is_orthonormal_and_flips_with_the_partner():
    rng = np.random.default_rng(0)
    for D in (2, 3):
        z = rng.normal(size=(50, D))
        R = pair_basis(z)
        np.testing.assert_allclose(
            R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(D), R.shape), atol=1e-12
        )
        np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
        np.testing.assert_allclose(R[:, 0], z / np.linalg.norm(z, axis=1, keepdims=True))
        Rb = pair_basis(-z)
        np.testing.assert_allclose(Rb[:, :2], -R[:, :2], atol=1e-12)  # A's frame = B's turned


def test_feedforward_makes_the_pair_a_double_integrator():
    """With the pair frame's decode, z'' = -accel_scale R^T (a_A + a_B) whatever the flocking
    terms are (eq. 23 with the observed flocking difference cancelled)."""
    cfg = make_config("paper", n_uavs=20, pair_accel_limit=1000.0, integrator="exact")
    core = PairFlockCore(cfg, num_swarms=1)
    res = core.reset(seed=[3])
    # put the pair inside the swarm so that the flocking terms on it are large
    q, p = core.q[0].copy(), core.p[0].copy()
    q[0], q[1] = q[5] + [1.5, 0.5], q[5] + [-2.0, 3.0]
    p[0], p[1] = [3.0, -1.0], [-2.0, 4.0]
    res = core.reset(seed=[3], options={"positions": q, "velocities": p})
    itf = make_interface("pair", cfg)
    flock = core.flock_accel[0, [0, 1]]
    assert np.abs(flock[1] - flock[0]).max() > 5.0
    a = np.array([[0.3, -0.2], [0.1, 0.4]])
    env_a = itf.decode(res.obs[0], a)
    z0, v0 = core.q[0, 1] - core.q[0, 0], core.p[0, 1] - core.p[0, 0]
    core.step(env_a[None])
    v1 = core.p[0, 1] - core.p[0, 0]
    R = pair_basis(z0)
    expected = -itf.params.accel_scale * R.T @ (a[0] + a[1])
    # exact up to the float32 observation of the flocking commands
    np.testing.assert_allclose((v1 - v0) / cfg.dt, expected, rtol=1e-6, atol=1e-4)
    # the applied acceleration vector never exceeds the limit in magnitude (not only per
    # axis: a box would allow sqrt(2) times more along a diagonal), direction kept
    ones = np.ones((2, 2))
    lay = itf.layout
    raw = itf.params.accel_scale * np.einsum(
        "mji,mj->mi", pair_basis(lay.get(res.obs[0], "partner_offset")), ones
    )
    raw += 0.5 * (lay.get(res.obs[0], "partner_flock_accel") - lay.get(res.obs[0], "flock_accel"))
    big = itf.decode(res.obs[0], ones)
    np.testing.assert_allclose(np.linalg.norm(big, axis=-1), 1.0, rtol=1e-12)
    np.testing.assert_allclose(big, raw / np.linalg.norm(raw, axis=-1, keepdims=True), rtol=1e-9)


def test_a_stored_interface_keeps_its_acceleration_limit_in_a_wider_env():
    """A policy trained at 50 m/s^2 stays within 50 m/s^2 when evaluated where the env allows
    1000 (the paper preset): the bound travels with the model."""
    trained = make_interface("pair", make_config("paper", n_uavs=20, pair_accel_limit=50.0))
    wide = make_config("paper", n_uavs=20)
    itf = interface_from_dict(trained.to_dict(), wide)
    core = PairFlockCore(wide, num_swarms=1)
    res = core.reset(seed=[0])
    u = itf.decode(res.obs[0], np.ones((2, 2))) * wide.pair_accel_limit
    np.testing.assert_allclose(np.linalg.norm(u, axis=-1), 50.0, rtol=1e-12)


def test_interface_encoding_is_bounded_finite_and_symmetric():
    cfg = make_config("paper", n_uavs=30, obs_neighbors=12, pair_accel_limit=50.0)
    itf = make_interface("pair", cfg)
    core = PairFlockCore(cfg, num_swarms=4)
    res = core.reset(seed=[0, 1, 2, 3])
    for _ in range(30):
        res = core.step(np.random.default_rng(0).uniform(-1, 1, (4, 2, 2)))
    enc = itf.encode(res.obs)
    assert enc.shape == (4, 2, itf.observation_size) and enc.dtype == np.float32
    assert np.isfinite(enc).all() and np.abs(enc).max() <= itf.observation_bound
    sl = {name: itf.features.slice(name) for name in itf.features.names}
    # both members see the same pair error and the same relative velocity in their frames
    np.testing.assert_allclose(enc[:, 0, sl["error"]], enc[:, 1, sl["error"]], atol=1e-6)
    np.testing.assert_allclose(
        enc[:, 0, sl["rel_velocity"]], enc[:, 1, sl["rel_velocity"]], atol=1e-6
    )
    # neighbours are ranked by distance at closest approach
    miss = enc[..., sl["neighbor_miss"]]
    mask = enc[..., sl["neighbor_mask"]] > 0
    assert np.all(np.diff(np.where(mask, miss, np.inf), axis=-1) >= -1e-6)
    d = itf.to_dict()
    again = interface_from_dict(d, cfg)
    np.testing.assert_array_equal(again.encode(res.obs), enc)
    with pytest.raises(ValueError, match="unknown pair-interface parameter"):
        make_interface("pair", cfg, w_eror=1.0)
    with pytest.raises(ValueError, match="threat_neighbors"):
        make_interface("pair", make_config("paper", obs_neighbors=3), threat_neighbors=6)
    with pytest.raises(ValueError, match="observation has shape"):
        itf.encode(np.zeros((2, 5)))


def test_import_stays_light():
    code = (
        "import sys, pairflock_env, gymnasium; gymnasium.spec('pairflock/PairFlock-v0'); "
        "print('torch' in sys.modules, 'stable_baselines3' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]
    assert pairflock_env.ENV_ID in gym.registry


def test_learning_views_fly_the_quadrotor():
    """The Gymnasium env (pair frame, 3-D) passes check_env on the quadrotor preset, and the
    native vector env steps it: the learning views are not particle-only."""
    env = gym.make(ENV_ID, preset="paper-quadrotor", max_cycles=20)
    _check(env.unwrapped)
    assert env.action_space.shape == (2 * 3,)
    envs = gym.make_vec(
        ENV_ID,
        num_envs=2,
        vectorization_mode="vector_entry_point",
        preset="paper-quadrotor",
        max_cycles=20,
    )
    obs, _ = envs.reset(seed=0)
    for _ in range(25):  # across an auto-reset
        obs, r, _term, _trunc, info = envs.step(envs.action_space.sample())
        assert np.isfinite(obs).all() and np.isfinite(r).all()
    assert not info["crashed"].any()


def test_pair_reward_is_finite_without_any_other_uav():
    """n_uavs=2: no non-partner UAV, so min_separation is inf; the cohesion term must not turn
    that into an infinite reward (it gave -inf before)."""
    env = gym.make(ENV_ID, n_uavs=2, max_cycles=20).unwrapped
    env.reset(seed=0)
    _, r, *_ = env.step(np.zeros(4))
    low, high = env.reward_range
    assert np.isfinite(r) and low <= r <= high
