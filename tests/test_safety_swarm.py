"""The swarm layer (``safety_scope="swarm"``, docs/swarm-safety.md): each UAV's problem
against a reference solver, forward invariance with every UAV filtering, the grid against
the scan of all N, the pair scope bit for bit as committed, the repulsion floor, the config
and the infos in every view."""

from __future__ import annotations

import csv
import hashlib
import json
import subprocess
import sys

import numpy as np
import pytest
from test_safety_filter import ref_margin, ref_qcqp
from view_helpers import VIEWS, make_view, reset_view, step_view, zero_action

from baselines.controllers import make_pair_policy
from baselines.experiments.safety.nearest import nearest_figure, nearest_series
from pairflock_env import PairFlockCore, make_config
from pairflock_env.config.sections.flocking import repulsion_floor, repulsion_peak
from pairflock_env.safety import SafetyParams, SwarmFilter
from pairflock_env.safety.cbf.kernels import _far_radius, _sigma_min
from pairflock_env.safety.cbf.search import (
    FIT_ROWS,
    LADDER_REACH,
    RADIUS_LEVELS,
    SCAN,
    SWEEP,
    candidates,
    outlier_level,
    radius_table,
    search_radius,
    sort_by_x,
    velocity_field,
)
from pairflock_env.safety.cbf.swarm_kernels import SWARM as SWARM_PARAMS
from pairflock_env.safety.cbf.swarm_kernels import _far_of
from pairflock_env.swarm.flocking import FLOCKING, flocking_params
from pairflock_env.swarm.grid import NeighborGrid
from pairflock_env.task.infos import SAFETY_SWARM_INFO_KEYS
from pairflock_env.task.metrics import (
    FLOCK_METRIC_DOCS,
    SWARM_SAFETY_METRIC_DOCS,
    flock_state,
    swarm_safety_metrics,
)

SWARM = dict(safety_filter="cbf", safety_scope="swarm")


def _filter(P, agents, N, partners=None, U=20.0, alpha=16.0, radius=8.4):
    return SwarmFilter(
        P, agents, N, partners, accel_limit=U, brake_accel=alpha, swarm_radius=radius
    )


def _random_state(rng, B, N, D, box, speed, spacing=1.2):
    """Positions at least ``spacing`` apart in a box of side ``box``, velocities N(0, speed)."""
    q = np.empty((B, N, D))
    for b in range(B):
        n = 0
        while n < N:
            x = rng.uniform(0, box, D)
            if n == 0 or np.linalg.norm(q[b, :n] - x, axis=1).min() >= spacing:
                q[b, n] = x
                n += 1
    return q, rng.normal(0.0, speed, (B, N, D))


# ------------------------------------------------------------------- each UAV's problem
def _reference_rows(P, filt, q, p, f, i, U_s, a_s, radius):
    """UAV i's rows written here from the definition (every UAV in range, no skip)."""
    N, D = q.shape[1:]
    paired = np.isin(np.arange(N), filt.agents)
    mate = dict(zip(filt.agents.tolist(), filt._ints[1][filt.agents].tolist(), strict=True))
    alpha = np.where(paired, P.brake_accel, a_s)
    ctr = f[0, i] if paired[i] else np.zeros(D)
    G, b = [], []
    for j in range(N):
        d = np.linalg.norm(q[0, i] - q[0, j])
        R = P.sensing_radius if paired[i] or paired[j] else radius
        alone = filt.pair_alone and paired[i] != paired[j]  # the paired UAV's row alone
        if j == i or not (d < R or mate.get(i) == j) or (alone and not paired[i]):
            continue
        n = (q[0, i] - q[0, j]) / d
        a = alpha[i] - U_s if alone else alpha[i] + alpha[j]
        _, smin = _sigma_min(d - P.barrier_distance, n @ (p[0, i] - p[0, j]), 0.0, a,
                             P.dt, P.position_gain, P.decay, P.reaction_time)  # fmt: skip
        G.append(n)
        b.append((smin + U_s if alone else alpha[i] / a * smin) - n @ ctr)
    U = P.accel_limit if paired[i] else U_s
    keep = np.array(b) > -U  # the others the ball implies (they only slow the reference)
    return np.array(G).reshape(-1, D)[keep], np.array(b)[keep], U, ctr


def test_each_uavs_problem_matches_a_reference_solver():
    """Random crowds (one pair among unpaired UAVs, some closing fast): every UAV's command
    is the reference solver's optimum of its problem to 1e-6, or, where no command meets
    every row, it attains the largest smallest margin. Paired UAVs that take their rows
    against unpaired ones alone (pair_accel_limit 60) and that share them (15)."""
    rng = np.random.default_rng(29)
    U_s, a_s, radius = 20.0, 16.0, 6.0
    solved = infeasible = 0
    for k in range(60):
        P = SafetyParams(accel_limit=60.0 if k % 2 else 15.0, sensing_radius=30.0)
        D = int(rng.integers(2, 4))
        N = int(rng.integers(4, 11))
        filt = _filter(P, [0, 1], N, [1, 0], U_s, a_s, radius)
        assert filt.pair_alone == bool(k % 2)
        q, p = _random_state(rng, 1, N, D, box=5.0, speed=float(rng.choice([1.0, 4.0])))
        f = rng.normal(0, 10.0, (1, N, D))
        a_nom = f + rng.normal(0, 30.0, (1, N, D))
        out = filt.apply(q, p, a_nom, f)
        for i in range(N):
            G, b, U, ctr = _reference_rows(P, filt, q, p, f, i, U_s, a_s, radius)
            x = out.a[0, i] - ctr
            if out.infeasible[0, i]:
                t = (G @ x - b).min()
                assert abs(t - ref_margin(G, b, U)) <= 1e-6 * (1 + abs(t)), (t, G, b)
                infeasible += 1
                continue
            ref = ref_qcqp(a_nom[0, i] - ctr, G, b, U) if len(b) else None
            if ref is None:  # no row: the nominal, within the ball
                xn = a_nom[0, i] - ctr
                ref = xn * min(1.0, U / np.linalg.norm(xn))
            assert np.linalg.norm(x - ref) <= 1e-6 * (1 + np.linalg.norm(ref)), (x, ref)
            solved += 1
    assert solved > 250 and infeasible > 0


def test_every_command_stays_in_its_ball():
    rng = np.random.default_rng(3)
    P = SafetyParams(accel_limit=50.0)
    filt = _filter(P, [0, 1, 2, 3], 30, [1, 0, 3, 2])
    q, p = _random_state(rng, 4, 30, 2, box=8.0, speed=5.0)
    f = rng.normal(0, 30.0, q.shape)
    out = filt.apply(q, p, f + rng.normal(0, 100.0, q.shape), f)
    norms = np.linalg.norm(out.a - np.where(filt._ints[0][:, None], f, 0.0), axis=-1)
    bound = np.where(filt._ints[0], 50.0, 20.0)
    assert (norms <= bound * (1 + 1e-12)).all()
    assert np.allclose(out.u, out.a[:, :4] - f[:, :4], rtol=0, atol=1e-12)
    assert out.active.any()


# ------------------------------------------------------------------- forward invariance
def _fly(seed, D, limit, steps=300, B=24, N=14, sigma=8.0):
    """Every UAV filters a fresh random nominal command each step (the pair members' much
    larger), semi-implicit Euler with the filtered commands held. Every UAV senses every
    other (assumption b). Returns, per swarm, whether it started safe, the closest two UAVs
    up to the first step on which some UAV was infeasible, and that step."""
    rng = np.random.default_rng(seed)
    P = SafetyParams(accel_limit=limit, sensing_radius=1e4)
    filt = _filter(P, [0, 1], N, [1, 0], radius=1e4)
    q, p = _random_state(rng, B, N, D, box=10.0, speed=2.0)
    out = filt.allocate(B, D)
    closest = np.full(B, np.inf)
    stop = np.full(B, steps)
    safe0 = None
    iu = np.triu_indices(N, 1)
    for k in range(steps):
        d = np.linalg.norm(q[:, :, None] - q[:, None], axis=-1)[:, iu[0], iu[1]].min(1)
        closest = np.where(stop > k, np.minimum(closest, d), closest)
        a_nom = rng.normal(0, sigma, (B, N, D))
        a_nom[:, :2] *= limit / 5.0
        f = rng.normal(0, 5.0, (B, N, D))
        filt.apply(q, p, a_nom, f, out)
        if safe0 is None:
            safe0 = out.barrier.min(1) >= 0
        stop = np.where(out.infeasible.any(1) & (stop == steps), k, stop)
        p += out.a * P.dt
        q += p * P.dt
    return safe0, closest, stop


@pytest.mark.parametrize(("D", "limit"), [(2, 100.0), (3, 100.0), (2, 20.0), (3, 20.0)])
def test_forward_invariance_with_every_uav_filtering(D, limit):
    """No two UAVs of a swarm that starts safe ever come closer than safety_distance while
    every UAV stays feasible (the state after a step on which all were feasible is safe).
    pair_accel_limit 100: the paired UAVs take their rows against unpaired ones alone; 20:
    they share them."""
    safe0, closest, stop = _fly(11 + D, D, limit)
    assert safe0.sum() >= 20
    assert (closest[safe0] >= 1.0 - 1e-9).all(), closest[safe0].min()
    assert (stop[safe0] == 300).sum() >= 5  # not vacuous: whole runs without infeasibility


# ------------------------------------------------------------------- grid and all pairs
@pytest.mark.parametrize(("D", "limit"), [(2, 80.0), (3, 80.0), (2, 20.0), (3, 20.0)])
def test_the_grid_gives_the_scan_bit_for_bit(D, limit):
    rng = np.random.default_rng(5 + D)
    P = SafetyParams(accel_limit=limit)
    N = 120
    filt = _filter(P, [0, 1, 5, 9], N, [1, 0, 9, 5])
    q, p = _random_state(rng, 3, N, D, box=25.0, speed=3.0)
    p[:, :2] *= 10.0  # a fast pair
    f = rng.normal(0, 10.0, q.shape)
    a_nom = f + rng.normal(0, 20.0, q.shape)
    scan = filt.apply(q, p, a_nom, f)
    for cell in (1.5, 4.0, 30.0):
        grid = NeighborGrid(3, N, D, cell_size=cell).build(q)
        on = filt.apply(q, p, a_nom, f, grid=grid)
        for x, y in zip(scan.arrays(), on.arrays(), strict=True):
            assert np.array_equal(x, y)
    assert scan.active.any()


def _contracting_state(rng, B, N, D, box=60.0, rate=1.5, drift=40.0, noise=0.3):
    """A flock closing on its centre as the swarm does after a spread reset: each UAV
    fast relative to the mean (rate x its offset), but nearly at its neighbours' speed."""
    q, _ = _random_state(rng, B, N, D, box=box, speed=0.0, spacing=1.5)
    v0 = rng.normal(0.0, drift, (B, 1, D))
    p = v0 - rate * (q - q.mean(1, keepdims=True)) + rng.normal(0.0, noise, q.shape)
    p[:, 3] += 12.0  # one fast UAV: its own residual is large
    return q, p


@pytest.mark.parametrize("D", [2, 3])
def test_the_velocity_field_bounds_every_relative_speed(D):
    """|p_i - p_j| <= k |q_i - q_j| + e_i + e_j + pad for every pair, with k, e from the
    affine fit; an exactly affine flock has residuals near zero."""
    rng = np.random.default_rng(40 + D)
    N = 200
    q, p = _contracting_state(rng, 1, N, D)
    fit, res = np.zeros((FIT_ROWS, 3)), np.zeros(N)
    paired = np.zeros(N, np.bool_)
    kn, eo, pad = velocity_field(q, p, 0, paired, fit, res)
    assert 0 < kn < 3.0 and np.isclose(eo, res.max())
    dq = np.linalg.norm(q[0, :, None] - q[0, None], axis=-1)
    dv = np.linalg.norm(p[0, :, None] - p[0, None], axis=-1)
    assert (dv <= kn * dq + res[:, None] + res[None] + 2 * pad).all()
    assert np.median(res) < 2.0 < np.median(np.linalg.norm(p[0] - p[0].mean(0), axis=1))
    K = rng.normal(0.0, 0.5, (D, D))
    exact = 3.0 + (q - q.mean(1, keepdims=True)) @ K.T
    velocity_field(q, exact, 0, paired, fit, res)
    assert res.max() < 1e-6  # the regulariser (1e-9 of the trace) and rounding
    p[0, 7, 0] = np.nan
    assert velocity_field(q, p, 0, paired, fit, res) == (np.inf, np.inf, np.inf)


def test_the_search_radius_leaves_out_only_what_the_skip_drops():
    """far_radius(k d + c) <= d for every d between the search radius and R (a fine sweep);
    the radius is at least the skip's radius at speed c, and tight: 0.2 % shorter fails."""
    P = SafetyParams(accel_limit=100.0)
    filt = _filter(P, [0, 1], 10, [1, 0])
    far = _far_of(filt._pr, 16.0, 16.0, 20.0, 0.0, 20.0, 20.0)
    for kn, c, R in ((0.0, 3.0, 100.0), (0.2, 5.0, 100.0), (1.0, 1.0, 50.0), (0.05, 40.0, 100.0)):
        r = search_radius(far, kn, c, R)
        assert _far_radius(c, far) <= r <= R
        d = np.linspace(r, R, 4001)
        assert all(_far_radius(kn * x + c, far) <= x for x in d)
        if r < R:  # no shorter radius would do (to the root's or the bisection's tolerance)
            x = r * (1 - 2e-3)
            assert _far_radius(kn * x + c, far) > x


@pytest.mark.parametrize("D", [2, 3])
def test_the_x_sweep_finds_what_the_scan_finds(D):
    """Without a grid the searches walk each swarm's x order (kept across steps): the same
    hits in the same order as the scan of all N, ties in x and a reordered flock included;
    a non-finite swarm is left to the scan."""
    rng = np.random.default_rng(60 + D)
    B, N = 2, 300
    q, p = _random_state(rng, B, N, D, box=40.0, speed=3.0)
    q[:, 10:20, 0] = q[:, 10:11, 0]  # ten UAVs at the same x
    order = np.tile(np.arange(N), (B, 1))
    pos, mark = np.zeros(N, np.int64), np.zeros(N // 64 + 2, np.uint64)
    hits, ref = np.zeros(N + 1, np.int64), np.zeros(N + 1, np.int64)
    gs = (NeighborGrid(1, 1, D, cell_size=1.0).build(np.zeros((1, 1, D))).arrays,) * 3
    gs += (np.zeros(1),)  # the ladder's reach
    unknown = np.zeros((B, N))
    for _ in range(3):  # steps
        d2 = ((q[:, :, None] - q[:, None]) ** 2).sum(-1) + np.where(np.eye(N), np.inf, 0.0)
        sep = d2.min(-1)  # the nearest neighbour: searches shorter than it are skipped
        for b in range(B):
            assert sort_by_x(q, p, b, order[b], pos)
            assert (np.diff(q[b, order[b], 0]) >= 0).all()
            xs = (order[b], pos, mark)
            for i in range(N):
                r2 = rng.uniform(0.0, 15.0) ** 2
                m = candidates(q, b, i, r2, SCAN, gs, xs, unknown, ref)
                for known in (unknown, sep):
                    n = candidates(q, b, i, r2, SWEEP, gs, xs, known, hits)
                    assert n == m and np.array_equal(hits[:n], ref[:m])
        q += rng.normal(0.0, 2.0, q.shape)  # the next step's positions
    q[1, 5, 1] = np.nan
    assert not sort_by_x(q, p, 1, order[1], pos)


@pytest.mark.parametrize("D", [2, 3])
def test_the_shortened_searches_miss_no_row(D):
    """The search radii from the velocity field, the radius table, the outlier split and
    the grid ladder drop only UAVs the far-UAV skip drops: the same commands and flags as
    every UAV in range evaluated, on the x order, one grid and a ladder of three."""
    rng = np.random.default_rng(50 + D)
    B, N = 3, 250
    P = SafetyParams(accel_limit=80.0)
    args = (P, [0, 1, 6, 9], N, [1, 0, 9, 6])
    kw = dict(accel_limit=20.0, brake_accel=16.0, swarm_radius=100.0)
    filt, every = SwarmFilter(*args, **kw), SwarmFilter(*args, **kw)
    every._pr[SWARM_PARAMS.index.skip_far] = 0.0
    q, p = _contracting_state(rng, B, N, D)
    f = rng.normal(0.0, 10.0, q.shape)
    a_nom = f + rng.normal(0.0, 30.0, q.shape)
    ref = every.apply(q, p, a_nom, f)
    assert ref.active.sum() >= 10
    # not vacuous: the searches are split around the fastest 5 % (outlier_level < inf)
    paired, res = filt._ints[0], np.zeros(N)
    fld = velocity_field(q, p, 0, paired, np.zeros((FIT_ROWS, 3)), res)
    far = _far_of(filt._pr, 16.0, 16.0, 20.0, 0.0, 20.0, 20.0)
    de, L = radius_table(100.0**2, far, fld, np.zeros(RADIUS_LEVELS + 1), N)
    assert outlier_level(res, paired, de, L, np.zeros(RADIUS_LEVELS + 1, np.int64)) < np.inf
    ladder = [NeighborGrid(B, N, D, cell_size=h).build(q) for h in (2.0, 8.0, 32.0)]
    d2 = ((q[:, :, None] - q[:, None]) ** 2).sum(-1) + np.where(np.eye(N), np.inf, 0.0)
    sep = d2.min(-1)  # each UAV's nearest neighbour, as the flocking pass gives it
    for grid in (None, ladder[0], ladder):
        for known in (None, sep):
            out = filt.apply(q, p, a_nom, f, grid=grid, separation=known)
            for x, y in zip(ref.arrays()[:5], out.arrays()[:5], strict=True):
                assert np.array_equal(x, y)
    with pytest.raises(ValueError, match="fine to coarse"):
        filt.apply(q, p, a_nom, f, grid=ladder[::-1])
    with pytest.raises(ValueError, match="separation has shape"):
        filt.apply(q, p, a_nom, f, separation=sep[0])


def test_the_ladder_builds_only_the_grids_the_searches_need():
    """A settled (rigidly moving) flock searches the finest grid only, and the next step
    builds only that one; a UAV 60 m/s off the flock's motion needs the coarsest."""
    core = PairFlockCore(make_config("large", n_uavs=400, **SWARM))
    core.reset(seed=1)
    stage, zero = core.safety, np.zeros((1, core.n_agents, 2))
    core.p[:] = core.p.mean(1, keepdims=True)
    core.step(zero)
    assert stage.filter.search_reach <= LADDER_REACH * stage.grids[0].cell_size
    assert stage._levels == 1
    core.p[:] = core.p.mean(1, keepdims=True)
    fast = np.setdiff1d(np.arange(400), core.agent_uavs)[0]  # an unpaired UAV
    core.p[0, fast] += 60.0
    core.step(zero)  # (on the finest grid: slower, the same commands)
    assert stage.filter.search_reach > LADDER_REACH * stage.grids[1].cell_size
    assert stage._levels == 3


def test_core_on_the_grid_flies_the_all_pairs_trajectories():
    kw = dict(n_uavs=60, init="random", pairs=((0, 1), (2, 3)), **SWARM)
    runs = []
    for search in ("all_pairs", "grid"):
        core = PairFlockCore(make_config("paper", neighbor_search=search, **kw), num_swarms=2)
        core.reset(seed=[4, 5])
        rng = np.random.default_rng(0)
        for _ in range(150):
            core.step(rng.uniform(-1, 1, (2, 4, 2)))
        runs.append((core.q.copy(), core.p.copy()))
    assert np.array_equal(runs[0][0], runs[1][0]) and np.array_equal(runs[0][1], runs[1][1])


# ------------------------------------------------------------------- off: as committed
#: sha256 of 300 steps of random pair actions (seed 7) of two swarms (seeds 3, 4): the applied
#: pair commands, the corrections, then the final state; taken from the commit before the
#: swarm layer (7f7c231)
COMMITTED = {
    "paper_n20_corners_cbf": (
        dict(preset="paper", n_uavs=20, safety_filter="cbf"),
        "33b29134bec4ef25f3b69e096574aaa2d61ec733feac4d8e8a89f982f40e126d",
    ),
    "paper_n50_random_cbf": (
        dict(preset="paper", n_uavs=50, init="random", safety_filter="cbf"),
        "a0c9488930f11844fed82350034336dedd7a09d87f4a6964166cad7f33aac924",
    ),
    "paper_n100_random_off": (
        dict(preset="paper", n_uavs=100, init="random"),
        "fad9a576a9bab1fa877d391ed13e9e3b15b0397219ea90569c5ca2fc66882c90",
    ),
    "quadrotor_cbf": (
        dict(preset="paper-quadrotor", safety_filter="cbf"),
        "4f3f740d395c1757cbeeb21b88d65e8564bf0df14288ed3434a0f947396d6817",
    ),
}
#: the same digests of the swarm layer, taken from the commit before its searches were
#: shortened by the velocity field and the grid ladder (a81a625)
COMMITTED_SWARM = {
    "paper_n50_random_swarm": (
        dict(preset="paper", n_uavs=50, init="random", **SWARM),
        "5b26ff18df004677815fbeae9341d6a6beb89f100d4191e946c5a40032266e7e",
    ),
    "large_n400_swarm": (
        dict(steps=200, seeds=(3,), preset="large", n_uavs=400, **SWARM),
        "4afdf2f18c3da57588892ed3d902dbbb9cd33c556c4d8ec5695070618b4d0fc9",
    ),
}


def _digest(steps=300, seeds=(3, 4), preset="paper", **kw):
    core = PairFlockCore(None, num_swarms=len(seeds), preset=preset, **kw)
    res = core.reset(seed=list(seeds))
    rng = np.random.default_rng(7)
    h = hashlib.sha256()
    for _ in range(steps):
        res = core.step(rng.uniform(-1.0, 1.0, (core.num_swarms, core.n_agents, core.config.dim)))
        h.update(core.pair_command.tobytes())
        h.update(res.info["safety_correction"].tobytes())
    h.update(core.q.tobytes())
    h.update(core.p.tobytes())
    return h.hexdigest()


@pytest.mark.parametrize("name", COMMITTED)
def test_the_pairs_scope_flies_as_committed(name):
    """With safety_scope="pairs" (the default, with or without the swarm fields set) the
    filter and the flocking law are bit for bit those before the swarm layer."""
    kw, digest = COMMITTED[name]
    assert _digest(**kw) == digest
    if name == "paper_n20_corners_cbf":
        extra = dict(safety_scope="pairs", swarm_accel_limit=5.0, swarm_repulsion_floor=True)
        assert _digest(**kw, **extra) == digest


@pytest.mark.parametrize("name", COMMITTED_SWARM)
def test_the_swarm_scope_flies_as_committed(name):
    """The searches' shortcuts change no bit of the layer's flights."""
    kw, digest = COMMITTED_SWARM[name]
    assert _digest(**kw) == digest


# ------------------------------------------------------------------- the repulsion floor
def test_the_floor_is_where_the_repulsion_peaks_and_grows_below():
    cfg = make_config("paper", **SWARM)
    rho = repulsion_peak(cfg)
    s2, a, br = cfg.repulsion_sigma2, cfg.attraction, cfg.repulsion

    def F(r):
        return r * (br * np.exp(-r * r / s2) - a)

    assert abs(rho - 3.0025) < 1e-4 and F(rho) > max(F(rho * 0.999), F(rho * 1.001))
    r2, K = repulsion_floor(cfg)
    assert r2 == rho * rho and pytest.approx(F(rho) * rho, rel=1e-15) == K
    prm = FLOCKING.unpack(flocking_params(cfg))
    assert (prm["floor_radius2"], prm["floor_gain"]) == (r2, K)
    for off in (make_config("paper"), cfg.replace(swarm_repulsion_floor=False)):
        assert repulsion_floor(off) == (0.0, 0.0)
    # two UAVs 1 m apart: the paper's repulsion is weaker than at rho*; the floor's is stronger
    q = np.array([[[0.0, 0.0], [1.0, 0.0]]])
    for c, force in ((make_config("paper", n_uavs=2), F(1.0)), (cfg.replace(n_uavs=2), K)):
        core = PairFlockCore(c, num_swarms=1)
        core.reset(seed=0, options=dict(positions=q[0], velocities=np.zeros((2, 2))))
        lq, lp = core.leader_state()
        pin = c.pin_position_gain * (lq[0] - q[0, 0]) + c.pin_velocity_gain * lp[0]
        assert core.flock_accel[0, 0] - pin == pytest.approx([-force, 0.0], rel=1e-12)


# ------------------------------------------------------------------- config and the env
def test_the_swarm_scope_needs_the_cbf_filter_and_follows_the_vehicle():
    with pytest.raises(ValueError, match=r"safety_scope='swarm'.*needs safety_filter in \['cbf'\]"):
        make_config("paper", safety_scope="swarm")
    with pytest.raises(ValueError, match="swarm_brake_accel"):
        make_config("paper", swarm_brake_accel=30.0, **SWARM)
    with pytest.raises(ValueError, match="safety_scope"):
        make_config("paper", safety_scope="all")
    particle = PairFlockCore(make_config("paper", **SWARM)).safety.filter
    quad = PairFlockCore(make_config("paper-quadrotor", **SWARM)).safety.filter
    for filt, U, alpha in ((particle, 20.0, 16.0), (quad, 6.0, 4.8)):
        paired = filt._ints[0]
        assert (filt._reals[1][~paired] == U).all()
        assert np.allclose(filt._reals[0][~paired], alpha)
    # the unset reaction time: the vehicle's lag, 1.5 times it under the swarm scope
    pairs = PairFlockCore(make_config("paper-quadrotor", safety_filter="cbf")).safety.filter
    assert particle.params.reaction_time == 0.0
    assert np.isclose(quad.params.reaction_time, 1.5 * pairs.params.reaction_time)
    assert np.isclose(pairs.params.reaction_time, 0.1)
    set_tau = make_config("paper-quadrotor", safety_reaction_time=0.05, **SWARM)
    assert PairFlockCore(set_tau).safety.filter.params.reaction_time == 0.05


def test_sliding_mode_with_the_swarm_layer_keeps_every_two_uavs_apart():
    cfg = make_config("paper", n_uavs=20, horizon=8.0, **SWARM)
    core = PairFlockCore(cfg, num_swarms=2)
    res = core.reset(seed=[71000, 71001])
    pol = make_pair_policy("smc", cfg)
    closest, active, infeasible = np.inf, 0, 0
    for _ in range(cfg.episode_steps):
        act, _ = pol.predict(res.obs.reshape(-1, res.obs.shape[-1]), deterministic=True)
        res = core.step(np.asarray(act, float).reshape(2, core.n_agents, 2))
        closest = min(closest, res.info["swarm_min_separation"].min())
        active += res.info["swarm_filter_active"].sum()
        infeasible += res.info["swarm_filter_infeasible"].sum()
        # the agents' rows of the layer are their per-agent infos
        o = core.safety.output
        assert np.array_equal(res.info["safety_active"], o.active[:, core.agent_uavs])
    assert closest >= 1.0 and active > 0 and infeasible == 0


@pytest.mark.parametrize("kind", VIEWS)
@pytest.mark.parametrize("scope", ["off", "pairs", "swarm"])
def test_swarm_infos_in_every_view(kind, scope):
    kw = {} if scope == "off" else dict(safety_filter="cbf", safety_scope=scope)
    if kind == "sb3":
        kw["info_keys"] = "all"
    env = make_view(kind, **kw)
    reset_view(env, kind, seed=0)
    for _ in range(3):
        out = step_view(env, kind, zero_action(env, kind))
    info = out[-1][env.agents[0]] if kind == "parallel" else out[-1]
    info = info[0] if kind == "sb3" else info
    for k in ("swarm_min_separation", *SAFETY_SWARM_INFO_KEYS):
        v = np.asarray(info[k])
        assert v.dtype.kind in "iuf" and np.isfinite(v).all() and (v >= 0).all(), (k, v)
    assert (np.asarray(info["swarm_min_separation"]) > 1.0).all()
    env.close()


def test_swarm_min_separation_is_the_closest_two_uavs_partners_included():
    q = np.array([[0.0, 0.0], [0.5, 0.0], [5.0, 0.0], [5.0, 3.0]])  # UAVs 0, 1: the pair
    for cfg in (make_config("paper", n_uavs=4), make_config("paper", n_uavs=4, **SWARM)):
        core = PairFlockCore(cfg, num_swarms=1)
        res = core.reset(seed=0, options=dict(positions=q, velocities=np.zeros((4, 2))))
        assert res.info["swarm_min_separation"][0] == 0.5
        assert res.info["min_separation"][0].min() == 4.5  # the partner left out there


# ------------------------------------------------------------------- metrics and commands
def test_flock_state_on_the_grid_and_by_all_pairs():
    rng = np.random.default_rng(2)
    q = rng.uniform(0, 60, (2, 300, 2))
    unpaired = np.ones(300, bool)
    unpaired[:4] = False
    grid = NeighborGrid(2, 300, 2, cell_size=8.4).build(q)
    lq = np.array([30.0, 20.0])
    for b in range(2):
        rg, track, dev = flock_state(q, b, lq, unpaired, 8.4, 7.0)
        assert flock_state(q, b, lq, unpaired, 8.4, 7.0, grid) == pytest.approx((rg, track, dev))
        x = q[b, unpaired]
        assert rg == pytest.approx(np.sqrt(((x - x.mean(0)) ** 2).sum(1).mean()))
        assert track == pytest.approx(np.linalg.norm(x.mean(0) - lq))
        d = np.linalg.norm(q[b, :, None] - q[b, None], axis=-1)[np.triu_indices(300, 1)]
        d = d[d < 8.4]
        assert dev == pytest.approx(((d - 7.0) ** 2).sum() / (d.size + 1))


def test_swarm_safety_metrics_count_steps_and_uav_steps():
    m = swarm_safety_metrics(np.array([3.0, 0.9, 1.2, 0.95]), [0, 4, 2], [0, 2, 0], 1.0)
    assert m == {
        "swarm_closest": 0.9,
        "swarm_steps_below": 2,
        "swarm_active_uav_steps": 6,
        "swarm_infeasible_uav_steps": 2,
        "swarm_infeasible_steps": 1,
    }


def test_the_swarm_safety_suite_reports_every_uav_and_the_flock(tmp_path):
    out = tmp_path / "ss"
    cmd = [sys.executable, "-m", "baselines.benchmark", "--suite", "swarm-safety", "--seeds", "1"]
    cmd += ["--n-uavs", "20", "--set", "init=corners", "-p", "smc", "--horizon", "12"]
    cmd += ["--workers", "2", "--no-figures", "--quiet", "--out", str(out)]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert [r["scenario"] for r in rows] == ["off", "pairs", "swarm"]
    assert all(r["seed"] == "72000" for r in rows)  # the held-out seeds
    for r in rows:
        assert set(SWARM_SAFETY_METRIC_DOCS) | set(FLOCK_METRIC_DOCS) <= set(r)
    assert float(rows[2]["swarm_closest"]) >= 1.0 and rows[2]["swarm_steps_below"] == "0"
    assert "## Every UAV and the flock" in (out / "summary.md").read_text()
    assert "closest two UAVs min (m)" in done.stdout
    report = subprocess.run(
        [sys.executable, "-m", "baselines.experiments.safety.swarm_report", str(out)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert "| 20 | corners | smc | 1 |" in report and "swarm/pairs" in report


def test_the_nearest_neighbour_figure(tmp_path):
    series = [nearest_series(30, layer, 71000, 1.0, 5.0) for layer in ("off", "swarm")]
    assert [len(s["t"]) for s in series] == [6, 6]
    assert all(s["min"][k] <= s["p1"][k] <= s["p50"][k] for s in series for k in range(6))
    assert nearest_figure(series, tmp_path / "nn.png").stat().st_size > 0


def test_the_nearest_neighbour_command_flies_the_layers_and_horizon_it_is_given(tmp_path):
    out = tmp_path / "nn.png"
    cmd = [sys.executable, "-m", "baselines.experiments.safety.nearest", "--n", "30"]
    cmd += ["--layers", "swarm", "--horizon", "1", "--every", "0.5", "--out", str(out)]
    printed = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    (series,) = json.loads(out.with_suffix(".json").read_text())
    assert series["layer"] == "swarm" and series["t"] == [0.0, 0.5, 1.0]
    assert "N=    30 swarm" in printed and out.stat().st_size > 0
