"""The native SB3 VecEnv: DummyVecEnv's contract, SB3 wrappers, attributes, and the sb3: loader."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from pathlib import Path

import gymnasium as gym
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import DummyVecEnv, VecCheckNan, VecEnv, VecMonitor
from view_helpers import snapshot

import pairflock_env
from baselines import make_pair_policy
from baselines.controllers.sb3 import METADATA_KEY
from baselines.evaluation.rollout import rollout, trace_metrics
from pairflock_env import ENV_ID, make_config, parallel_env
from pairflock_env.envs import PairFlockSB3VecEnv, sb3

SMALL = dict(n_uavs=12, pair_accel_limit=50.0)


@pytest.mark.parametrize("interface", ["pair", "world"])
def test_native_vecenv_follows_dummy_vec_env_exactly(interface):
    """Rows b*M+m of the native VecEnv == agent m of sub-env b of a DummyVecEnv over the
    Gymnasium single env: observations, rewards, dones, terminal_observation and
    TimeLimit.truncated, through several auto-resets, with per-swarm seeds from seed()."""
    B, M, steps = 3, 2, 9
    cycles = 13 if interface == "pair" else 4  # pair: 3 decisions of 5 steps (the last cut short)
    kw = dict(SMALL, interface=interface, max_cycles=cycles)
    native = PairFlockSB3VecEnv(num_swarms=B, **kw)
    dummy = DummyVecEnv([lambda: gym.make(ENV_ID, **kw) for _ in range(B)])
    assert native.num_envs == B * M
    assert native.seed(21) == [21, 21, 22, 22, 23, 23]
    dummy.seed(21)
    on, od = native.reset(), dummy.reset()
    np.testing.assert_array_equal(on, od.reshape(B * M, -1))
    rng = np.random.default_rng(0)
    n_done = 0
    for _ in range(steps):
        a = rng.uniform(-1, 1, (B * M, 2)).astype(np.float32)
        on, rn, dn, infn = native.step(a)
        od, rd, dd, infd = dummy.step(a.reshape(B, M * 2))
        np.testing.assert_array_equal(on, od.reshape(B * M, -1))
        np.testing.assert_allclose(rn.reshape(B, M).mean(axis=1), rd, rtol=1e-6, atol=1e-6)
        np.testing.assert_array_equal(dn, np.repeat(dd, M))
        assert rn.dtype == np.float32 and dn.dtype == bool
        for i in range(B * M):
            b, m = divmod(i, M)
            assert infn[i]["TimeLimit.truncated"] == infd[b]["TimeLimit.truncated"]
            assert ("terminal_observation" in infn[i]) == ("terminal_observation" in infd[b])
            if "terminal_observation" in infn[i]:
                np.testing.assert_array_equal(
                    infn[i]["terminal_observation"],
                    infd[b]["terminal_observation"].reshape(M, -1)[m],
                )
        n_done += int(dd.sum())
    per_episode = -(-cycles // native.interface.decision_period)
    assert n_done == B * (steps // per_episode) and n_done >= 2 * B


def test_seed_matches_pettingzoo_and_options_apply_per_swarm():
    env = PairFlockSB3VecEnv(num_swarms=2, interface="world", **SMALL)
    env.seed(5)
    obs = env.reset().reshape(2, 2, -1)
    for b in range(2):
        po, _ = parallel_env(**SMALL).reset(seed=5 + b)
        np.testing.assert_array_equal(obs[b, 0], po["uav_0"])
        np.testing.assert_array_equal(obs[b, 1], po["uav_1"])
    q = np.zeros((12, 2))
    q[:, 0] = np.arange(12) * 3.0
    env.set_options([{"positions": q}] * 2 + [{}] * 2)
    env.reset()
    np.testing.assert_array_equal(env.core.q[0], q)
    assert not np.array_equal(env.core.q[1], q)
    env.set_options([{"positions": q}, {}, {}, {}])
    with pytest.raises(ValueError, match="rows of one swarm share"):
        env.reset()


def test_attributes_methods_and_bad_actions():
    env = PairFlockSB3VecEnv(num_swarms=2, render_mode="rgb_array", **SMALL)
    env.reset()
    assert env.get_attr("agent") == ["uav_0", "uav_1", "uav_0", "uav_1"]
    assert env.get_attr("swarm", indices=[1, 2]) == [0, 1]
    assert env.get_attr("np_random", indices=2)[0] is env.core.rngs[1]
    env.set_attr("curriculum_level", 3, indices=[0, 1])
    assert env.get_attr("curriculum_level", indices=[0, 1]) == [3, 3]
    with pytest.raises(AttributeError):
        env.get_attr("curriculum_level", indices=[2])
    with pytest.raises(AttributeError, match="read-only"):
        env.set_attr("config", None)
    st = env.env_method("swarm_state", indices=[3])[0]
    np.testing.assert_array_equal(st["positions"], env.core.q[1])
    frames = env.env_method("render", indices=[0])
    assert frames[0].ndim == 3
    assert env.get_images()[0].shape == frames[0].shape
    assert env.env_is_wrapped(gym.Wrapper) == [False] * 4
    assert env.has_attr("partner") and not env.has_attr("nope")
    q0 = env.core.q.copy()
    for bad, exc in [
        (np.full((4, 2), np.inf), ValueError),
        (np.zeros((2, 2)), ValueError),
        (np.array([["x", "y"]] * 4), TypeError),
    ]:
        with pytest.raises(exc, match="actions"):
            env.step(bad)
        np.testing.assert_array_equal(env.core.q, q0)
    with pytest.raises(ValueError, match="info_keys"):
        PairFlockSB3VecEnv(info_keys=["pair_eror"])
    with pytest.raises(IndexError):
        env.get_attr("agent", indices=[9])


def test_state_snapshot_continues_identically():
    env = PairFlockSB3VecEnv(num_swarms=2, seed=3, max_cycles=20, **SMALL)
    env.reset()
    a = np.full((4, 2), 0.3, np.float32)
    env.step(a)
    snap = env.get_state()
    first = [env.step(a) for _ in range(6)]
    env.set_state(snap)
    again = [env.step(a) for _ in range(6)]
    for x, y in zip(first, again, strict=False):
        np.testing.assert_array_equal(x[0], y[0])
        np.testing.assert_array_equal(x[1], y[1])
        np.testing.assert_array_equal(x[2], y[2])
    with pytest.raises(ValueError, match="different config"):
        PairFlockSB3VecEnv(num_swarms=2, n_uavs=13).set_state(snap)


def test_sb3_wrappers_and_ppo_train_on_native_vecenv():
    env = VecCheckNan(
        VecMonitor(PairFlockSB3VecEnv(num_swarms=2, max_cycles=30, info_keys="all", **SMALL)),
        raise_exception=True,
    )
    model = PPO("MlpPolicy", env, n_steps=16, batch_size=32, n_epochs=1, seed=0, device="cpu")
    model.learn(128)
    assert model.num_timesteps == 128
    _obs, _r, _d, infos = env.step(np.zeros((4, 2), np.float32))
    assert "pair_error" in infos[0] and "sim_time" in infos[0]


def test_sb3_loader_in_the_action_slot(tmp_path):
    """make_pair_policy("sb3:<path>", env) loads a model saved with its interface and acts on
    the env's standard observation; it holds its decision for decision_period steps."""

    venv = PairFlockSB3VecEnv(num_swarms=1, **SMALL)
    model = PPO("MlpPolicy", venv, n_steps=8, batch_size=16, n_epochs=1, seed=0, device="cpu")
    setattr(model, METADATA_KEY, {"algo": "PPO", "interface": venv.interface.to_dict()})
    path = tmp_path / "m.zip"
    model.save(path)
    cfg = make_config("paper", horizon=0.3, **SMALL)
    pol = make_pair_policy(f"sb3:{path}", cfg)
    pz = parallel_env(config=cfg)
    obs, _ = pz.reset(seed=0)
    act, _state = pol.predict(obs["uav_0"])
    assert act.shape == (2,) and act.dtype == np.float32 and np.all(np.abs(act) <= 1.0)
    batch = np.stack([obs["uav_0"], obs["uav_1"]])
    _, st = pol.predict(batch, episode_start=np.ones(2, bool))
    held = st[0].copy()
    for _ in range(4):  # decisions are held for 5 calls when the state is passed back
        _a1, st = pol.predict(batch, state=st, episode_start=np.zeros(2, bool))
        np.testing.assert_array_equal(st[0], held)
    rows = trace_metrics(rollout(cfg, pol, [0, 1]))
    assert len(rows) == 2 and np.isfinite(rows[0]["ss_mean_error"])
    with pytest.raises(FileNotFoundError):
        make_pair_policy("sb3:/no/such/model.zip", cfg)
    plain = tmp_path / "plain.zip"
    PPO("MlpPolicy", venv, n_steps=8, batch_size=16, device="cpu").save(plain)
    with pytest.raises(ValueError, match="not a pairflock model"):
        make_pair_policy(f"sb3:{plain}", cfg)
    with pytest.raises(ValueError, match="observes shape"):
        make_pair_policy(f"sb3:{path}", make_config("paper", dim=3, n_uavs=12))


def test_committed_policy_keeps_its_budget_in_the_paper_env():
    """models/pair_n20_a50.zip (the README's policy) loads, flies the paper preset whose env
    limit is 1000 m/s^2 and stays within the 50 m/s^2 it was trained for, and closes the pair."""

    model = Path(__file__).resolve().parents[1] / "models" / "pair_n20_a50.zip"
    cfg = make_config("paper", n_uavs=20, obs_neighbors=12, horizon=8.0)
    tr = rollout(cfg, make_pair_policy(f"sb3:{model}", cfg), [10000])
    assert np.linalg.norm(tr.u, axis=-1).max() <= 50.0 * (1 + 1e-6)  # float32 actions
    assert np.abs(tr.pair_error[0, :, -1]).max() < 0.5


def test_per_swarm_options_are_all_validated_before_any_swarm_resets():
    """Swarm 1's bad options raise before swarm 0 is reset (validate everything, then apply)."""

    env = PairFlockSB3VecEnv(num_swarms=2, **SMALL)
    env.reset()
    env.step(np.zeros((4, 2), np.float32))
    q = np.arange(24.0).reshape(12, 2) * 3.0
    for bad, exc in [
        (np.full((12, 2), np.nan), ValueError),
        (np.zeros((11, 2)), ValueError),
        ([["a", "b"]] * 12, TypeError),
    ]:
        opts = [{"positions": q}] * 2 + [{"positions": bad}] * 2
        before = snapshot(env)
        with pytest.raises(exc, match="row 2"):
            env.set_options(opts)  # checked where it is received
        assert snapshot(env) == before
        VecEnv.set_options(env, opts)  # stored unchecked, as SB3's own set_options does
        before = snapshot(env)
        with pytest.raises(exc, match="swarm 1"):
            env.reset()
        assert snapshot(env) == before
    with pytest.raises(ValueError, match="entries"):
        env.set_options([{}] * 3)
    env.set_options([{"positions": q}] * 2 + [{"velocities": np.ones((12, 2))}] * 2)
    env.reset()
    np.testing.assert_array_equal(env.core.q[0], q)
    np.testing.assert_array_equal(env.core.p[1], np.ones((12, 2)))


def test_names_say_what_they_count_and_old_names_are_gone():

    env = PairFlockSB3VecEnv(num_swarms=3, **SMALL)
    assert (env.num_swarms, env.num_rows, env.num_envs, env.agents_per_swarm) == (3, 6, 6, 2)
    vec = pairflock_env.PairFlockGymVectorEnv(num_envs=3, **SMALL)
    assert (vec.num_swarms, vec.num_rows, vec.num_envs) == (3, 3, 3)
    # no old name is kept alive before the first release (docs/changes.md)
    for module, old in ((sb3, "PairFlockVecEnv"), (pairflock_env, "PairFlockVectorEnv")):
        assert not hasattr(module, old)
    with pytest.raises(TypeError, match="'frame'"):
        PairFlockSB3VecEnv(num_swarms=1, frame="world", **SMALL)
    assert PairFlockSB3VecEnv(interface="world", **SMALL).interface_name == "world"
