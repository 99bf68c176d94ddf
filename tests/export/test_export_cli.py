"""pairflock-export (python -m baselines.export): the export folder, --force, --no-onnx,
--check, and bad input ending in one line on stderr with exit status 2."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

pytest.importorskip("stable_baselines3")

import export_cases as cases
from stable_baselines3 import PPO

from baselines.controllers.sb3 import METADATA_KEY
from baselines.export import build, cli


def _fails(argv, capsys, *needles):
    with pytest.raises(SystemExit) as e:
        cli.main(argv)
    err = capsys.readouterr().err
    assert e.value.code == 2
    assert err.count("\n") == 1 and err.startswith("pairflock-export: error: "), err
    for needle in needles:
        assert needle in err, (needle, err)
    return err


def test_export_writes_the_four_files_and_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "cf"
    assert cli.main(["sb3:pair_n20_a50", "--out", str(out), "--no-onnx"]) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(build.FILES[1:])
    doc = json.loads((out / build.CONTRACT).read_text())
    assert doc["model"]["name"] == "pair_n20_a50" and "policy.onnx" not in doc["files"]
    _fails(["sb3:pair_n20_a50", "--out", str(out)], capsys, "not empty", "--force")
    (out / "notes.txt").write_text("mine")
    with_onnx = build.onnx.onnx is not None
    argv = ["sb3:pair_n20_a50", "--out", str(out), "--force"]
    assert cli.main(argv if with_onnx else [*argv, "--no-onnx"]) == 0
    assert (out / "notes.txt").read_text() == "mine"  # --force replaces only the export
    assert (out / build.ONNX).is_file() == with_onnx


def test_bad_input_is_one_line_and_status_2(tmp_path, capsys):
    out = str(tmp_path / "x")
    _fails(["sb3:no_such_policy", "--out", out], capsys, "no_such_policy", "does not exist")
    _fails(["smc", "--out", out], capsys, "only a trained policy")
    _fails(["sb3:", "--out", out], capsys, "sb3:")
    _fails(["sb3:pair_n20_a50"], capsys, "--out")
    _fails(["sb3:pair_n20_a50", "--out", out, "--check", "-1"], capsys, "--check")
    (tmp_path / "file").write_text("")
    _fails(["sb3:pair_n20_a50", "--out", str(tmp_path / "file")], capsys, "is a file")


def _saved(tmp_path, meta):
    env = cases.Spaces(*cases.spaces_of("sb3:pair_n20_a50"))
    model = PPO("MlpPolicy", env, device="cpu", policy_kwargs={"net_arch": [8]})
    if meta is not None:
        setattr(model, METADATA_KEY, meta)
    path = tmp_path / "model.zip"
    model.save(path)
    return f"sb3:{path}"


def test_models_that_are_not_exportable_are_refused(tmp_path, capsys):
    out = str(tmp_path / "x")
    _fails([_saved(tmp_path, None), "--out", out], capsys, "is not a pairflock model")
    stored = cases.loaded("sb3:pair_n20_a50").meta
    other = {**stored, "algo": "A2C"}
    _fails([_saved(tmp_path, other), "--out", out], capsys, "'A2C'", "PPO, SAC, TD3")


@pytest.mark.skipif(build.onnx.onnx is None, reason="needs the export extra (onnx)")
def test_check_compares_onnx_and_c_with_sb3(tmp_path, capsys):
    pytest.importorskip("onnxruntime")
    spec = cases.tiny("sac-pair-2d")
    assert cli.main([spec, "--out", str(tmp_path / "e"), "--check", "300"]) == 0
    text = capsys.readouterr().out
    assert "onnx_vs_predict" in text and "passed: True" in text


def test_python_dash_m_runs_the_same_command():
    res = subprocess.run(
        [sys.executable, "-m", "baselines.export", "--help"], capture_output=True, text=True
    )
    assert res.returncode == 0 and "pairflock-export" in res.stdout and "--out" in res.stdout
