"""RecordEpisode on the SB3 VecEnv: an SB3 VecEnvWrapper, one recording per swarm and episode
with SB3's auto-reset, the same steps as the core ran."""

from __future__ import annotations

import os

import numpy as np
import pytest

vec_env = pytest.importorskip("stable_baselines3.common.vec_env")

from pairflock_env.envs.record import RecordEpisode, find_core  # noqa: E402
from pairflock_env.envs.sb3 import PairFlockSB3VecEnv  # noqa: E402
from pairflock_env.recording import open_recording  # noqa: E402


def test_sb3_vecenv(tmp_path):
    venv = PairFlockSB3VecEnv(num_swarms=2, interface="world", n_uavs=6, max_cycles=6)
    env = RecordEpisode(venv, tmp_path, controller="zero", every=2)
    assert isinstance(env, vec_env.VecEnvWrapper) and isinstance(env, RecordEpisode)
    assert env.num_envs == 4 and env.get_attr("swarm") == [0, 0, 1, 1]
    core = find_core(env)
    env.seed(7)
    env.reset()
    seen = {0: core.q.copy()}
    for k in range(1, 9):
        _, _, dones, _ = env.step(np.zeros((4, 2), np.float32))
        if k <= 6:
            seen[k] = core.q.copy() if k < 6 else None  # step 6 ends: auto-reset follows
    assert dones.shape == (4,)
    env.close()
    assert sorted(os.listdir(tmp_path)) == [f"swarm{b}_ep{n}.pfrec" for b in (0, 1) for n in (0, 1)]
    for b in (0, 1):
        rec = open_recording(tmp_path / f"swarm{b}_ep0.pfrec")
        assert rec.complete and rec["step"].tolist() == [0, 2, 4, 6]
        for k, step in enumerate([0, 2, 4]):
            np.testing.assert_allclose(rec["positions"][k], seen[step][b], atol=1e-4)
        second = open_recording(tmp_path / f"swarm{b}_ep1.pfrec")
        assert not second.complete and second["step"].tolist() == [0, 2]
