"""The neighbour grid gives exactly what the all-pairs passes give (bit for bit), and grid
placement draws exactly the positions of the O(N^2) rejection sampler it replaces."""

from __future__ import annotations

import numpy as np
import pytest

from pairflock_env import PairFlockCore, make_config
from pairflock_env.config import corner_diagonals
from pairflock_env.swarm.flocking import flocking_params, flocking_pass
from pairflock_env.swarm.grid import (
    GridArrays,
    NeighborGrid,
    block_count,
    nearest_indices,
    order_indices,
    point_cell,
)
from pairflock_env.swarm.pair_pass import pair_pass
from pairflock_env.swarm.slots import sort_indices
from pairflock_env.swarm.spacing import place, redraw_conflicts


def same(a: np.ndarray, b: np.ndarray) -> bool:
    """Bit-for-bit equality (NaN payloads and signed zeros included)."""
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def positions(layout: str, rng, B: int, N: int, D: int, h: float) -> np.ndarray:
    if layout == "spread":  # sparse: many UAVs without a neighbour, nearest ones far away
        return rng.uniform(-40.0 * N ** (1 / D), 40.0 * N ** (1 / D), (B, N, D))
    if layout == "clustered":  # a few dense blobs far apart
        centres = rng.uniform(-300.0, 300.0, (B, 4, D))
        return centres[:, rng.integers(0, 4, N)] + rng.normal(0.0, 3.0, (B, N, D))
    if layout == "borders":  # on cell borders and at exactly the radius / the cell edge
        k = rng.integers(0, 6, (B, N, D)).astype(float)
        step = np.where(rng.uniform(size=(B, N, 1)) < 0.5, h, 8.4)
        q = k * step
        q[:, 0] = 0.0  # the lowest corner, so the borders sit at multiples of h
        return q
    if layout == "coincident":  # many UAVs on the same few points: zero offsets and ties
        pts = rng.uniform(-5.0, 5.0, (B, 3, D))
        return pts[:, rng.integers(0, 3, N)].copy()
    if layout == "runaway":  # one UAV far away (and one swarm far from the origin)
        q = rng.uniform(-30.0, 30.0, (B, N, D))
        q[:, 3] = 1e5
        q[-1] += 1e4
        return q
    if layout == "nonfinite":  # a swarm the grid cannot hold: all pairs for it
        q = rng.uniform(-30.0, 30.0, (B, N, D))
        q[0, 2, 0] = np.nan
        q[-1, 5, 1] = np.inf
        return q
    raise AssertionError(layout)


def compare_passes(cfg, q, p, K, max_cells=None):
    B, N, D = q.shape
    rng = np.random.default_rng(N)
    lq, lp = rng.normal(size=(B, D)), rng.normal(size=(B, D))
    pinned = (rng.uniform(size=(B, N)) < 0.3).astype(float)
    pairs = np.asarray(cfg.pairs)
    agents, partners = pairs.reshape(-1), pairs[:, ::-1].reshape(-1)
    partner = np.full(N, -1, np.int64)
    partner[agents] = partners
    prm = flocking_params(cfg)
    cell = max(cfg.radius, cfg.collision_distance)
    grid = NeighborGrid(B, N, D, cell, max_cells=max_cells).build(q)
    ref = flocking_pass(prm, q, p, lq, lp, pinned, partner)
    got = flocking_pass(prm, q, p, lq, lp, pinned, partner, grid=grid)
    assert ref.keys() == got.keys()
    for k in ref:
        assert same(ref[k], got[k]) or k.startswith("_"), k
    ref = pair_pass(q, p, agents, partners, cfg.radius, K)
    got = pair_pass(q, p, agents, partners, cfg.radius, K, grid=grid)
    for k in ref:
        assert same(ref[k], got[k]) or k.startswith("_"), k
    return grid


LAYOUTS = ["spread", "clustered", "borders", "coincident", "runaway", "nonfinite"]


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("layout", LAYOUTS)
def test_grid_passes_equal_all_pairs(layout, dim):
    rng = np.random.default_rng(LAYOUTS.index(layout) + 10 * dim)
    for N, B, K, coll in ((500, 2, 6, 0.5), (60, 3, 10, 12.0), (7, 2, 9, 0.5)):
        cfg = make_config(
            "paper", n_uavs=N, dim=dim, pairs=((0, 1), (4, 2)), collision_distance=coll
        )
        h = NeighborGrid(1, 1, dim, max(cfg.radius, coll)).arrays.h
        q = positions(layout, rng, B, N, dim, h)
        p = rng.normal(size=(B, N, dim))
        grid = compare_passes(cfg, q, p, K)
        assert grid.ok.tolist() == np.isfinite(q).all(axis=(1, 2)).tolist()
        if layout == "runaway":  # the far UAV folds the grid instead of growing it
            assert grid.arrays.wrap.any(axis=1).all()
        if layout in ("borders", "coincident") and N == 500:  # padded, unfolded cells
            assert (grid.arrays.n_ring == 3**dim).all() and not grid.arrays.wrap.any()
        # few buckets: far cells share buckets, and every answer stays the same
        compare_passes(cfg, q, p, K, max_cells=7)


def reference_pair_pass(q, p, agents, partners, radius, K):
    """The pair pass in plain numpy: np.lexsort of (squared distance, index) over the UAVs
    other than the agent and its partner, non-finite distances left out."""
    B, N, D = q.shape
    M = agents.size
    pos, vel, mask = np.zeros((B, M, K, D)), np.zeros((B, M, K, D)), np.zeros((B, M, K))
    shared = np.zeros((B, M // 2))
    for b in range(B):
        d2 = np.zeros((N, N))
        with np.errstate(invalid="ignore", over="ignore"):  # inf - inf: a NaN distance
            for k in range(D):  # axes summed in order, as the kernels do
                d2 = d2 + (q[b, None, :, k] - q[b, :, None, k]) ** 2
        near = d2 < radius**2
        for m in range(0, M, 2):
            a, c = agents[m], agents[m + 1]
            others = np.ones(N, bool)
            others[[a, c]] = False
            shared[b, m // 2] = np.sum(near[a] & near[c] & others) + 2 * near[a, c]
        for m, (i, j) in enumerate(zip(agents, partners, strict=True)):
            ok = np.isfinite(d2[i])
            ok[[i, j]] = False
            idx = np.flatnonzero(ok)
            best = idx[np.lexsort((idx, d2[i, idx]))][:K]
            pos[b, m, : best.size] = q[b, best] - q[b, i]
            vel[b, m, : best.size] = p[b, best] - p[b, i]
            mask[b, m, : best.size] = 1.0
    return shared, pos, vel, mask


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("N", [7, 20, 150])
@pytest.mark.parametrize("layout", ["spread", "coincident", "nonfinite"])
def test_pair_pass_equals_a_numpy_reference(layout, N, dim):
    rng = np.random.default_rng(N + 7 * dim)
    q = positions(layout, rng, 3, N, dim, 8.4)
    p = rng.normal(size=q.shape)
    agents, partners = np.array([0, 1, 4, 2]), np.array([1, 0, 2, 4])
    for K in (0, 3, N + 2):  # none, a few, more than there are
        got = pair_pass(q, p, agents, partners, 8.4, K)
        ref = reference_pair_pass(q, p, agents, partners, 8.4, K)
        for key, r in zip(("shared", "nbr_pos", "nbr_vel", "nbr_mask"), ref, strict=True):
            assert same(got[key], r), (key, K)


def test_grid_flocking_trajectory_equals_all_pairs():
    """Same trajectories: 150 semi-implicit Euler steps of the flocking command."""
    rng = np.random.default_rng(5)
    N, D, dt = 300, 2, 0.05
    cfg = make_config("paper", n_uavs=N, pinning=())
    prm = flocking_params(cfg)
    q0 = rng.uniform(-60.0, 60.0, (1, N, D))
    partner = np.full(N, -1, np.int64)
    zero, none = np.zeros((1, D)), np.zeros((1, N))
    grid = NeighborGrid(1, N, D, cfg.radius)
    runs = []
    for use_grid in (False, True):
        q, p = q0.copy(), np.zeros_like(q0)
        for _ in range(150):
            g = grid.build(q) if use_grid else None
            acc = flocking_pass(prm, q, p, zero, zero, none, partner, grid=g)["acc"]
            p += dt * acc
            q += dt * p
        runs.append(q)
    assert np.abs(runs[0] - q0).max() > 1.0  # the swarm did move
    assert same(runs[0], runs[1])


def test_within_radius_takes_the_grid_or_the_scan_by_block_size():
    """A query whose block has fewer cells than the swarm has UAVs visits the cells, a
    larger one checks every UAV; both give the brute-force answer, both regimes occur."""
    rng = np.random.default_rng(3)
    N, D, cell = 500, 2, 2.0
    q = rng.uniform(-60.0, 60.0, (1, N, D))
    grid = NeighborGrid(1, N, D, cell).build(q)
    g = GridArrays(*grid.arrays)
    kinds = set()
    for radius in (1.0, 5.0, 12.0, 20.0, 40.0, 90.0):
        for _ in range(10):
            point = rng.uniform(-70.0, 70.0, D)
            c0, c1, c2, _ = point_cell(g, 0, np.array(point))
            L = max(int(np.ceil(radius / cell + 1e-9)), 1)
            kinds.add(block_count(g, 0, c0, c1, c2, L) < N)
            want = np.flatnonzero(np.sum((q[0] - point) ** 2, axis=1) < radius**2).tolist()
            assert grid.within(0, point, radius).tolist() == want
    assert kinds == {True, False}


def test_order_indices_sorts_through_the_bitmap_and_leaves_it_zeroed():
    rng = np.random.default_rng(5)
    mark = np.zeros((1000 + 63) // 64, np.uint64)
    for n in (0, 1, 5, 24, 25, 64, 200, 999, 1000):
        a = rng.permutation(1000)[:n].astype(np.int64)
        want = np.sort(a)
        assert order_indices(a, n, mark) == n
        assert a[:n].tolist() == want.tolist()
        assert not mark.any()


def test_within_radius_matches_brute_force():
    rng = np.random.default_rng(7)
    for D in (2, 3):
        q = rng.uniform(-50.0, 50.0, (2, 400, D))
        q[1, :50] = q[1, 50:100]  # coincident UAVs
        for max_cells in (None, 5):
            grid = NeighborGrid(2, 400, D, 8.4, max_cells=max_cells).build(q)
            for _ in range(40):
                b = int(rng.integers(0, 2))
                point = rng.uniform(-80.0, 80.0, D)
                radius = float(rng.choice([0.0, 3.0, 8.4, 20.0, 200.0]))
                exclude = int(rng.integers(-1, 400))
                d2 = np.sum((q[b] - point) ** 2, axis=1)
                want = [j for j in np.flatnonzero(d2 < radius**2) if j != exclude]
                assert grid.within(b, point, radius, exclude).tolist() == want
    far = grid.within(0, np.full(D, 1e15), 1e16)  # beyond the grid's cells: scanned in full
    assert far.tolist() == list(range(400))
    d = np.linalg.norm(q[1] - q[1, 7], axis=1)
    want = [j for j in np.flatnonzero(d < 9.0) if j != 7]
    assert grid.neighbors_of(1, 7, 9.0).tolist() == want


def test_nearest_indices_is_the_stable_sort():
    rng = np.random.default_rng(8)
    for _ in range(30):
        N = int(rng.integers(1, 60))
        q = rng.integers(-3, 4, (N, 2)).astype(float)  # many equal distances
        point = rng.integers(-2, 3, 2).astype(float)
        d = np.linalg.norm(q - point, axis=1)
        for k in (0, 1, N // 2, N, N + 3):
            want = np.argsort(d, kind="stable")[: max(k, 0)]
            assert nearest_indices(q, point, k).tolist() == want.tolist()


def test_grid_input_errors():
    with pytest.raises(ValueError, match="cell_size"):
        NeighborGrid(1, 10, 2, cell_size=0.0)
    with pytest.raises(ValueError, match="dim"):
        NeighborGrid(1, 10, 4, cell_size=1.0)
    with pytest.raises(ValueError, match="max_cells"):
        NeighborGrid(1, 10, 2, cell_size=1.0, max_cells=0)
    grid = NeighborGrid(1, 10, 2, cell_size=5.0)
    with pytest.raises(RuntimeError, match="build"):
        grid.within(0, [0.0, 0.0], 1.0)
    with pytest.raises(ValueError, match="shape"):
        grid.build(np.zeros((1, 11, 2)))
    cfg = make_config("paper", n_uavs=10)
    q = np.zeros((1, 10, 2))
    args = (q, q, np.zeros((1, 2)), np.zeros((1, 2)), np.ones((1, 10)), np.full(10, -1))
    with pytest.raises(ValueError, match="too small"):
        flocking_pass(flocking_params(cfg), *args, grid=grid.build(q))
    with pytest.raises(TypeError, match="NeighborGrid"):
        flocking_pass(flocking_params(cfg), *args, grid="grid")
    with pytest.raises(ValueError, match="radius"):
        pair_pass(q, q, np.array([0, 1]), np.array([1, 0]), 8.4, 3, grid=grid)


def reference_placement(rng, half, q, fixed, spacing):
    """The O(N^2) rejection sampler the grid version replaces (kept here as the oracle)."""
    N, D = q.shape
    free = np.flatnonzero(~fixed)
    q[free] = rng.uniform(-1.0, 1.0, (free.size, D)) * half[free]
    for _ in range(1000):
        d2 = np.sum((q[:, None, :] - q[None, :, :]) ** 2, axis=-1)
        np.fill_diagonal(d2, np.inf)
        earlier = np.tri(N, k=-1, dtype=bool) | fixed[None, :]
        conflict = np.any((d2 < spacing**2) & earlier, axis=1) & ~fixed
        if not conflict.any():
            return q
        idx = np.flatnonzero(conflict)
        q[idx] = rng.uniform(-1.0, 1.0, (idx.size, D)) * half[idx]
    return None


def start_boxes(cfg):
    """(half, fixed positions, fixed mask) of a config, as the core lays them out."""
    N, D = cfg.n_uavs, cfg.dim
    q, fixed = np.zeros((N, D)), np.zeros(N, bool)
    if cfg.init == "corners":
        diags = corner_diagonals(D) * cfg.vector("pair_corner")
        for k, (a, b) in enumerate(cfg.pairs):
            q[a], q[b] = -diags[k], diags[k]
            fixed[a] = fixed[b] = True
    paired = np.zeros(N, bool)
    paired[np.asarray(cfg.pairs).reshape(-1)] = True
    half = np.where(paired[:, None], cfg.vector("pair_corner"), cfg.vector("swarm_half_width"))
    return half, q, fixed


PLACEMENT_CASES = [
    ("paper", {}),
    ("paper", dict(n_uavs=200, swarm_half_width=22.0)),
    ("paper", dict(n_uavs=150, dim=3, swarm_half_width=7.0, min_init_spacing=1.5)),
    ("paper", dict(n_uavs=40, init="random", pairs=((0, 1), (2, 3)), swarm_half_width=9.5)),
    ("paper", dict(n_uavs=30, swarm_half_width=(30.0, 0.2), min_init_spacing=0.9)),
    ("paper-quadrotor", {}),
]


@pytest.mark.parametrize(("preset", "overrides"), PLACEMENT_CASES)
def test_placement_reproduces_the_draws(preset, overrides):
    cfg = make_config(preset, **overrides)
    half, fixed_q, fixed = start_boxes(cfg)
    centre = cfg.vector("swarm_center")
    for seed in range(6):
        r_ref, r_new = np.random.default_rng(seed), np.random.default_rng(seed)
        want = reference_placement(r_ref, half, fixed_q.copy(), fixed, cfg.min_init_spacing)
        got = place(r_new, half, fixed_q, fixed, cfg.min_init_spacing, centre)
        assert same(got, want + centre)
        assert r_ref.random() == r_new.random()  # the generators advanced alike
    # and the core's own reset draws the same start (swarm 0 of seed 3)
    core = PairFlockCore(cfg)
    core.reset(seed=3)
    rng = np.random.default_rng(np.random.SeedSequence(3).spawn(1)[0])
    assert same(core.q[0], place(rng, half, fixed_q, fixed, cfg.min_init_spacing, centre))


def test_placement_gives_up_with_a_clear_error():
    half = np.full((50, 1), 1.0)
    with pytest.raises(ValueError, match=r"min_spacing=3\.0"):
        place(np.random.default_rng(0), half, np.zeros((50, 2)), np.zeros(50, bool), 3.0, 0.0)
    # no spacing: nothing is checked, nothing drawn
    rng, q = np.random.default_rng(0), np.zeros((3, 2))
    assert redraw_conflicts(rng, q, half[:3], np.zeros(3, bool), 0.0)
    assert np.all(q == 0.0) and rng.random() == np.random.default_rng(0).random()


@pytest.mark.parametrize("D", [2, 3])
def test_within_radius_is_the_brute_force_answer_property(D):
    """Property-based: any swarm size, spread, cell, radius and point (with clusters of
    coincident UAVs), grid or scan, insertion sort or bitmap: the brute-force answer."""
    hypothesis = pytest.importorskip("hypothesis")
    st = hypothesis.strategies
    seen = set()  # which path each query took: the scan, or the grid with either ordering

    @hypothesis.settings(max_examples=60, deadline=None, derandomize=True)
    @hypothesis.given(
        n=st.integers(1, 300),
        spread=st.floats(0.0, 500.0),
        cell=st.floats(0.3, 30.0),
        radius=st.floats(0.0, 400.0),
        seed=st.integers(0, 2**32 - 1),
        exclude=st.integers(-1, 299),
    )
    def check(n, spread, cell, radius, seed, exclude):
        rng = np.random.default_rng(seed)
        q = rng.uniform(-spread, spread, (1, n, D))
        q[0, : n // 4] = q[0, n // 4 : 2 * (n // 4)]  # coincident UAVs
        grid = NeighborGrid(1, n, D, cell).build(q)
        g = GridArrays(*grid.arrays)
        for _ in range(3):
            point = rng.uniform(-1.2 * spread - 1, 1.2 * spread + 1, D)
            d2 = np.sum((q[0] - point) ** 2, axis=1)
            want = [j for j in np.flatnonzero(d2 < radius**2) if j != exclude]
            assert grid.within(0, point, radius, exclude).tolist() == want
            c0, c1, c2, _ = point_cell(g, 0, np.array(point))
            L = max(int(np.ceil(radius * g.inv_h + 1e-4)), 1)
            if block_count(g, 0, c0, c1, c2, L) >= n:
                seen.add("scan")
            else:
                seen.add("grid, bitmap" if len(want) > 24 else "grid, insertion")

    check()
    assert seen == {"scan", "grid, bitmap", "grid, insertion"}


def test_sort_indices_by_rank_bitmap_and_radix():
    """The candidate lists' sort: each of its three ways (short lists by rank, lists whose
    indices span few bitmap words, long scattered lists by radix) gives np.sort and leaves
    the bitmap zeroed."""
    rng = np.random.default_rng(11)
    for n_max in (100, 10_000, 200_000):
        mark = np.zeros((n_max + 63) // 64, np.uint64)
        tmp, hist = np.zeros(n_max, np.int64), np.zeros(256, np.int64)
        for n in (0, 1, 7, 40, 41, 100, 1000, 5000):
            if n > n_max:
                continue
            for spread in (True, False):  # scattered over all indices, or a narrow block
                pool = n_max if spread else min(n_max, 2 * n + 3)
                a = rng.permutation(pool)[:n].astype(np.int64) + (n_max - pool)
                want = np.sort(a)
                sort_indices(a, n, tmp, hist, mark, n_max)
                assert a.tolist() == want.tolist()
                assert not mark.any()
