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
