"""init_model: a run that starts from a saved policy's weights (fine-tuning)."""

import pytest

from baselines.controllers.zoo import resolve_model

pytest.importorskip("stable_baselines3")

import torch
from stable_baselines3.common.save_util import load_from_zip_file

from train.model import build_model
from train.run import make_vec_env
from train.settings import RunSettings


def _settings(**kw):
    base = dict(
        env={"n_uavs": 20, "pair_accel_limit": 50.0, "obs_neighbors": 12, "max_cycles": 50},
        interface="pair",
        interface_params={"decision_period": 5, "w_effort": 0.02, "w_band": 0.2},
        num_swarms=1,
        total_steps=64,
        eval_every=0,
        checkpoint_every=0,
        eval_baselines=[],
        hyperparameters={"n_steps": 16, "batch_size": 32},
    )
    return RunSettings(**{**base, **kw})


def test_init_model_copies_the_packaged_policys_weights():
    s = _settings(init_model="pair_n20_a50")
    model = build_model(s, make_vec_env(s))
    _, params, _ = load_from_zip_file(resolve_model("pair_n20_a50"), device="cpu")
    got = model.policy.state_dict()
    assert set(got) == set(params["policy"])
    assert all(torch.equal(got[k], v) for k, v in params["policy"].items())
    fresh = build_model(_settings(), make_vec_env(_settings()))
    assert not all(torch.equal(fresh.policy.state_dict()[k], v) for k, v in got.items())
    assert "init_model" not in _settings().to_dict()  # runs without it store what they stored


def test_bad_init_models_are_named():
    with pytest.raises(ValueError, match="init_model='no_such_model' is invalid"):
        _settings(init_model="no_such_model")
    with pytest.raises(TypeError, match="init_model=3 is invalid"):
        _settings(init_model=3)
    s = _settings(init_model="pair_n20_a50", env={"n_uavs": 20, "obs_neighbors": 4})
    with pytest.raises(ValueError, match="observation_space"):
        build_model(s, make_vec_env(s))
