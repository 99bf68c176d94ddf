"""Outside RL clients on the public API, as docs/clients.md shows them: SB3, TorchRL
(PettingZoo wrapper for the parallel and AEC envs, GymEnv), SuperSuit, Tianshou. RLlib needs
its own Gymnasium and runs in tests/test_clients_rllib.py."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from clients_docs import examples, run_example

import pairflock_env

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def test_every_documented_client_has_an_example():
    for section in ("stable-baselines3", "TorchRL", "RLlib", "SuperSuit", "Tianshou"):
        assert examples(section), section


def test_sb3_example():
    pytest.importorskip("stable_baselines3")
    ns = run_example("stable-baselines3")
    assert ns["model"].num_timesteps >= 512
    assert ns["venv"].num_rows == 2 * ns["venv"].num_swarms


@pytest.mark.parametrize("aec", [False, True])
@pytest.mark.parametrize("interface", ["world", "pair"])
def test_torchrl_pettingzoo_wrapper_builds_specs_and_rolls_out(aec, interface):
    PettingZooWrapper = pytest.importorskip("torchrl.envs.libs.pettingzoo").PettingZooWrapper
    check_env_specs = pytest.importorskip("torchrl.envs.utils").check_env_specs

    make = pairflock_env.env if aec else pairflock_env.parallel_env
    env = PettingZooWrapper(
        env=make(n_uavs=8, interface=interface, max_cycles=12), return_state=True, use_mask=aec
    )
    check_env_specs(env)
    td = env.rollout(30, break_when_any_done=False)  # across an episode end and a reset
    group = "uav_0" if aec else "uav"
    obs = td["next", group, "observation"].numpy()
    assert np.isfinite(obs).all() and np.isfinite(td["next", "state"].numpy()).all()
    partner = td["next", group, "info", "partner_index"].numpy()
    assert (partner == (1 if aec else np.array([1, 0]))).all()


def test_torchrl_example():
    pytest.importorskip("torchrl")
    ns = run_example("TorchRL", 0)
    assert ns["rollout"]["uav", "observation"].shape[:2] == (10, 2)


def test_torchrl_gymenv_example():
    pytest.importorskip("torchrl")
    ns = run_example("TorchRL", 1)
    assert ns["rollout"].batch_size[0] == 10


def test_supersuit_example():
    pytest.importorskip("supersuit")
    pytest.importorskip("stable_baselines3")
    ns = run_example("SuperSuit")
    assert ns["model"].num_timesteps >= 256


def test_supersuit_normalize_obs_on_both_interfaces():
    ss = pytest.importorskip("supersuit")
    for interface in ("world", "pair"):
        env = ss.normalize_obs_v0(
            pairflock_env.parallel_env(n_uavs=8, interface=interface, max_cycles=12)
        )
        obs, _ = env.reset(seed=0)
        for _ in range(5):
            assert all(((o >= 0) & (o <= 1)).all() for o in obs.values())
            obs, *_ = env.step({a: env.action_space(a).sample() for a in env.agents})


def test_tianshou_example():
    pytest.importorskip("tianshou")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ns = run_example("Tianshou")
    assert ns["obs"].shape[0] == 2  # two vectorised envs
