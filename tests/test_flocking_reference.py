"""The flocking pass (all pairs and grid) equals the symmetric sweep it replaced, bit for
bit: the gather sweep forms every sum in the same order (tests/reference_flocking.py)."""

from __future__ import annotations

import numpy as np
import pytest
from reference_flocking import reference_flocking_pass

from pairflock_env import make_config
from pairflock_env.swarm.flocking import flocking_params, flocking_pass
from pairflock_env.swarm.grid import NeighborGrid


def _state(kind: str, rng, B: int, N: int, D: int) -> np.ndarray:
    if kind == "sparse":
        return rng.uniform(-12.0 * N ** (1 / D), 12.0 * N ** (1 / D), (B, N, D))
    if kind == "packed":  # tens of neighbours each, the state of a long flight
        return rng.normal(0.0, 1.2 * N ** (1 / D), (B, N, D))
    if kind == "ties":  # coincident UAVs: zero offsets, equal distances
        return rng.uniform(-6.0, 6.0, (B, 4, D))[:, rng.integers(0, 4, N)].copy()
    if kind == "lattice":  # a lattice with its indices shuffled
        n = int(np.ceil(N ** (1 / D)))
        axes = np.meshgrid(*[np.arange(n)] * D, indexing="ij")
        pts = 7.0 * np.stack(axes, -1).reshape(-1, D)[:N]
        return np.stack([pts[rng.permutation(N)] for _ in range(B)]) + rng.normal(0, 0.3, (B, N, D))
    if kind == "nonfinite":
        q = rng.uniform(-40.0, 40.0, (B, N, D))
        q[0, min(3, N - 1), 0] = np.nan
        q[-1, 1, 1] = 1e9  # beyond divergence_limit
        return q
    raise AssertionError(kind)


def same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def ellipsoid_collisions(q: np.ndarray, horizontal: float, vertical: float) -> np.ndarray:
    """Per swarm, the UAV pairs i < j with (dx^2 + dy^2) / horizontal^2 + dz^2 / vertical^2
    < 1: the collision ellipsoid counted directly, in numpy."""
    d = q[:, :, None, :] - q[:, None, :, :]
    e = (d[..., 0] ** 2 + d[..., 1] ** 2) / horizontal**2 + d[..., 2] ** 2 / vertical**2
    return np.triu(e < 1.0, k=1).sum(axis=(1, 2))


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("kind", ["sparse", "packed", "ties", "lattice", "nonfinite"])
@pytest.mark.parametrize("floor", [False, True])
@pytest.mark.parametrize("ellipsoid", [False, True])
def test_flocking_pass_equals_the_symmetric_sweep(kind, dim, floor, ellipsoid):
    if ellipsoid and dim == 2:
        pytest.skip("the collision ellipsoid needs dim=3")
    rng = np.random.default_rng(7 + dim)
    layer = dict(safety_filter="cbf", safety_scope="swarm") if floor else {}
    # an ellipsoid 3x taller than wide, as Crazyswarm's; its height reaches past the radius
    # (8.4 m), so that the grid's cells follow collision_height
    shape = dict(collision_distance=3.0, collision_height=9.0) if ellipsoid else {}
    if ellipsoid and floor:  # the filter's sphere must hold the ellipsoid
        layer["safety_distance"] = 9.0
    for N, B in ((150, 3), (9, 2), (2, 1), (700, 1)):
        cfg = make_config(
            "paper",
            n_uavs=N,
            dim=dim,
            pairs=((0, 1),),
            **{"collision_distance": 2.0, **shape},
            **layer,
        )
        prm = flocking_params(cfg)
        q, p = _state(kind, rng, B, N, dim), rng.normal(0.0, 2.0, (B, N, dim))
        lq, lp = rng.normal(size=(B, dim)), rng.normal(size=(B, dim))
        pinned = (rng.uniform(size=(B, N)) < 0.3).astype(float)
        partner = np.full(N, -1, np.int64)
        partner[[0, 1]] = [1, 0]
        ref = reference_flocking_pass(prm, q, p, lq, lp, pinned, partner)
        if ellipsoid and kind != "nonfinite":  # the reference's count is the direct one
            direct = ellipsoid_collisions(q, 3.0, 9.0)
            assert np.array_equal(ref["collisions"], direct)
            if kind == "packed" and N >= 150:  # more than the sphere of the horizontal radius
                d = np.linalg.norm(q[:, :, None] - q[:, None], axis=-1)
                assert np.all(direct > np.triu(d < 3.0, 1).sum(axis=(1, 2)))
        cell = max(cfg.radius, cfg.collision_distance, cfg.collision_height or 0.0)
        grid = NeighborGrid(B, N, dim, cell).build(q)
        for g in (None, grid):
            got = flocking_pass(prm, q, p, lq, lp, pinned, partner, grid=g)
            for k, v in ref.items():
                assert same(got[k], v), (k, g is not None)
        assert kind != "packed" or ref["largest_component"].min() > N // 2


def test_the_grid_refuses_cells_shorter_than_the_ellipsoid():
    cfg = make_config("paper", n_uavs=20, dim=3, collision_distance=3.0, collision_height=9.0)
    q = np.random.default_rng(0).normal(0.0, 5.0, (1, 20, 3))
    short = NeighborGrid(1, 20, 3, cfg.radius).build(q)  # 8.4 m < collision_height
    z = np.zeros((1, 3))
    args = (q, np.zeros_like(q), z, z, np.ones((1, 20)), np.full(20, -1, np.int64))
    with pytest.raises(ValueError, match="collision_height"):
        flocking_pass(flocking_params(cfg), *args, grid=short)
