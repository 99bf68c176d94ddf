"""The pieces the core is built from, each on its own: placement and pinning, the partner
delay buffer, the observation builder, step results and infos, reward and episode end, and
the stages of a step."""

from __future__ import annotations

import numpy as np
import pytest

from pairflock_env import PairFlockCore, make_config
from pairflock_env.safety import NoFilterStage
from pairflock_env.swarm import placement
from pairflock_env.swarm.placement import initial_state, pinning_mask
from pairflock_env.task.delay import PartnerDelayBuffer
from pairflock_env.task.infos import (
    AGENT_INFO_KEYS,
    FLOCK_INFO_KEYS,
    LIVE_INFO_KEYS,
    PAIR_INFO_KEYS,
    SWARM_INFO_KEYS,
    hold_last_finite,
    make_info,
)
from pairflock_env.task.observations import ObsLayout
from pairflock_env.task.pairing import agent_pair_state, pair_error, sliding_surface
from pairflock_env.task.rewards import DIVERGENCE_PENALTY, episode_end, reward_terms, total_reward


# --------------------------------------------------------------------------- placement
def test_placement_is_a_pure_function_of_config_and_generator(small_config):
    cfg = small_config
    agents = np.asarray(cfg.pairs).reshape(-1)
    q1, p1 = initial_state(cfg, np.random.default_rng(4), agents)
    q2, _ = initial_state(cfg, np.random.default_rng(4), agents)
    np.testing.assert_array_equal(q1, q2)
    assert np.all(p1 == 0.0) and q1.shape == p1.shape == (cfg.n_uavs, cfg.dim)
    core = PairFlockCore(cfg)
    core.reset(seed=[np.random.SeedSequence(9)])
    q3, _ = initial_state(cfg, np.random.default_rng(np.random.SeedSequence(9)), agents)
    np.testing.assert_array_equal(core.q[0], q3)  # the core places swarms with it


def test_random_placement_keeps_the_spacing_and_the_box():
    cfg = make_config("paper", n_uavs=30, init="random", min_init_spacing=3.0)
    agents = np.asarray(cfg.pairs).reshape(-1)
    q, _ = initial_state(cfg, np.random.default_rng(0), agents)
    d = np.linalg.norm(q[:, None] - q[None], axis=-1) + np.diag(np.full(30, np.inf))
    assert d.min() >= 3.0
    half = np.where(
        np.isin(np.arange(30), agents)[:, None],
        cfg.vector("pair_corner"),
        cfg.vector("swarm_half_width"),
    )
    assert np.all(np.abs(q - cfg.vector("swarm_center")) <= half)


def test_placement_that_gives_up_names_the_spacing(monkeypatch):
    # the config rejects what it can tell is impossible; placement still gives up cleanly
    # when its redraws run out
    cfg = make_config("paper", n_uavs=40, init="random", min_init_spacing=3.0)
    monkeypatch.setattr(placement, "MAX_PLACEMENT_ROUNDS", 0)
    with pytest.raises(ValueError, match="min_init_spacing"):
        initial_state(cfg, np.random.default_rng(0), np.asarray(cfg.pairs).reshape(-1))


def test_pinning_mask_variants():
    q = np.array([[5.0, 0.0], [1.0, 0.0], [3.0, 0.0], [1.0, 0.0]])
    leader = np.zeros(2)
    cfg = make_config("paper", n_uavs=4, pinning="all")
    assert pinning_mask(cfg, q, leader).tolist() == [1.0] * 4
    cfg = make_config("paper", n_uavs=4, pinning=2)  # the two nearest, ties by index
    assert pinning_mask(cfg, q, leader).tolist() == [0.0, 1.0, 0.0, 1.0]
    cfg = make_config("paper", n_uavs=4, pinning=0)
    assert pinning_mask(cfg, q, leader).tolist() == [0.0] * 4
    cfg = make_config("paper", n_uavs=4, pinning=(0, 2))
    assert pinning_mask(cfg, q, leader).tolist() == [1.0, 0.0, 1.0, 0.0]


# --------------------------------------------------------------------------- delay
def test_delay_buffer_returns_the_partner_sample_of_d_steps_ago():
    B, M, D, d = 2, 4, 3, 2
    buf = PartnerDelayBuffer(d, B, M, D, np.arange(M) ^ 1)
    rng = np.random.default_rng(0)
    hist = [rng.normal(size=(3, B, M, D))]
    got = buf.push(hist[0], reset_rows=np.arange(B))
    np.testing.assert_array_equal(got, hist[0][:, :, [1, 0, 3, 2]])  # the reset fill
    for k in range(1, 7):
        hist.append(rng.normal(size=(3, B, M, D)))
        got = buf.push(hist[k])
        np.testing.assert_array_equal(got, hist[max(k - d, 0)][:, :, [1, 0, 3, 2]])
    # a reset between steps: no time passes for the other rows (their sample is the
    # latest one again), the reset row's whole history becomes its new sample
    last_read = got.copy()
    fresh = hist[-1].copy()
    fresh[:, 1] = rng.normal(size=(3, M, D))
    got = buf.push(fresh, reset_rows=np.array([1]))
    np.testing.assert_array_equal(got[:, 1], fresh[:, 1][:, [1, 0, 3, 2]])
    np.testing.assert_array_equal(got[:, 0], last_read[:, 0])
    hist.append(rng.normal(size=(3, B, M, D)))
    got = buf.push(hist[-1])
    np.testing.assert_array_equal(got[:, 1], fresh[:, 1][:, [1, 0, 3, 2]])
    np.testing.assert_array_equal(got[:, 0], hist[-1 - d][:, 0][:, [1, 0, 3, 2]])


def test_delay_buffer_needs_a_positive_delay():
    with pytest.raises(ValueError, match="delay"):
        PartnerDelayBuffer(0, 1, 2, 2, np.array([1, 0]))


# --------------------------------------------------------------------------- observation
def test_the_layout_fills_every_field_by_name():
    lay = ObsLayout(2, 3)
    B, M = 2, 4
    rng = np.random.default_rng(1)
    fields = {f.name: rng.normal(size=(B, M, *f.shape)) for f in lay}
    fields["target_distance"] = np.arange(M, dtype=float)[None, :, None]  # broadcast over B
    obs = lay.fill((B, M), fields)
    assert obs.shape == (B, M, lay.size) and obs.dtype == np.float32
    for f in lay:
        want = np.broadcast_to(fields[f.name], (B, M, *f.shape)).astype(np.float32)
        np.testing.assert_array_equal(lay.get(obs, f.name), want)
    del fields["leader_velocity"]
    with pytest.raises(KeyError, match="leader_velocity"):
        lay.fill((B, M), fields)


def test_layout_without_neighbours_ignores_their_values():
    lay = ObsLayout(2, 0)
    assert "neighbor_offsets" not in lay
    fields = {f.name: np.zeros((1, 2, *f.shape)) for f in ObsLayout(2, 3)}
    assert lay.fill((1, 2), fields).shape == (1, 2, lay.size)


# --------------------------------------------------------------------------- pair state
def test_agent_pair_state_matches_the_pairing_formulas():
    rng = np.random.default_rng(2)
    q, p = rng.normal(size=(2, 3, 6, 2))
    ia, ip = np.array([0, 1, 4, 5]), np.array([1, 0, 5, 4])
    dm = np.array([2.0, 2.0, 3.0, 3.0])
    st = agent_pair_state(q, p, ia, ip, dm, 0.7)
    y, yd = q[:, ip] - q[:, ia], p[:, ip] - p[:, ia]
    np.testing.assert_array_equal(st["offset"], y)
    np.testing.assert_allclose(st["pair_error"], pair_error(y, dm), rtol=1e-14)
    np.testing.assert_allclose(st["sliding_surface"], sliding_surface(y, yd, dm, 0.7))
    # both members of a pair see the same distance and surface
    np.testing.assert_array_equal(st["pair_distance"][:, 0], st["pair_distance"][:, 1])
    np.testing.assert_allclose(st["sliding_surface"][:, 2], st["sliding_surface"][:, 3])


# --------------------------------------------------------------------------- results
def _info(B=2, M=2, D=2, value=1.0):
    pair = {k: np.full((B, M), value) for k in PAIR_INFO_KEYS}
    flock = {k: np.full(B, value) for k in FLOCK_INFO_KEYS}
    terms = {"error": np.full((B, M), -value)}
    u = np.full((B, M, D), 3.0)
    safety = NoFilterStage(None, np.arange(M), B).info()
    return make_info(
        pair, flock, u, np.zeros((B, M), bool), np.full(B, 0.5), np.zeros(B, bool), terms, safety
    )


def test_make_info_holds_every_documented_key_in_order():
    info = _info()
    assert list(info) == [*AGENT_INFO_KEYS, *SWARM_INFO_KEYS, "reward_error"]
    np.testing.assert_allclose(info["pair_accel"], 3.0 * np.sqrt(2.0))
    assert info["sim_time"].tolist() == [0.5, 0.5]


def test_hold_last_finite_keeps_live_keys_current():
    last, now = _info(value=1.0), _info(value=np.inf)
    now["sim_time"][:] = 9.0
    rows = np.array([False, True])
    hold_last_finite(now, last, rows)
    for k, v in now.items():
        if k in LIVE_INFO_KEYS:
            continue
        np.testing.assert_array_equal(v[1], last[k][1], err_msg=k)
        assert np.all(np.isinf(v[0])), k  # other rows untouched
    assert now["sim_time"].tolist() == [9.0, 9.0]
    first = _info(value=np.nan)
    hold_last_finite(first, None, rows)  # no previous step: zeros
    assert first["pair_distance"][1].tolist() == [0.0, 0.0]


def test_reward_and_episode_end():
    cfg = make_config("paper", n_uavs=6, collision_distance=0.5, terminate_on_collision=True)
    err = np.array([[1.0, -2.0]])
    u = np.array([[[cfg.pair_accel_limit, 0.0], [0.0, 0.0]]])
    sep = np.array([[0.25, 5.0]])
    terms = reward_terms(cfg, err, u, sep)
    r = total_reward(terms)
    np.testing.assert_allclose(r, sum(terms.values()))
    assert terms["collision"][0].tolist() == [-cfg.reward_collision_weight, 0.0]
    steps = np.array([cfg.episode_steps])
    term, trunc = episode_end(cfg, np.array([False]), {}, sep, steps)
    assert term.tolist() == [True] and trunc.tolist() == [False]  # a collision ends it
    far = np.array([[5.0, 5.0]])
    term, trunc = episode_end(cfg, np.array([False]), {}, far, steps)
    assert term.tolist() == [False] and trunc.tolist() == [True]
    crashed = {"vehicle_terminated": np.array([True])}
    term, _ = episode_end(cfg, np.array([False]), crashed, far, steps - 1)
    assert term.tolist() == [True]
    assert DIVERGENCE_PENALTY > 0


# --------------------------------------------------------------------------- step stages
def test_decode_stage_is_the_pair_command_and_changes_nothing(small_config):
    core = PairFlockCore(small_config.replace(pair_accel_limit=8.0))
    core.reset(seed=1)
    M, D = core.n_agents, small_config.dim
    a = np.linspace(-2.0, 2.0, M * D).reshape(1, M, D)
    q = core.q.copy()
    u, clipped = core.decode_actions(core.check_actions(a))
    np.testing.assert_array_equal(u, np.clip(a, -1, 1) * 8.0)
    assert clipped.tolist() == np.any(np.abs(a) > 1, axis=-1).tolist()
    np.testing.assert_array_equal(core.q, q)
    res = core.step(a)  # the step applies exactly that command
    np.testing.assert_array_equal(res.info["pair_accel"], np.linalg.norm(u, axis=-1))
