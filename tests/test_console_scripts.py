"""Every CLI has a console script (pyproject ``[project.scripts]``) whose ``--help`` works."""

from __future__ import annotations

import importlib.metadata
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: the documented ``python -m`` commands and the console script each one must have
EXPECTED = {
    "pairflock-benchmark": "baselines.benchmark:main",
    "pairflock-reproduce": "baselines.reproduce:main",
    "pairflock-quadrotor": "baselines.quadrotor_experiment:main",
    "pairflock-quadrotor-invariants": "baselines.quadrotor_invariants:main",
    "pairflock-quadrotor-compare": "baselines.quadrotor_compare:main",
    "pairflock-safety-compare": "baselines.safety_compare:main",
    "pairflock-train": "train.__main__:main",
    "pairflock-evaluate": "train.evaluate.__main__:main",
    "pairflock-sweep": "train.sweep.__main__:main",
    "pairflock-imitate": "train.imitate.__main__:main",
    "pairflock-replay": "pairflock_env.replay.__main__:main",
    "pairflock-export": "baselines.export.__main__:main",
}


def _declared() -> dict[str, str]:
    """``[project.scripts]`` of pyproject.toml."""
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    section = re.search(r"^\[project\.scripts\]\n(.*?)(?=^\[)", text, flags=re.S | re.M)
    assert section, "pyproject.toml has no [project.scripts]"
    return dict(re.findall(r'^([\w-]+)\s*=\s*"([^"]+)"', section.group(1), flags=re.M))


def test_every_cli_has_a_console_script():
    declared = _declared()
    assert {k: declared.get(k) for k in EXPECTED} == EXPECTED
    installed = {
        ep.name: ep.value
        for ep in importlib.metadata.entry_points(group="console_scripts")
        if ep.dist is not None and ep.dist.name == "pairflock-env"
    }
    missing = {k: v for k, v in declared.items() if installed.get(k) != v}
    assert not missing, (
        f"installed scripts differ from pyproject (reinstall: pip install -e .): {missing}"
    )


def test_every_console_script_answers_help():
    """All at once, in parallel: each prints its usage and exits 0."""
    bindir = Path(sys.executable).parent
    env = dict(os.environ, OMP_NUM_THREADS="1", MPLBACKEND="Agg")
    procs = {
        name: subprocess.Popen(
            [str(bindir / name), "--help"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
            cwd=ROOT.parent,  # outside the checkout: the installed package answers
        )
        for name in _declared()
    }
    for name, proc in procs.items():
        out, err = proc.communicate(timeout=60)
        assert proc.returncode == 0, (name, err[-2000:])
        assert out.startswith("usage:"), (name, out[:200])
