"""Packaged resources: the training configs and the committed policies resolve by name from
any folder, unknown names list the valid ones, and pyproject ships every file of both
folders (``.ci/wheel-check`` runs the same from an installed wheel)."""

from __future__ import annotations

import fnmatch
import os
from pathlib import Path

import pytest

from baselines import make_pair_policy
from baselines.controllers.sb3 import read_metadata
from baselines.controllers.zoo import find_packaged, model_names, resolve_model
from pairflock_env import make_config
from train import cli
from train.evaluate import cli as evaluate
from train.settings import config_names, load_yaml, resolve_config

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: pytest's own TOML reader
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
#: (package, folder, suffix) of each kind of packaged file
FOLDERS = {"model": ("baselines", "models", ".zip"), "config": ("train", "configs", ".yaml")}
RESOLVERS = {"model": (resolve_model, model_names), "config": (resolve_config, config_names)}


def _files(kind: str) -> list[Path]:
    package, folder, _ = FOLDERS[kind]
    return sorted(p for p in (ROOT / package / folder).iterdir() if p.is_file())


@pytest.mark.parametrize("kind", sorted(FOLDERS))
def test_every_packaged_file_resolves_by_name_from_another_folder(kind, tmp_path, monkeypatch):
    resolve, names = RESOLVERS[kind]
    suffix = FOLDERS[kind][2]
    files = _files(kind)
    assert names() == [p.name[: -len(suffix)] for p in files] and names()
    monkeypatch.chdir(tmp_path)
    for path in files:
        stem = path.name[: -len(suffix)]
        for given in (stem, path.name, Path(stem)):
            found = resolve(given)
            assert isinstance(found, Path) and found.samefile(path), (given, found)


@pytest.mark.parametrize("kind", sorted(FOLDERS))
def test_a_path_wins_over_a_packaged_name(kind, tmp_path, monkeypatch):
    resolve, names = RESOLVERS[kind]
    suffix = FOLDERS[kind][2]
    name = names()[0]
    monkeypatch.chdir(tmp_path)
    (tmp_path / f"{name}{suffix}").write_text("local")
    assert resolve(name) == Path(f"{name}{suffix}")  # with the suffix added
    assert resolve(f"{name}{suffix}") == Path(f"{name}{suffix}")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "other").write_text("local")
    assert resolve("sub/other") == Path("sub/other")  # as given, any suffix


@pytest.mark.parametrize("kind", sorted(FOLDERS))
def test_unknown_names_list_the_packaged_ones(kind, tmp_path, monkeypatch):
    resolve, names = RESOLVERS[kind]
    monkeypatch.chdir(tmp_path)
    near = names()[0][:-1]  # a typo of a real name gets a suggestion
    with pytest.raises(FileNotFoundError) as info:
        resolve(near)
    msg = str(info.value)
    assert f"{kind} {near!r} does not exist" in msg and f"did you mean {names()[0]!r}" in msg
    assert msg.endswith(", ".join(names()))
    # a path with a folder part is never looked up among the packaged names
    with pytest.raises(FileNotFoundError, match="no such file;") as info:
        resolve(f"elsewhere/{names()[0]}")
    assert str(info.value).endswith(", ".join(names()))
    with pytest.raises(TypeError, match=f"{kind} 3 is invalid"):
        resolve(3)
    with pytest.raises(ValueError, match=f"{kind} '' is invalid"):
        resolve("")


def test_find_packaged_names_the_folder_when_it_is_empty(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(FileNotFoundError, match=r"packaged things .*: none$"):
        find_packaged("x", package="baselines", folder="no_such_folder", suffix=".x", what="thing")


def test_pyproject_package_data_ships_every_packaged_file():
    """Each file of ``baselines/models`` and ``train/configs`` matches a package-data pattern
    of its package (the wheel and the sdist contain what the resolvers list)."""
    data = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    package_data = data["tool"]["setuptools"]["package-data"]
    for kind, (package, _, _) in FOLDERS.items():
        patterns = package_data.get(package, [])
        for path in _files(kind):
            rel = path.relative_to(ROOT / package).as_posix()
            assert any(fnmatch.fnmatchcase(rel, p) for p in patterns), (kind, rel, patterns)


def test_the_checkout_models_folder_is_the_packaged_one():
    """``models/<name>.zip`` (the documented path) is the packaged file: stored once."""
    for path in _files("model"):
        assert (ROOT / "models" / path.name).samefile(path)
    assert (ROOT / "models").resolve() == (ROOT / "baselines" / "models").resolve()


def test_packaged_names_load_through_the_public_entry_points(tmp_path, monkeypatch, capsys):
    """``--config NAME``, ``sb3:NAME`` and ``python -m train.evaluate NAME`` from a folder
    without the files; a bad name stops the CLIs with the list of valid ones."""
    monkeypatch.chdir(tmp_path)
    name = config_names()[0]
    assert load_yaml(name) == load_yaml(ROOT / "train" / "configs" / f"{name}.yaml")
    model = "pair_n20_a50"  # the README's policy
    assert read_metadata(model)["algo"] == "PPO"
    cfg = make_config("paper", n_uavs=20, obs_neighbors=12)
    assert "PPO" in repr(make_pair_policy(f"sb3:{model}", cfg))
    args = evaluate.build_parser().parse_args([model])
    evaluate._check_args(args, evaluate.build_parser())
    assert args.model.samefile(ROOT / "models" / f"{model}.zip")
    for main, argv, names in (
        (cli.main, ["--config", "no_such_config", "--out", str(tmp_path / "run")], config_names),
        (evaluate.main, ["no_such_model", "--out", str(tmp_path / "ev")], model_names),
    ):
        with pytest.raises(SystemExit) as info:
            main(argv)
        assert info.value.code == 2
        err = capsys.readouterr().err
        assert "'no_such_" in err and err.rstrip().endswith(", ".join(names())), err
    assert not os.listdir(tmp_path)  # nothing written


def test_ci_runs_the_wheel_check_with_the_declared_scripts():
    """``.ci/run`` calls ``.ci/wheel-check``, which reads the console scripts from pyproject
    (so the list cannot drift) and runs the packaged names from outside the checkout."""
    check = ROOT / ".ci" / "wheel-check"
    assert os.access(check, os.X_OK)
    assert ".ci/wheel-check" in [
        line.split("#")[0].strip() for line in (ROOT / ".ci" / "run").read_text().splitlines()
    ]
    text = check.read_text()
    assert "set -euo pipefail" in text and '["project"]["scripts"]' in text
    for command in (
        'pairflock-reproduce" --check',
        'pairflock-evaluate" pair_n20_a50',
        'pairflock-train" --config pair_n20_a50',
        "sb3:pair_n20_a50",
    ):
        assert command in text, command
