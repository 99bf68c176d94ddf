"""record_core and the rollout callback, for the command lines' ``--record``: a rollout of a
batched core writes one recording per seed, holding the rollout's own trace."""

from __future__ import annotations

import numpy as np
import pytest

from baselines import make_pair_policy
from baselines.evaluation.rollout import rollout
from pairflock_env import PairFlockCore, make_config
from pairflock_env.recording import open_recording
from pairflock_env.recording.episodes import CoreRecorder, record_core


def test_rollout_callback_writes_one_recording_per_seed(tmp_path):
    cfg = make_config("paper", n_uavs=8, max_cycles=40)
    seeds = [3, 11]
    rec = CoreRecorder(tmp_path, controller="smc", every=5, name="seed{seed}", seeds=seeds)
    with rec:
        tr = rollout(cfg, make_pair_policy("smc", cfg), seeds, record_rows=[0, 1], on_step=rec)
    assert [p.rsplit("/", 1)[1] for p in rec.paths] == ["seed3.pfrec", "seed11.pfrec"]
    for b, seed in enumerate(seeds):
        r = open_recording(tmp_path / f"seed{seed}.pfrec")
        assert r.complete and r.seed == seed and r.controller == "smc"
        steps = np.asarray(r["step"])
        assert steps.tolist() == list(range(0, 41, 5))
        np.testing.assert_allclose(r["positions"], tr.positions[b][steps], atol=1e-4)
        np.testing.assert_allclose(r["pair_error"][:, 0], tr.pair_error[b, 0, steps], atol=1e-5)
        np.testing.assert_allclose(r["leader_position"], tr.leader_positions[b][steps], atol=1e-4)


def test_rollout_cut_short_is_incomplete(tmp_path):
    cfg = make_config("paper", n_uavs=6, max_cycles=100)
    with CoreRecorder(tmp_path, seeds=[0]) as rec:
        rollout(cfg, make_pair_policy("zero", cfg), [0], steps=10, on_step=rec)
    r = open_recording(rec.paths[0])
    assert not r.complete and r.steps == 11
    assert r.manifest["stopped"] == "closed before the episode ended"


def test_record_core_hooks_and_unhooks(tmp_path):
    core = PairFlockCore(preset="paper", n_uavs=6, max_cycles=4, num_swarms=2)
    zero = np.zeros((2, core.n_agents, 2))
    with record_core(core, tmp_path, controller="zero", swarms=[1]) as rec:
        core.reset(seed=[4, 5])
        for _ in range(4):
            core.step(zero)
        core.reset_rows([1])
        core.step(zero)
    assert "step" not in core.__dict__
    core.step(zero)  # no longer recorded
    first, second = (open_recording(p) for p in rec.paths)
    assert first.complete and first.steps == 5 and first.seed == 5
    assert not second.complete and second.steps == 2
    assert second.manifest["metadata"]["seeded"] == 5
    assert second.manifest["metadata"]["resets_since_seed"] == 1


def test_one_recorder_one_core(tmp_path):
    a = PairFlockCore(preset="paper", n_uavs=6)
    b = PairFlockCore(preset="paper", n_uavs=6)
    rec = record_core(a, tmp_path)
    with pytest.raises(ValueError, match="another core"):
        rec.attach(b)
    with pytest.raises(ValueError, match="seeds has 2 entries"):
        CoreRecorder(tmp_path / "x", seeds=[1, 2]).bind(a)
    rec.close()


def test_several_recorders_fill_one_folder(tmp_path):
    """Like a command line's jobs: each records its own seeds into the run's folder."""
    cfg = make_config("paper", n_uavs=6, max_cycles=5)
    for block in ([0, 1], [2]):
        with CoreRecorder(tmp_path, name="seed{seed}", seeds=block, allow_existing=True) as rec:
            rollout(cfg, make_pair_policy("zero", cfg), block, on_step=rec)
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"seed{s}.pfrec" for s in (0, 1, 2)]
    again = CoreRecorder(tmp_path, name="seed{seed}", seeds=[2], allow_existing=True)
    with pytest.raises(FileExistsError, match=r"seed2\.pfrec"), again:
        rollout(cfg, make_pair_policy("zero", cfg), [2], on_step=again)
