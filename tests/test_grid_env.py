"""The neighbour search of the core (``neighbor_search``): the grid and all pairs give the
same episodes, "auto" keeps small swarms on all pairs, and large swarms start sensibly."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from pairflock_env import PairFlockCore, make_config, parallel_env
from pairflock_env.config.sections.initial_state import START_HALF_WIDTH, START_UAVS
from pairflock_env.config.sections.swarm import GRID_MIN_UAVS
from pairflock_env.render import CROWD_UAVS, SwarmRenderer, crowd_scale
from pairflock_env.swarm.placement import pinning_mask

#: distance within which the two searches' trajectories must agree (m)
TRAJECTORY_TOL = 1e-9


def run(search: str, steps: int, seed: int, **overrides):
    """Positions, velocities, rewards and infos of every step under random actions."""
    cfg = make_config("paper", neighbor_search=search, max_cycles=10 * steps, **overrides)
    core = PairFlockCore(cfg, num_swarms=2, seed=seed)
    first = core.reset()
    rng = np.random.default_rng(seed)
    out = [(core.q.copy(), core.p.copy(), first)]
    for _ in range(steps):
        res = core.step(rng.uniform(-1.0, 1.0, (2, core.n_agents, cfg.dim)))
        out.append((core.q.copy(), core.p.copy(), res))
    return core, out


def test_grid_and_all_pairs_give_the_same_episode():
    """N = 300, 200 steps of random actions, two swarms, three pairs: same trajectories
    (within TRAJECTORY_TOL), observations, rewards, flags and infos."""
    kw = dict(n_uavs=300, init="random", pairs=((0, 1), (7, 150), (298, 299)), pinning=20)
    steps = 200
    grid_core, grid = run("grid", steps, seed=4, **kw)
    pairs_core, pairs = run("all_pairs", steps, seed=4, **kw)
    assert grid_core.neighbor_grid is not None and pairs_core.neighbor_grid is None
    moved = np.abs(pairs[-1][0] - pairs[0][0]).max()
    assert moved > 1.0  # the swarms did fly
    for (qg, pg, rg), (qa, pa, ra) in zip(grid, pairs, strict=True):
        assert np.abs(qg - qa).max() <= TRAJECTORY_TOL
        assert np.abs(pg - pa).max() <= TRAJECTORY_TOL
        np.testing.assert_allclose(rg.obs, ra.obs, rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(rg.reward, ra.reward, rtol=1e-9, atol=1e-9)
        assert (rg.terminated == ra.terminated).all() and (rg.truncated == ra.truncated).all()
        assert rg.info.keys() == ra.info.keys()
        for key in ra.info:
            np.testing.assert_allclose(
                np.asarray(rg.info[key], float), np.asarray(ra.info[key], float), 1e-9, 1e-9
            )


def test_auto_picks_all_pairs_for_small_swarms_and_the_grid_for_large():
    below, at = GRID_MIN_UAVS - 1, GRID_MIN_UAVS
    assert not make_config("paper", n_uavs=below).uses_grid
    assert make_config("paper", n_uavs=at).uses_grid
    assert make_config("paper", n_uavs=below, neighbor_search="grid").uses_grid
    assert not make_config("paper", n_uavs=at, neighbor_search="all_pairs").uses_grid
    assert PairFlockCore(make_config("paper")).neighbor_grid is None
    with pytest.raises(ValueError, match="neighbor_search"):
        make_config("paper", neighbor_search="cells")


def test_start_box_grows_with_the_swarm_unless_set():
    assert make_config("paper", n_uavs=START_UAVS).swarm_half_width == START_HALF_WIDTH
    big = 4 * START_UAVS
    for dim in (2, 3):
        w = make_config("paper", n_uavs=big, dim=dim).swarm_half_width
        assert w == pytest.approx(START_HALF_WIDTH * 4 ** (1 / dim))
    assert make_config("paper", n_uavs=big, swarm_half_width=80.0).swarm_half_width == 80.0
    # the box follows n_uavs through replace() too, and a set value stays
    cfg = make_config("paper").replace(n_uavs=big)
    assert cfg.swarm_half_width > START_HALF_WIDTH


def test_pinning_to_the_k_nearest_is_the_stable_sort():
    cfg = make_config("paper", n_uavs=60, pinning=9)
    rng = np.random.default_rng(1)
    q = np.round(rng.uniform(-3.0, 3.0, (60, 2)))  # many ties in distance
    leader = np.array([0.5, 0.0])
    want = np.zeros(60)
    want[np.argsort(np.linalg.norm(q - leader, axis=1), kind="stable")[:9]] = 1.0
    assert (pinning_mask(cfg, q, leader) == want).all()


def test_ten_thousand_uavs_just_work():
    """parallel_env(n_uavs=10_000) with defaults: placed min_init_spacing apart in a box
    grown with N, on the grid, and it steps."""
    env = parallel_env(n_uavs=10_000)
    env.reset(seed=0)
    core, cfg = env.core, env.config
    assert cfg.swarm_half_width > START_HALF_WIDTH
    assert core.neighbor_grid is not None and core.neighbor_grid.ok.all()
    flock = core._neighbors.flock_out
    unpaired = core.partner_of < 0
    assert np.sqrt(flock["min_d2"][0, unpaired].min()) >= cfg.min_init_spacing
    obs, _, term, trunc, _ = env.step({a: np.zeros(2, np.float32) for a in env.agents})
    assert all(np.isfinite(o).all() for o in obs.values())
    assert not any(term.values()) and not any(trunc.values())


def test_a_frame_of_ten_thousand_uavs():
    """Rendering is O(N): a frame of 10,000 UAVs draws, markers shrink for crowded swarms
    (pairs keep the uncrowded size) and swarms up to CROWD_UAVS are drawn as before."""

    assert crowd_scale(CROWD_UAVS) == 1.0 and crowd_scale(4 * CROWD_UAVS) == 0.5
    rng = np.random.default_rng(0)
    q, p = rng.uniform(-500.0, 500.0, (10_000, 2)), rng.normal(size=(10_000, 2))
    frame = SwarmRenderer(((0, 1), (2, 3)), 5.0, "rgb_array").rgb_array(q, p, np.zeros(2))
    assert frame.ndim == 3 and frame.dtype == np.uint8 and frame.std() > 0


def _peak_bytes(n_uavs: int) -> int:
    """Peak of numpy's traced allocations while building, resetting and stepping a core."""

    tracemalloc.start()
    core = PairFlockCore(make_config("paper", n_uavs=n_uavs), seed=0)
    core.reset()
    core.step(np.zeros((1, core.n_agents, 2)))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def test_memory_grows_linearly_with_the_swarm():
    """Four times the UAVs: about four times the memory (an N x N array would be 16x)."""
    small = GRID_MIN_UAVS * 4
    factor = 4
    _peak_bytes(small)  # compile and import outside the measurement
    ratio = _peak_bytes(factor * small) / _peak_bytes(small)
    assert ratio < 1.5 * factor
