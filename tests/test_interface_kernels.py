"""The pair interface's kernels give the numbers of its numpy formulation, bit for bit
(tests/reference_interface.py), in 2-D and 3-D, with every option and the edge cases of the
pair frame (zero and vertical offsets), empty neighbour slots and ties."""

from __future__ import annotations

import numpy as np
import pytest
import reference_interface as ref

from pairflock_env import make_config
from pairflock_env.interfaces import make_interface


def same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _observations(rng, itf, B: int, M: int) -> np.ndarray:
    lay, D = itf.layout, itf.config.dim
    obs = np.zeros((B, M, lay.size), np.float32)
    for f in lay:
        scale = 10.0 ** rng.uniform(-3, 2, (B, M, f.size))
        obs[..., lay.slice(f.name)] = rng.normal(size=(B, M, f.size)) * scale
    if "neighbor_mask" in lay:
        obs[..., lay.slice("neighbor_mask")] = (
            rng.uniform(size=(B, M, itf.config.obs_neighbors)) < 0.7
        )
        # ties: two slots at the same offset and velocity
        K = itf.config.obs_neighbors
        if K > 1:
            x = lay.slice("neighbor_offsets")
            w = lay.slice("neighbor_velocities")
            obs[:, 0, x.start + D : x.start + 2 * D] = obs[:, 0, x.start : x.start + D]
            obs[:, 0, w.start + D : w.start + 2 * D] = obs[:, 0, w.start : w.start + D]
    z = lay.slice("partner_offset")
    obs[0, 0, z] = 0.0  # no partner offset: the world axes
    if D == 3:
        obs[-1, -1, z] = (0.0, 0.0, 3.0)  # straight up: the other branch of the frame
        obs[-1, 0, z] = (1e-9, 0.0, -2.0)
    return obs


CASES = [
    dict(),
    dict(feedforward=False, threat_neighbors=0),
    dict(approach_horizon=0.0, threat_neighbors=2, max_accel=3.0),
    dict(w_band=0.3, w_cohesion=0.5, accel_scale=7.0, tca_horizon=0.2),
]


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("case", range(len(CASES)))
@pytest.mark.parametrize("n_uavs", [2, 12])
def test_pair_interface_kernels_equal_numpy(dim, case, n_uavs):
    K = 0 if n_uavs == 2 else 5
    cfg = make_config("paper", n_uavs=n_uavs, dim=dim, obs_neighbors=K, pair_accel_limit=40.0)
    params = dict(CASES[case])
    if K == 0:
        params["threat_neighbors"] = 0
    itf = make_interface("pair", cfg, **params)
    rng = np.random.default_rng(case + 10 * dim + n_uavs)
    B, M = 4, 6
    obs = _observations(rng, itf, B, M)
    assert same(itf.encode(obs), ref.encode(itf, obs))
    assert same(itf.encode(obs[0, 0]), ref.encode(itf, obs[0, 0]))  # one row
    action = rng.uniform(-1.5, 1.5, (B, M, dim))
    assert same(itf.decode(obs, action), ref.decode(itf, obs, action))
    info = {
        "pair_error": rng.normal(0.0, 2.0, (B, M)),
        "min_separation": rng.uniform(0.0, 12.0, (B, M)),
        "diverged": np.array([False, True, False, False]),
    }
    for o in (obs, None):
        assert same(itf.reward(None, info, action, o), ref.reward(itf, info, action, o))
    # one row: scalar infos (a swarm's divergence flag with its row's error and separation)
    row = {k: v[1, 2] if k != "diverged" else v[1] for k, v in info.items()}
    whole = itf.reward(None, info, action, obs)
    assert same(itf.reward(None, row, action[1, 2], obs[1, 2]), whole[1, 2])
    # per-row divergence flags give what the per-swarm ones give
    per_row = dict(info, diverged=np.repeat(info["diverged"], M).reshape(B, M))
    assert same(itf.reward(None, per_row, action, obs), whole)
