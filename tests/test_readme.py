"""The README is a contract: CI runs its commands, and its Python example runs.

The controller a user adds is shown (and run) on the extending page: tests/test_docs.py."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def _blocks(lang: str, text: str = README) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", text, flags=re.S)


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
