"""The import layers and the import graph.

Layers: the env imports neither experiments nor training code, and ``baselines`` / ``train``
import only downwards::

    pairflock_env  <  baselines.runtime  <  baselines.controllers  <  baselines.evaluation
                   <  baselines.reporting  <  baselines.experiments (and the launchers
                      beside baselines/__init__.py)
    baselines.evaluation  <  baselines.export (a policy for a flight controller)
                   <  train (runtime, controllers, evaluation and reporting; no experiment)

``baselines.runtime`` (files, run records, thread pinning, processes, the CLI error path) is
the bottom of ``baselines`` and imports no other first-party code. Checked statically (every
``import`` in every file, also inside functions) and, for the env, by importing every module
in a fresh interpreter and looking at ``sys.modules``. The graph of the three packages has no
cycle, and a launcher loads nothing heavy before it pins the threads.
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("pairflock_env", "baselines", "train")

#: layer -> the layers its modules may import (besides pairflock_env and third-party code)
ALLOWED = {
    "runtime": {"runtime"},
    "controllers": {"runtime", "controllers"},
    "evaluation": {"runtime", "controllers", "evaluation"},
    "reporting": {"runtime", "controllers", "evaluation", "reporting"},
    "experiments": {"runtime", "controllers", "evaluation", "reporting", "experiments"},
    # a trained policy exported for a flight controller (its parity checks roll it out)
    "export": {"runtime", "controllers", "evaluation", "export"},
    "train": {"runtime", "controllers", "evaluation", "reporting", "train"},
}
#: the documented commands ``python -m baselines.<name>``: launchers of the experiments
LAUNCHERS = (
    "benchmark",
    "reproduce",
    "quadrotor_experiment",
    "quadrotor_invariants",
    "quadrotor_compare",
    "safety_compare",
)


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
    if parts[1] in LAUNCHERS:
        return "experiments"
    return "controllers"  # a name of the facade (baselines.make_pair_policy)


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
    if len(rel) == 2:  # baselines/__init__.py or a launcher
        return "experiments" if Path(rel[1]).stem in LAUNCHERS else "controllers"
    return rel[1]


@pytest.mark.parametrize("package", ["baselines", "train"])
def test_each_layer_imports_only_downwards(package):
    wrong = {}
    for f in _files(package):
        own = _own_layer(f)
        up = sorted(m for m in _imports(f) if _layer(m) and _layer(m) not in ALLOWED[own])
        if up:
            wrong[f"{f.relative_to(ROOT)} ({own})"] = up
    assert not wrong


def test_runtime_is_the_bottom_of_baselines():
    """``baselines.runtime`` imports no other first-party code (the env neither)."""
    wrong = {
        str(f.relative_to(ROOT)): sorted(
            m for m in _imports(f) if m.split(".")[0] in PACKAGES and _layer(m) != "runtime"
        )
        for f in _files("baselines/runtime")
    }
    assert not {f: m for f, m in wrong.items() if m}


def test_the_checker_sees_relative_and_nested_imports():
    """An evaluation module importing reporting - relatively, inside a function - is
    flagged; the facade ``baselines`` counts as the controllers; a launcher as an
    experiment; runtime as the bottom."""
    source = "def f():\n    from ..reporting import tables\n    import train.run\n"
    found = _imports_of(source, "baselines.evaluation.rollout")
    assert {"baselines.reporting", "baselines.reporting.tables", "train.run"} <= found
    assert {_layer(m) for m in found} - ALLOWED["evaluation"] == {"reporting", "train"}
    assert _layer("baselines.experiments.benchmark") not in ALLOWED["train"]
    assert _layer("baselines.benchmark") not in ALLOWED["train"]
    assert _layer("baselines") in ALLOWED["evaluation"]
    assert _layer("baselines.runtime.files") in ALLOWED["controllers"]
    assert _layer("baselines.controllers") not in ALLOWED["runtime"]


# --------------------------------------------------------------------------- cycles
def _graph() -> dict[str, set[str]]:
    """Module -> the first-party modules it imports (at any depth), as module names."""
    files = [f for pkg in PACKAGES for f in _files(pkg)]
    modules = {_module_name(f) for f in files}
    graph: dict[str, set[str]] = {}
    for f in files:
        deps = set()
        for m in _imports(f):
            # "from a.b import c": the module a.b.c if there is one, else a.b
            while m and m not in modules:
                m = m.rpartition(".")[0]
            if m and m != _module_name(f):
                deps.add(m)
        graph[_module_name(f)] = deps
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


@pytest.mark.parametrize("package", PACKAGES)
def test_no_import_cycle(package):
    """No two modules import each other, directly or through others (imports inside
    functions count: a cycle hidden there is still one)."""
    found = [c for c in _cycles(_graph()) if any(m.split(".")[0] == package for m in c)]
    assert not found, f"import cycles: {found}"


def test_the_cycle_finder_finds_one():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


# --------------------------------------------------------------------------- launchers
@pytest.mark.parametrize(
    "module",
    [
        "baselines.runtime.threads",
        *(f"baselines.{name}" for name in LAUNCHERS),
        "train.__main__",
        "train.evaluate.__main__",
        "train.imitate.__main__",
        "train.sweep.__main__",
        "train.sweep.worker",
    ],
)
def test_a_launcher_loads_nothing_heavy_before_it_pins_the_threads(module):
    """Each command's launcher pins one thread per process before numpy, numba or torch
    load, so importing it (and the thread pinning) loads none of them."""
    code = (
        f"import importlib, sys; importlib.import_module({module!r});"
        "print(sorted(m for m in ('numpy', 'torch', 'numba', 'pairflock_env') if m in sys.modules))"
    )
    r = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=ROOT
    )
    assert r.returncode == 0 and r.stdout.strip() == "[]", (r.stdout, r.stderr)
