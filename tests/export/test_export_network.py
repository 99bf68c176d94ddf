"""The policy network read from an SB3 model (baselines.export.network) computes what SB3's
predict(obs, deterministic=True) computes: on the committed policies over the observations
they meet in their own task, and on small models of every exported algorithm."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

import export_cases as cases
from gymnasium import spaces
from stable_baselines3 import A2C, PPO
from torch import nn

from baselines.export.network import policy_network


@pytest.mark.slow
@pytest.mark.parametrize("name", cases.MODELS)
def test_network_equals_predict_on_the_policys_own_observations(name):
    spec = f"sb3:{name}"
    features, net, _ = cases.reference(spec)
    assert len(features) >= cases.N_OBS
    got = cases.loaded(spec).network.forward(features)
    assert got.dtype == np.float32 and got.shape == net.shape
    np.testing.assert_allclose(got, net, rtol=0, atol=cases.TOL)


@pytest.mark.parametrize("case", sorted(cases.TINY))
def test_network_of_every_algorithm_and_output_transform(case):
    """SAC and TD3 (tanh, then SB3's unscale), PPO with a squashed gSDE mean, PPO with ReLU
    and the world interface; random features across the whole box."""
    lp = cases.loaded(cases.tiny(case))
    rng = np.random.default_rng(0)
    x = rng.uniform(-5, 5, (2000, lp.network.input_size)).astype(np.float32)
    want, _ = lp.policy.model.predict(x, deterministic=True)
    np.testing.assert_allclose(lp.network.forward(x), want, rtol=0, atol=1e-6)
    assert lp.network.output == ("clip" if case == "ppo-world-relu" else "unscale")


def _env():
    box = spaces.Box
    return cases.Spaces(box(-5.0, 5.0, (7,), np.float32), box(-1.0, 1.0, (2,), np.float32))


def test_what_the_exporter_cannot_port_is_refused_by_name():
    elu = dict(activation_fn=nn.ELU, net_arch=[8])
    with pytest.raises(ValueError, match="ELU"):
        policy_network(PPO("MlpPolicy", _env(), device="cpu", policy_kwargs=elu))
    with pytest.raises(TypeError, match="must be PPO, SAC or TD3"):
        policy_network(A2C("MlpPolicy", _env(), device="cpu"))
    discrete = cases.Spaces(spaces.Box(-1.0, 1.0, (3,)), spaces.Discrete(4))
    with pytest.raises(ValueError, match="only a flat Box"):
        policy_network(PPO("MlpPolicy", discrete, device="cpu"))
