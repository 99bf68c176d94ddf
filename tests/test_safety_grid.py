"""The safety filter with the neighbour grid: each agent takes its candidates from the grid
(O(M k) per swarm) and gets exactly the result of the scan of all N, in the filter alone and
in the core (grid against all-pairs search), with fall-backs for swarms the grid cannot hold."""

from __future__ import annotations

import numpy as np
import pytest

from baselines import make_pair_policy
from pairflock_env import PairFlockCore, make_config
from pairflock_env.safety import SafetyFilter, SafetyParams
from pairflock_env.safety.cbf.kernels import BARRIER, _far_radius, _far_terms, _with_partner
from pairflock_env.swarm.grid import NeighborGrid


def _case(rng, B, N, D, spread):
    q = rng.uniform(-spread, spread, (B, N, D))
    p = rng.normal(0.0, 15.0, (B, N, D))
    return q, p


@pytest.mark.parametrize("D", [2, 3])
@pytest.mark.parametrize(
    "kw",
    [
        dict(sensing_radius=6.0),
        dict(sensing_radius=25.0),
        dict(sensing_radius=1e5, reaction_time=0.1),  # the grid falls back
        dict(sensing_radius=40.0, decay=1.0),
    ],
)
def test_grid_gives_the_full_scan_bit_for_bit(D, kw):
    rng = np.random.default_rng(17 + D)
    B, N = 5, 300  # enough UAVs that most queries take the grid (fewer cells than UAVs)
    P = SafetyParams(accel_limit=80.0, dt=0.01, **kw)
    agents = np.array([0, 1, 2, 3, 10, 11])
    partners = np.array([1, 0, 3, 2, 11, 10])
    filt = SafetyFilter(P, agents, N, partners)
    every = SafetyFilter(P, agents, N, partners)
    every._pr[BARRIER.index.skip_far] = (
        0.0  # the far-UAV skip off: the same commands and flags on the grid too
    )
    for spread in (8.0, 30.0, 200.0):  # dense, medium, partners far apart
        q, p = _case(rng, B, N, D, spread)
        q[0, 5] = q[0, 0]  # a coincident pair
        q[1, 1] = q[1, 0] + 150.0  # a partner far outside the sensing radius
        p[2, 7] = np.inf  # a non-finite swarm: the grid is not used there
        f = rng.normal(0.0, 5.0, (B, agents.size, D))
        un = rng.normal(0.0, 60.0, (B, agents.size, D))
        for cell in (1.0, 4.0):  # cells much smaller than the ranges, and larger
            grid = NeighborGrid(B, N, D, cell_size=cell).build(q)
            scan = filt.apply(q, p, f, un)
            fast = filt.apply(q, p, f, un, grid=grid)
            for a, b in zip(scan.arrays(), fast.arrays(), strict=True):
                np.testing.assert_array_equal(a, b)
            unskipped = every.apply(q, p, f, un, grid=grid)
            for a, b in zip(fast.arrays()[:4], unskipped.arrays()[:4], strict=True):
                np.testing.assert_array_equal(a, b)
            assert scan.active[:, :].any()


@pytest.mark.parametrize("D", [2, 3])
def test_the_grid_query_shortened_by_the_skip_gives_the_scan_bit_for_bit(D):
    """A slow, dense swarm and a long sensing radius: each agent's grid query stops where the
    far-UAV skip takes every UAV at the swarm's largest speed (well inside R_s), and the
    filter still gives the scan's outputs bit for bit, near the shortened radius too."""
    rng = np.random.default_rng(40 + D)
    B, N = 4, 400
    P = SafetyParams(accel_limit=50.0, dt=0.01, sensing_radius=80.0)
    agents, partners = np.array([0, 1, 5, 6]), np.array([1, 0, 6, 5])
    filt = SafetyFilter(P, agents, N, partners)
    shortened = 0
    for speed in (0.3, 3.0, 30.0):
        q = rng.uniform(-40.0, 40.0, (B, N, D))
        p = rng.normal(0.0, speed, (B, N, D))
        p[:, agents] *= 10.0  # the paired UAVs close faster
        f = rng.normal(0.0, 2.0, (B, agents.size, D))
        un = rng.normal(0.0, 50.0, (B, agents.size, D))
        grid = NeighborGrid(B, N, D, cell_size=4.0).build(q)
        scan = filt.apply(q, p, f, un)
        fast = filt.apply(q, p, f, un, grid=grid)
        for a, b in zip(scan.arrays(), fast.arrays(), strict=True):
            np.testing.assert_array_equal(a, b)
        vmax = np.linalg.norm(p, axis=-1).max(axis=1)
        for b in range(B):
            for m, i in enumerate(agents):
                fn = float(np.linalg.norm(f[b, m]))
                Wm = (np.linalg.norm(p[b, i]) + vmax[b]) * (1 + 1e-9)
                r = max(_far_radius(Wm, _far_terms(filt._pr, fn, c)) for c in (False, True))
                shortened += r < P.sensing_radius
    assert shortened > 10


def test_grid_must_be_built_from_the_positions_given():
    rng = np.random.default_rng(3)
    q, p = _case(rng, 2, 10, 2, 10.0)
    filt = SafetyFilter(SafetyParams(accel_limit=10.0), [0, 1], 10, [1, 0])
    f = np.zeros((2, 2, 2))
    other = NeighborGrid(2, 10, 2, cell_size=2.0).build(q + 1.0)
    with pytest.raises(ValueError, match="grid is invalid: it must be built from the positions"):
        filt.apply(q, p, f, f, grid=other)
    with pytest.raises(ValueError, match="grid is invalid"):
        filt.apply(q, p, f, f, grid=NeighborGrid(2, 10, 2, cell_size=2.0))  # never built
    with pytest.raises(TypeError, match=r"grid=.* is invalid: must be a NeighborGrid or None"):
        filt.apply(q, p, f, f, grid=object())
    # a copy of the same positions is accepted and gives the scan's result
    same = NeighborGrid(2, 10, 2, cell_size=2.0).build(q.copy())
    a, b = filt.apply(q, p, f, f), filt.apply(q, p, f, f, grid=same)
    np.testing.assert_array_equal(a.u, b.u)


@pytest.mark.parametrize("policy", ["smc", "proportional"])
def test_core_with_the_grid_flies_the_all_pairs_trajectories(policy):
    """Grid and all-pairs search with the filter on: the same states, commands and infos
    for 150 steps of 3 swarms (a 150-UAV swarm with 6 pairs drawn anywhere)."""
    kw = dict(
        n_uavs=150,
        pairs=tuple((2 * k, 2 * k + 1) for k in range(6)),
        init="random",
        pair_corner=40.0,
        safety_filter="cbf",
        safety_sensing_radius=60.0,
    )
    cores = {
        s: PairFlockCore(make_config("paper", neighbor_search=s, **kw), num_swarms=3)
        for s in ("all_pairs", "grid")
    }
    assert cores["grid"].neighbor_grid is not None and cores["all_pairs"].neighbor_grid is None
    pol = make_pair_policy(policy, cores["grid"].config)
    res = {s: c.reset(seed=[5, 6, 7]) for s, c in cores.items()}
    active = 0
    for _ in range(150):
        obs = res["grid"].obs
        a, _ = pol.predict(obs.reshape(-1, obs.shape[-1]), deterministic=True)
        a = a.reshape(obs.shape[0], obs.shape[1], -1)
        res = {s: c.step(a) for s, c in cores.items()}
        for k in ("safety_active", "safety_correction", "safety_infeasible"):
            np.testing.assert_array_equal(res["grid"].info[k], res["all_pairs"].info[k])
        np.testing.assert_array_equal(cores["grid"].q, cores["all_pairs"].q)
        active += int(res["grid"].info["safety_active"].sum())
    assert active > 0  # the filter had work to do


def test_the_grid_is_really_consulted():
    """White box: a UAV moved next to an agent after the grid was built (in place, so the
    grid still holds the same array) is missed by the grid path and seen by the scan."""
    rng = np.random.default_rng(0)
    N = 200
    q = rng.uniform(100.0, 500.0, (1, N, 2))  # everyone far from agent 0 ...
    q[0, 0], q[0, 1] = [0.0, 0.0], [-300.0, 0.0]  # ... and from its partner, behind it
    p = np.zeros_like(q)
    p[0, 0] = [20.0, 0.0]
    filt = SafetyFilter(SafetyParams(accel_limit=10.0, sensing_radius=20.0), [0, 1], N, [1, 0])
    grid = NeighborGrid(1, N, 2, cell_size=25.0).build(q)
    f, un = np.zeros((1, 2, 2)), np.zeros((1, 2, 2))
    assert not filt.apply(q, p, f, un, grid=grid).active.any()
    q[0, N - 1] = [2.0, 0.0]  # now right ahead of agent 0, closing at 20 m/s
    scan, fast = filt.apply(q, p, f, un), filt.apply(q, p, f, un, grid=grid)
    assert scan.active[0, 0] and not fast.active[0, 0]


@pytest.mark.parametrize(
    "hits, mate, expected",
    [
        ([2, 5, 9], 7, [2, 5, 7, 9]),
        ([2, 5, 9], 5, [2, 5, 9]),  # already found by the grid
        ([2, 5, 9], 0, [0, 2, 5, 9]),
        ([2, 5, 9], 12, [2, 5, 9, 12]),
        ([], 3, [3]),
        ([2, 5], -1, [2, 5]),  # no partner
    ],
)
def test_partner_is_merged_at_its_index(hits, mate, expected):

    buf = np.full(len(hits) + 1, -7, np.int64)
    buf[: len(hits)] = hits
    n = _with_partner(buf, len(hits), mate)
    assert buf[:n].tolist() == expected
