"""A plug-in of each seam (vehicle model, safety filter, leader trajectory, observation
field), registered from tests/plugins/pairflock_toys.py without editing the package, runs
through every view, the benchmark command line and the generated config docs.

Each check runs in a fresh interpreter with ``PAIRFLOCK_PLUGINS=pairflock_toys`` (how a
plug-in reaches fresh processes such as the benchmark's workers), so the toys never enter
this test process's registries.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ENV = {
    **os.environ,
    "PAIRFLOCK_PLUGINS": "pairflock_toys",
    "PYTHONPATH": os.pathsep.join([str(ROOT / "tests" / "plugins"), str(ROOT)]),
    "OMP_NUM_THREADS": "1",
    "MPLBACKEND": "Agg",
}
TOYS = dict(
    n_uavs=12,
    max_cycles=60,
    dynamics="toy_dragged",
    safety_filter="toy_clip",
    leader="toy_circle",
    obs_extra=("toy_leader_distance",),
    toy_clip_accel=5.0,
)


def _run(code: str) -> dict:
    r = subprocess.run(
        [sys.executable, "-c", code], env=ENV, cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


def test_the_toys_run_through_every_view_and_the_official_checkers():
    code = f"""
import json
import numpy as np
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test
from stable_baselines3.common.env_checker import check_env as sb3_check
from pairflock_env import PairFlockGymEnv, PairFlockGymVectorEnv, env, parallel_env
from pairflock_env.envs.sb3 import PairFlockSB3VecEnv

kw = {TOYS!r}
out = {{}}
par = parallel_env(**kw)
parallel_api_test(parallel_env(**kw), num_cycles=20)
obs, _ = par.reset(seed=0)
core = par.core
for _ in range(40):
    obs, rew, term, trunc, infos = par.step({{a: np.ones(2) for a in par.agents}})
lq, _ = core.leader_state()
want = np.linalg.norm(lq[0] - core.q[0, core.agent_uavs], axis=-1)
got = [float(par.layout.get(obs[a], "toy_leader_distance")[0]) for a in par.agents]
out["obs_matches"] = bool(np.allclose(got, want, rtol=1e-6))
out["clipped_to"] = float(np.linalg.norm(core.pair_command, axis=-1).max())
out["filter_active"] = bool(all(infos[a]["safety_active"] for a in par.agents))
out["leader_radius"] = float(np.linalg.norm(lq[0] - np.asarray(par.config.leader_position)))
out["in_space"] = all(par.observation_space(a).contains(obs[a]) for a in par.agents)
check_env(PairFlockGymEnv(**kw), skip_render_check=True)
sb3_check(PairFlockGymEnv(**kw))
aec = env(**kw)
aec.reset(seed=1)
for agent in aec.agent_iter(30):
    aec.step(None if any(aec.last()[2:4]) else np.zeros(2))
vec = PairFlockGymVectorEnv(num_envs=3, **kw)
vec.reset(seed=2)
vec.step(np.zeros(vec.action_space.shape))
sb3 = PairFlockSB3VecEnv(num_swarms=2, **kw)
sb3.reset()
_, r, _, _ = sb3.step(np.zeros((sb3.num_envs, 2)))
out["sb3_finite"] = bool(np.isfinite(r).all())
print(json.dumps(out))
"""
    out = _run(code)
    assert out["obs_matches"] and out["in_space"] and out["sb3_finite"]
    assert out["clipped_to"] <= 5.0 + 1e-9 and out["filter_active"]  # the toy filter acts
    assert abs(out["leader_radius"] - 30.0) < 1e-9  # the toy leader circles at its radius


def test_the_toys_declare_their_parameters_like_built_in_fields():
    code = """
import json
from pairflock_env import make_config
from pairflock_env.config.docs import render
from pairflock_env.dynamics import VEHICLES
from pairflock_env.swarm.leader import LEADERS, Leader
out = {}
cfg = make_config("paper", dynamics="toy_dragged", toy_drag=0.5)
out["drag"] = cfg.toy_drag
out["stored"] = make_config("paper").to_dict()["toy_circle_radius"]
try:
    make_config("paper", toy_drag=-1.0)
except ValueError as e:
    out["bad"] = str(e)
try:
    make_config("paper", dynamics="toy_draged")
except ValueError as e:
    out["unknown"] = str(e)
try:
    LEADERS.register(Leader(name="toy_circle", doc="again", trajectory=None, speed_bound=None))
except ValueError as e:
    out["twice"] = str(e)
text = render()
out["docs"] = all(s in text for s in ("`toy_drag`", "`toy_clip_accel`", "`toy_circle_radius`"))
out["choices"] = "'toy_dragged'" in text
print(json.dumps(out))
"""
    out = _run(code)
    assert out["drag"] == 0.5 and out["stored"] == 30.0
    assert out["bad"].startswith("toy_drag=-1.0 is invalid: must be a finite number in [0, 100]")
    assert "toy_dragged" in out["unknown"] and "registered already" in out["twice"]
    assert out["docs"] and out["choices"]


def test_the_benchmark_command_line_runs_the_toys(tmp_path):
    sets = [
        "--set",
        "dynamics=toy_dragged",
        "--set",
        "safety_filter=toy_clip",
        "--set",
        "leader=toy_circle",
        "--set",
        "toy_clip_accel=5,50",
    ]
    cmd = [sys.executable, "-m", "baselines.benchmark", "-p", "smc", "zero", "--n-uavs", "12"]
    cmd += [*sets, "--seeds", "1", "--horizon", "1", "--no-figures", "--quiet"]
    cmd += ["--workers", "2", "--out", str(tmp_path / "bench")]
    r = subprocess.run(cmd, env=ENV, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    with (tmp_path / "bench" / "results.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert {(row["policy"], row["toy_clip_accel"]) for row in rows} == {
        ("smc", "5"),
        ("smc", "50"),
        ("zero", "5"),
        ("zero", "50"),
    }
    peak = {
        row["toy_clip_accel"]: float(row["peak_accel"]) for row in rows if row["policy"] == "smc"
    }
    assert peak["5"] <= 5.0 + 1e-6 < peak["50"]  # the toy filter bounds sliding mode's command
