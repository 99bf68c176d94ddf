"""The benchmark CLI with a learned policy (``sb3:<path>``); needs stable-baselines3."""

from __future__ import annotations

import json

import pytest

from baselines import POLICIES
from baselines.benchmark import main

pytest.importorskip("stable_baselines3")

from train.settings import settings_from_sources

TINY = ["--suite", "quick", "--n-uavs", "8", "--horizon", "2", "--seeds", "2", "--quiet"]


def test_learned_policy_runs_next_to_the_analytic_ones(tmp_path):
    """``sb3:<path>``: a (barely) trained model from ``python -m train`` is benchmarked on the
    same seeds as smc, and its label names it in the results."""
    pytest.importorskip("stable_baselines3")
    train_run = pytest.importorskip("train.run")

    if "sb3:" not in POLICIES:
        pytest.skip("this install has no sb3: policies")
    settings = settings_from_sources(
        dict(
            env={"n_uavs": 8, "max_cycles": 50},
            num_swarms=2,
            total_steps=64,
            eval_every=0,
            checkpoint_every=0,
            eval_baselines=[],
            tensorboard=False,
            hyperparameters={
                "n_steps": 16,
                "batch_size": 32,
                "n_epochs": 1,
                "policy_kwargs": {"net_arch": [8]},
            },
        )
    )
    train_run.train(settings, tmp_path / "run", quiet=True)
    model = tmp_path / "run" / "final_model.zip"
    spec = f"sb3:{model}"
    out = tmp_path / "b"
    assert (
        main([*TINY, "-p", "smc", spec, "--workers", "1", "--no-figures", "--out", str(out)]) == 0
    )
    res = json.loads((out / "results.json").read_text())
    assert [p["label"] for p in res["policies"]] == ["smc", spec]
    runs = {(r["policy"], r["seed"]) for r in res["runs"]}
    assert runs == {(p, s) for p in ("smc", spec) for s in (0, 1)}
