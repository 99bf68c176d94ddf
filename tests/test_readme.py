"""The README is a contract: CI runs its commands, and its Python examples run."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

import baselines
from pairflock_env import parallel_env

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def _blocks(lang: str, text: str = README) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", text, flags=re.S)


def _section(title: str) -> str:
    """The README text under the level-2 heading ``title`` (up to the next one)."""
    match = re.search(rf"^## {re.escape(title)}\n(.*?)(?=^## |\Z)", README, flags=re.S | re.M)
    assert match, f"the README has no section {title!r}"
    return match.group(1)


def test_ci_runs_the_readme_install_and_test_commands():
    quick_start = _blocks("bash")[0].strip().splitlines()
    assert len(quick_start) == 2, "the quick start is exactly two commands: install, test"
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    for cmd in quick_start:
        assert cmd in ci, f"{cmd!r} is not run by .ci/run"


def test_python_quick_start_runs(capsys):
    code = _blocks("python")[0]
    exec(compile(code, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert "pair distance" in out
    dist = float(re.search(r"pair distance ([0-9.]+) m", out).group(1))
    assert abs(dist - 5.0) < 0.5  # the sliding-mode pair holds d_m = 5 m


def test_the_readme_controller_registers_by_name_and_holds_the_pair():
    (code,) = _blocks("python", _section("Add a controller"))
    before = set(baselines.POLICIES)
    try:
        exec(compile(code, "README.md", "exec"), {})
        env = parallel_env(preset="paper", n_uavs=20, horizon=20.0)
        policy = baselines.make_pair_policy("ff_pd", env, k_p=9.0)
        obs, infos = env.reset(seed=0)
        while env.agents:
            obs, _, _, _, infos = env.step({a: policy.predict(obs[a])[0] for a in env.agents})
    finally:  # the example adds to the registry; other tests see it as it was
        for name in set(baselines.POLICIES) - before:
            del baselines.POLICIES[name]
    errors = [infos[a]["pair_error"] for a in ("uav_0", "uav_1")]
    assert np.all(np.abs(errors) < 0.5), errors  # inside the 0.5 m band after 20 s
