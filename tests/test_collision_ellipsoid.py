"""The collision ellipsoid (``collision_height``, Crazyswarm's downwash measure): the field's
validation, the flocking pass's count against a direct count (all pairs and grid), and the
safety filter's sphere holding the ellipsoid (docs/crazyflie.md)."""

from __future__ import annotations

import numpy as np
import pytest

from pairflock_env import make_config
from pairflock_env.config.sections.reward import collision_ellipsoid
from pairflock_env.swarm.flocking import flocking_params, flocking_pass
from pairflock_env.swarm.grid import NeighborGrid
from pairflock_env.swarm.passes import make_grid


def _ellipsoid_norm(d: np.ndarray, horizontal: float, vertical: float) -> np.ndarray:
    """sqrt((dx^2 + dy^2) / h^2 + dz^2 / v^2) of offsets d (..., 3): < 1 inside."""
    return np.sqrt((d[..., 0] ** 2 + d[..., 1] ** 2) / horizontal**2 + d[..., 2] ** 2 / vertical**2)


def _direct_count(q: np.ndarray, horizontal: float, vertical: float) -> np.ndarray:
    e = _ellipsoid_norm(q[:, :, None, :] - q[:, None, :, :], horizontal, vertical)
    return np.triu(e < 1.0, k=1).sum(axis=(1, 2))


def test_the_crazyflie_preset_states_crazyswarm_s_radii_and_the_default_is_the_sphere():
    cf = make_config("crazyflie")
    assert (cf.collision_distance, cf.collision_height) == (0.125, 0.375)
    assert cf.safety_distance >= cf.collision_height
    assert collision_ellipsoid(cf) == (0.125**2, (0.125 / 0.375) ** 2)
    assert make_config("paper").collision_height is None
    assert collision_ellipsoid(make_config("paper-quadrotor")) is None


@pytest.mark.parametrize(
    "value, why",
    [
        (-1.0, "collision_height=-1"),
        (0.0, "collision_height=0"),
        (float("nan"), "collision_height=nan"),
        (float("inf"), "collision_height=inf"),
        (0.1, r"collision_height=0.1 is invalid: must be None or >= collision_distance \(0.125"),
    ],
)
def test_bad_heights_are_refused_naming_the_field_value_and_range(value, why):
    with pytest.raises(ValueError, match=why):
        make_config("crazyflie", collision_height=value)


def test_a_height_is_refused_for_a_non_number_and_in_2d():
    with pytest.raises((TypeError, ValueError), match="collision_height"):
        make_config("crazyflie", collision_height="tall")
    with pytest.raises(ValueError, match=r"collision_height=1.0 is invalid: .*needs dim=3"):
        make_config("paper", collision_height=1.0)  # 2-D
    assert make_config("paper", dim=3, collision_height=0.5).collision_height == 0.5  # = sphere


def test_the_filter_must_keep_a_sphere_that_holds_the_ellipsoid():
    with pytest.raises(ValueError, match=r"safety_distance=0.3 is invalid: .*collision_height"):
        make_config("crazyflie", safety_filter="cbf", safety_distance=0.3)
    with pytest.raises(ValueError, match=r"collision_height=0.5 is invalid: .*safety_distance"):
        make_config("crazyflie", safety_filter="cbf", collision_height=0.5)
    make_config("crazyflie", safety_distance=0.3)  # no filter: nothing to hold
    make_config("crazyflie", safety_filter="cbf", safety_distance=0.3, collision_height=None)


@pytest.mark.parametrize("height", [0.375, 0.5, 2.0])
def test_a_sphere_at_least_as_tall_holds_the_ellipsoid(height):
    """The statement the filter rests on: for collision_distance <= collision_height <=
    safety_distance, every offset of length >= safety_distance lies outside the ellipsoid,
    since (dx^2 + dy^2) / h^2 + dz^2 / v^2 >= |d|^2 / v^2 >= 1 for h <= v <= |d|."""
    rng = np.random.default_rng(3)
    u = rng.normal(size=(200_000, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    for D in (height, 1.01 * height, 3.0 * height):
        d = u * rng.uniform(D, 2.0 * D, (len(u), 1))
        assert np.all(_ellipsoid_norm(d, 0.125, height) >= 1.0 - 1e-12)
    # tight: the ellipsoid's top touches the sphere of radius collision_height
    assert _ellipsoid_norm(np.array([0.0, 0.0, height]), 0.125, height) == 1.0
    # and a smaller sphere does not hold it: a point straight above, inside the ellipsoid
    below = np.array([0.0, 0.0, 0.9 * height])
    assert _ellipsoid_norm(below, 0.125, height) < 1.0


def _pass(cfg, q, grid=None):
    B, N, _ = q.shape
    z = np.zeros((B, 3))
    partner = np.full(N, -1, np.int64)
    partner[list(cfg.pairs[0])] = list(cfg.pairs[0])[::-1]
    args = (q, np.zeros_like(q), z, z, np.zeros((B, N)), partner)
    return flocking_pass(flocking_params(cfg), *args, grid=grid)


@pytest.mark.parametrize("N", [10, 60, 600])  # pairs met once; grid; each UAV in turn (> 512)
def test_the_ellipsoid_count_equals_a_direct_count_on_both_paths(N):
    cfg = make_config("crazyflie", n_uavs=N, neighbor_search="grid", min_init_spacing=0.01)
    rng = np.random.default_rng(N)
    B = 3
    side = 0.25 * N ** (1 / 3)  # a packed flock: downwash contacts in every swarm
    q = rng.uniform(-side, side, (B, N, 3)) * np.array([1.0, 1.0, 0.5])
    want = _direct_count(q, 0.125, 0.375)
    sphere = np.triu(np.linalg.norm(q[:, :, None] - q[:, None], axis=-1) < 0.125, 1)
    assert want.sum() > sphere.sum()  # the ellipsoid sees more than the sphere
    grid = make_grid(cfg, B)
    assert grid.cell_size == max(cfg.radius, 0.375)
    for g in (None, grid.build(q)):
        assert np.array_equal(_pass(cfg, q, g)["collisions"], want), g is not None


def test_downwash_straight_above_counts_and_the_default_kernels_do_not_see_it():
    """A UAV 0.3 m above another: inside Crazyswarm's ellipsoid, outside the 0.125 m sphere;
    at the filter's 0.375 m, outside both."""
    q = np.zeros((1, 10, 3))
    q[0, :, 0] = 5.0 * np.arange(10)  # far apart along x
    q[0, 2] = q[0, 0] + [0.0, 0.0, 0.3]
    cf = make_config("crazyflie")
    assert _pass(cf, q)["collisions"][0] == 1
    assert _pass(cf.replace(collision_height=None), q)["collisions"][0] == 0
    q[0, 2] = q[0, 0] + [0.0, 0.0, cf.safety_distance]
    assert _pass(cf, q)["collisions"][0] == 0


def test_the_grid_must_cover_the_ellipsoid_s_height():
    cfg = make_config("crazyflie", n_uavs=12, spacing=0.15, radius=0.2, neighbor_search="grid")
    assert make_grid(cfg, 1).cell_size == 0.375
    q = np.random.default_rng(0).uniform(-1.0, 1.0, (1, 12, 3))
    with pytest.raises(ValueError, match="collision_height"):
        _pass(cfg, q, NeighborGrid(1, 12, 3, 0.2).build(q))
