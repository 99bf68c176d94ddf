"""Physics invariants of the particle model and the flocking pass, against closed forms and
an independent brute-force evaluation of eqs. 2 and 11-19 written here in plain numpy."""

from __future__ import annotations

import numpy as np
import pytest

from pairflock_env import PairFlockCore, make_config
from pairflock_env.dynamics import ParticleModel
from pairflock_env.swarm.flocking import flocking_params, flocking_pass
from pairflock_env.swarm.pair_pass import pair_pass


def brute_force_flocking(cfg, q, p, lq, lp, h):
    """Eqs. 13-19 summed pair by pair (slow, obviously right)."""
    B, N, _D = q.shape
    sigma2 = cfg.repulsion_sigma2
    acc = np.zeros_like(q)
    for b in range(B):
        for i in range(N):
            a = h[b, i] * (
                cfg.pin_position_gain * (lq[b] - q[b, i])
                + cfg.pin_velocity_gain * (lp[b] - p[b, i])
            )
            for j in range(N):
                if j == i:
                    continue
                rho = np.linalg.norm(q[b, j] - q[b, i])
                if rho < cfg.radius:
                    g = cfg.attraction - cfg.repulsion * np.exp(-(rho**2) / sigma2)
                    a = a + g * (q[b, j] - q[b, i]) + cfg.consensus * (p[b, j] - p[b, i])
            acc[b, i] = a
    return acc


def _random_swarm(rng, B, N, D, box=12.0):
    q = rng.uniform(-box, box, (B, N, D))
    p = rng.normal(0.0, 1.0, (B, N, D))
    lq = rng.uniform(-5, 5, (B, D))
    lp = rng.normal(0, 1, (B, D))
    return q, p, lq, lp


@pytest.mark.parametrize("dim", [2, 3])
def test_flocking_pass_matches_brute_force(dim):
    rng = np.random.default_rng(1)
    cfg = make_config("paper", n_uavs=15, dim=dim, pinning=(0, 3, 7))
    q, p, lq, lp = _random_swarm(rng, 3, 15, dim)
    h = np.zeros((3, 15))
    h[:, [0, 3, 7]] = 1.0
    partner = np.full(15, -1, np.int64)
    out = flocking_pass(flocking_params(cfg), q, p, lq, lp, h, partner)
    np.testing.assert_allclose(
        out["acc"], brute_force_flocking(cfg, q, p, lq, lp, h), rtol=1e-12, atol=1e-12
    )


def test_forces_sum_to_zero_without_pinning():
    rng = np.random.default_rng(2)
    cfg = make_config("paper", n_uavs=40, pinning=())
    q, p, lq, lp = _random_swarm(rng, 4, 40, 2, box=15.0)
    out = flocking_pass(
        flocking_params(cfg), q, p, lq, lp, np.zeros((4, 40)), np.full(40, -1, np.int64)
    )
    assert np.abs(out["acc"]).max() > 1.0  # the swarm does interact
    np.testing.assert_allclose(out["acc"].sum(axis=1), 0.0, atol=1e-10)


def test_no_interaction_beyond_radius_and_balance_at_spacing():
    cfg = make_config("paper", n_uavs=2, pinning=())
    prm = flocking_params(cfg)
    partner = np.full(2, -1, np.int64)
    zeros = np.zeros((1, 2))
    p = np.array([[[0.0, 0.0], [1.0, -2.0]]])  # different velocities: consensus would act

    def acc_at(dist):
        q = np.array([[[0.0, 0.0], [dist, 0.0]]])
        return flocking_pass(prm, q, p, np.zeros((1, 2)), np.zeros((1, 2)), zeros, partner)["acc"]

    assert np.all(acc_at(cfg.radius + 1e-9) == 0.0)
    assert np.all(acc_at(50.0) == 0.0)
    assert np.abs(acc_at(cfg.radius - 1e-6)).max() > 0.1
    # at the spacing d attraction and repulsion cancel: only the consensus term is left
    a = acc_at(cfg.spacing)[0]
    np.testing.assert_allclose(a[0], cfg.consensus * (p[0, 1] - p[0, 0]), atol=1e-12)

    # closer than d pushes apart, farther pulls together (eq. 15)
    def position_term(dist):  # x-force on UAV 0 minus its consensus part (p_1x - p_0x = 1)
        return acc_at(dist)[0, 0, 0] - cfg.consensus * 1.0

    assert position_term(0.8 * cfg.spacing) < 0.0 < position_term(1.1 * cfg.spacing)


def test_proximity_quantities_match_brute_force():
    rng = np.random.default_rng(3)
    N, D, B = 25, 2, 3
    cfg = make_config("paper", n_uavs=N, pairs=((0, 1), (2, 3)), collision_distance=1.5)
    q, p, lq, lp = _random_swarm(rng, B, N, D, box=10.0)
    partner = np.full(N, -1, np.int64)
    partner[[0, 1, 2, 3]] = [1, 0, 3, 2]
    out = flocking_pass(flocking_params(cfg), q, p, lq, lp, np.ones((B, N)), partner)
    d = np.linalg.norm(q[:, :, None] - q[:, None, :], axis=-1)  # (B, N, N)
    for b in range(B):
        db = d[b] + np.diag(np.full(N, np.inf))
        masked = db.copy()
        for i in range(N):
            if partner[i] >= 0:
                masked[i, partner[i]] = np.inf
        np.testing.assert_allclose(np.sqrt(out["min_d2"][b]), masked.min(axis=1), rtol=1e-12)
        assert out["collisions"][b] == np.sum(np.triu(db < 1.5, 1))
        # largest connected component by breadth-first search over the radius graph
        adj = db < cfg.radius
        seen, best = np.zeros(N, bool), 0
        for s in range(N):
            if seen[s]:
                continue
            stack, size = [s], 0
            seen[s] = True
            while stack:
                x = stack.pop()
                size += 1
                for y in np.flatnonzero(adj[x] & ~seen):
                    seen[y] = True
                    stack.append(y)
            best = max(best, size)
        assert out["largest_component"][b] == best

    agents = np.array([0, 1, 2, 3])
    partners = np.array([1, 0, 3, 2])
    pp = pair_pass(q, p, agents, partners, cfg.radius, 4)
    for b in range(B):
        nb = d[b] < cfg.radius
        np.fill_diagonal(nb, False)
        for k, (a, c) in enumerate([(0, 1), (2, 3)]):
            others = np.ones(N, bool)
            others[[a, c]] = False
            expect = np.sum(nb[a] & nb[c] & others) + (2 if nb[a, c] else 0)
            assert pp["shared"][b, k] == expect
        for m, (i, j) in enumerate(zip(agents, partners, strict=False)):
            order = [x for x in np.argsort(d[b, i], kind="stable") if x not in (i, j)][:4]
            np.testing.assert_allclose(pp["nbr_pos"][b, m], q[b, order] - q[b, i])
            np.testing.assert_allclose(pp["nbr_vel"][b, m], p[b, order] - p[b, i])
            assert np.all(pp["nbr_mask"][b, m] == 1.0)


def test_neighbor_slots_are_padded_when_the_swarm_is_small():
    cfg = make_config("paper", n_uavs=4, obs_neighbors=5)
    core = PairFlockCore(cfg, seed=0)
    res = core.reset()
    mask = core.layout.get(res.obs[0, 0], "neighbor_mask")
    assert mask.tolist() == [1.0, 1.0, 0.0, 0.0, 0.0]
    assert np.all(core.layout.get(res.obs[0, 0], "neighbor_offsets")[2:] == 0.0)


@pytest.mark.parametrize("substeps", [1, 4])
def test_particle_model_matches_closed_forms(substeps):
    rng = np.random.default_rng(4)
    q0, p0, a = rng.normal(size=(3, 2, 5, 3))
    n_ctrl = 37
    for integrator in ("exact", "semi_implicit"):
        cfg = make_config("paper", dim=3, dt=0.02, substeps=substeps, integrator=integrator)
        model = ParticleModel(cfg, 2)
        q, p = q0.copy(), p0.copy()
        for _ in range(n_ctrl):
            model.advance(q, p, a)
        T = n_ctrl * cfg.dt
        np.testing.assert_allclose(p, p0 + a * T, rtol=1e-12, atol=1e-12)
        if integrator == "exact":
            expect = q0 + p0 * T + 0.5 * a * T**2
        else:  # symplectic Euler: q_K = q0 + K h p0 + h^2 a K (K + 1) / 2
            K, h = n_ctrl * substeps, cfg.physics_dt
            expect = q0 + K * h * p0 + h**2 * a * K * (K + 1) / 2
        np.testing.assert_allclose(q, expect, rtol=1e-12, atol=1e-12)


def test_isolated_pair_is_a_double_integrator_through_the_core():
    """Two UAVs far beyond r, no pinning: only the pair actions move them."""
    cfg = make_config("paper", n_uavs=2, pinning=(), integrator="exact", max_cycles=50)
    core = PairFlockCore(cfg)
    core.reset(seed=[0])
    q0, p0 = core.q.copy(), core.p.copy()
    act = np.array([[[0.02, -0.01], [-0.03, 0.005]]])
    for _ in range(50):
        core.step(act)
    T = 50 * cfg.dt
    a = act[0] * cfg.pair_accel_limit
    np.testing.assert_allclose(core.q[0], q0[0] + p0[0] * T + 0.5 * a * T**2, rtol=1e-12)
    np.testing.assert_allclose(core.p[0], p0[0] + a * T, rtol=1e-12)
