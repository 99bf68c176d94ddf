"""The import layers: the env imports neither controllers, evaluation nor training code, and
``baselines`` / ``train`` import only downwards.

    pairflock_env  <  baselines.controllers  <  baselines.evaluation  <  baselines.reporting
                   <  baselines.experiments (the CLIs)
                   <  train (which uses controllers, evaluation and reporting, not the CLIs)

Checked twice: statically (every ``import`` in every file, also inside functions) and, for
the env, by importing every module in a fresh interpreter and looking at ``sys.modules``.
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: layer -> the layers its modules may import (besides pairflock_env and third-party code)
ALLOWED = {
    "controllers": {"controllers"},
    "evaluation": {"controllers", "evaluation"},
    "reporting": {"controllers", "evaluation", "reporting"},
    "experiments": {"controllers", "evaluation", "reporting", "experiments"},
    "train": {"controllers", "evaluation", "reporting", "train"},
}
#: the top-level modules of ``baselines``: the package facade (the controllers' names) and
#: the launchers of the documented ``python -m baselines.<cli>`` commands
TOP_LEVEL = {
    "__init__": "controllers",
    "_moved": "controllers",
    "benchmark": "experiments",
    "reproduce": "experiments",
    "quadrotor_experiment": "experiments",
    "quadrotor_invariants": "experiments",
    "quadrotor_compare": "experiments",
    "safety_compare": "experiments",
}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> set[str]:
    """Every module ``path`` imports (relative imports resolved), at any depth."""
    source = path.read_text(encoding="utf-8")
    return _imports_of(source, _module_name(path), path.name == "__init__.py")


def _imports_of(source: str, name: str, is_package: bool = False) -> set[str]:
    package = name if is_package else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                mod = ".".join([*base, *([node.module] if node.module else [])])
            else:
                mod = node.module or ""
            out.add(mod)
            out.update(f"{mod}.{a.name}" for a in node.names)  # "from pkg import submodule"
    return out


def _layer(module: str) -> str | None:
    """The layer of a ``baselines``/``train`` module name (None for anything else)."""
    parts = module.split(".")
    if parts[0] == "train":
        return "train"
    if parts[0] != "baselines":
        return None
    if len(parts) == 1:
        return "controllers"  # the package facade: the controllers' names
    if parts[1] in ALLOWED:
        return parts[1]
    return TOP_LEVEL.get(parts[1], "controllers")  # an old alias path or a facade name


def _files(package: str) -> list[Path]:
    return sorted((ROOT / package).rglob("*.py"))


def test_the_env_never_imports_baselines_or_train_statically():
    bad = {
        str(f.relative_to(ROOT)): sorted(m for m in _imports(f) if _layer(m))
        for f in _files("pairflock_env")
    }
    assert not {f: m for f, m in bad.items() if m}


def test_the_env_never_imports_baselines_or_train_at_run_time():
    """Import every module of pairflock_env in a fresh interpreter (optional dependencies
    may be missing: those modules are skipped), then look at what got loaded."""
    code = """
import importlib, json, pkgutil, sys
import pairflock_env
skipped = []
for m in pkgutil.walk_packages(pairflock_env.__path__, "pairflock_env."):
    try:
        importlib.import_module(m.name)
    except ImportError as e:
        if (e.name or "").split(".")[0] in ("pairflock_env", "baselines", "train"):
            raise
        skipped.append(m.name)
print(json.dumps({"modules": sorted(sys.modules), "skipped": skipped}))
"""
    r = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=ROOT
    )
    assert r.returncode == 0, r.stderr[-2000:]
    loaded = json.loads(r.stdout.splitlines()[-1])["modules"]
    assert "pairflock_env.envs.parallel" in loaded  # the walk did import the views
    assert not [m for m in loaded if m.split(".")[0] in ("baselines", "train")]


def _own_layer(path: Path) -> str:
    rel = path.relative_to(ROOT).parts
    if rel[0] == "train":
        return "train"
    return rel[1] if rel[1] in ALLOWED else TOP_LEVEL[Path(rel[1]).stem]


@pytest.mark.parametrize("package", ["baselines", "train"])
def test_each_layer_imports_only_downwards(package):
    wrong = {}
    for f in _files(package):
        own = _own_layer(f)
        up = sorted(m for m in _imports(f) if _layer(m) and _layer(m) not in ALLOWED[own])
        if up:
            wrong[f"{f.relative_to(ROOT)} ({own})"] = up
    assert not wrong


def test_the_checker_sees_relative_and_nested_imports():
    """An evaluation module importing reporting - relatively, inside a function - is
    flagged; the facade ``baselines`` counts as the controllers."""
    source = "def f():\n    from ..reporting import tables\n    import train.run\n"
    found = _imports_of(source, "baselines.evaluation.rollout")
    assert {"baselines.reporting", "baselines.reporting.tables", "train.run"} <= found
    assert {_layer(m) for m in found} - ALLOWED["evaluation"] == {"reporting", "train"}
    assert _layer("baselines.experiments.benchmark") not in ALLOWED["train"]
    assert _layer("baselines") in ALLOWED["evaluation"]


def test_thread_pinning_loads_before_numpy():
    """``pin_threads`` must run before numpy loads, so importing it loads nothing heavy."""
    code = (
        "import sys; from baselines.evaluation.parallel import pin_threads; pin_threads();"
        "print(sorted(m for m in ('numpy', 'torch', 'numba', 'pairflock_env') if m in sys.modules))"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stdout.strip() == "[]", (r.stdout, r.stderr)


OLD_PATHS = {
    "baselines.rollout": ("rollout", "baselines.evaluation.rollout"),
    "baselines.sweep": ("run_jobs", "baselines.evaluation.jobs"),
    "baselines.specs": ("parse_policy", "baselines.evaluation.specs"),
    "baselines.io": ("write_csv", "baselines.evaluation.io"),
    "baselines.report": ("check_paper_claims", "baselines.reporting.criteria"),
    "baselines.figures": ("save_figure", "baselines.reporting.figures"),
    "baselines.quadrotor_figures": ("euler_figure", "baselines.reporting.quadrotor_figures"),
    "baselines.video": ("write_episode_video", "baselines.reporting.video"),
    "baselines.policies": ("PairPolicy", "baselines.controllers.base"),
    "baselines.sliding_mode": ("SlidingModeController", "baselines.controllers.sliding_mode"),
    "baselines.proportional": ("ProportionalController", "baselines.controllers.proportional"),
    "baselines.sb3_policy": ("SB3PairPolicy", "baselines.controllers.sb3"),
}


@pytest.mark.parametrize("old", sorted(OLD_PATHS))
def test_old_module_paths_warn_and_give_the_same_objects(old):
    import importlib

    name, new = OLD_PATHS[old]
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=f"{old} is deprecated"):
        mod = importlib.import_module(old)
    assert getattr(mod, name) is getattr(importlib.import_module(new), name)
    assert name in mod.__all__
    with pytest.raises(AttributeError, match="no attribute"):
        mod.no_such_name  # noqa: B018


def test_the_cli_paths_are_launchers_not_deprecated():
    import importlib

    for cli in ("benchmark", "reproduce", "quadrotor_experiment", "quadrotor_invariants"):
        with warnings.catch_warnings():
            warnings.simplefilter("error", DeprecationWarning)
            launcher = importlib.import_module(f"baselines.{cli}")
        impl = importlib.import_module(f"baselines.experiments.{cli}")
        assert launcher.main is impl.main
