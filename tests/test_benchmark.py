"""The benchmark CLI: smoke test by subprocess, reproducibility, backends, specs, bad input."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from baselines import POLICIES, reproduce
from baselines.benchmark import main
from baselines.evaluation.specs import expand_scenarios, parse_policy, parse_scenario, slug
from baselines.experiments.benchmark import build_parser, resolve
from baselines.experiments.benchmark.figures import load_traces
from baselines.experiments.quadrotor.experiment import _settings
from baselines.experiments.quadrotor.experiment import build_parser as quad_parser

#: a tiny task: 8 UAVs, 2 s, so that each run is a fraction of a second
TINY = ["--suite", "quick", "--n-uavs", "8", "--horizon", "2", "--seeds", "2", "--quiet"]


def _cli(args, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, OMP_NUM_THREADS="1", MPLBACKEND="Agg")
    return subprocess.run(
        [sys.executable, "-m", "baselines.benchmark", *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_help_lists_suites_and_policy_syntax(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--help"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    for text in ("--suite", "paper", "robustness", "sb3:", "--backend", "--video", "--set"):
        assert text in out


def test_cli_twice_gives_byte_identical_results(tmp_path):
    args = [
        *TINY,
        "-p",
        "smc",
        "proportional:k_p=2",
        "zero",
        "--delay",
        "0",
        "3",
        "--workers",
        "2",
        "--no-figures",
    ]
    a, b = tmp_path / "a", tmp_path / "b"
    for out in (a, b):
        r = _cli([*args, "--out", str(out)], tmp_path)
        assert r.returncode == 0, r.stderr
    for name in ("results.csv", "results.json", "summary.md"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    # timestamps and timing live in run.json only
    ra, rb = (json.loads((d / "run.json").read_text()) for d in (a, b))
    assert set(ra["timestamps"]) == {"started_utc", "finished_utc"}
    assert "simulation_s" in ra["timing"] and ra["seeds"] == rb["seeds"] == [0, 1]
    assert ra["versions"]["numpy"] and "git_commit" in ra and ra["scenarios"][1]["config"]

    lines = (a / "results.csv").read_text().splitlines()
    header = lines[0].split(",")
    assert header[:6] == ["scenario", "preset", "dynamics", "dim", "n_uavs", "n_pairs"]
    assert {
        "partner_delay",
        "policy",
        "seed",
        "ss_mean_error",
        "effort",
        "chattering",
        "final_largest_component",
        "min_pair_separation",
    } <= set(header)
    assert len(lines) - 1 == 2 * 3 * 2  # scenarios x policies x seeds (one pair)
    res = json.loads((a / "results.json").read_text())
    assert [p["label"] for p in res["policies"]] == ["smc", "proportional:k_p=2", "zero"]
    assert "k_p=2.0" in res["policies"][1]["resolved"]
    assert [s["label"] for s in res["scenarios"]] == ["partner_delay=0", "partner_delay=3"]


@pytest.fixture(scope="module")
def figure_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("figs")
    assert (
        main(
            [
                *TINY,
                "--seeds",
                "1",
                "-p",
                "smc",
                "zero",
                "--workers",
                "1",
                "--video",
                str(out / "ep.gif"),
                "--video-policy",
                "zero",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    return out


def test_figures_video_and_same_initial_states(figure_run):
    figs = sorted(p.name for p in figure_run.glob("*.png"))
    assert figs == [
        "pair_error.png",
        "sliding_surface.png",
        "snapshots_nominal_smc.png",
        "steady_error.png",
        "steady_max_error.png",
    ]  # no snapshots of "zero"
    iio = pytest.importorskip("imageio.v3")
    frames = iio.imread(figure_run / "ep.gif")
    assert frames.ndim == 4 and frames.shape[0] > 1 and frames.shape[-1] in (3, 4)
    # every policy starts from the same initial state
    tr = load_traces(figure_run / "traces.npz")
    assert sorted(tr) == [(0, 0), (0, 1)]
    np.testing.assert_array_equal(tr[0, 1]["positions"][0], tr[0, 0]["positions"][0])
    assert not np.array_equal(tr[0, 1]["positions"][-1], tr[0, 0]["positions"][-1])
    assert "ep.gif" in json.loads((figure_run / "run.json").read_text())["outputs"]


def _run(out: Path, *extra: str) -> bytes:
    assert main([*TINY, "--workers", "1", "--no-figures", "--out", str(out), *extra]) == 0
    return (out / "results.csv").read_bytes()


def test_seed_blocks_do_not_change_results(tmp_path):
    """A swarm's result depends on its seed only, not on how seeds are batched into jobs."""
    whole = _run(tmp_path / "a", "--seeds", "3")
    split = _run(tmp_path / "b", "--seeds", "3", "--batch-size", "1")
    assert whole == split


def test_ray_backend_matches_local(tmp_path):
    ray = pytest.importorskip("ray")
    local = _run(tmp_path / "local", "--noise-position", "0.2", "--disturbance", "2")
    ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False)
    try:
        remote = _run(
            tmp_path / "ray", "--noise-position", "0.2", "--disturbance", "2", "--backend", "ray"
        )
    finally:
        ray.shutdown()
    assert remote == local
    record = json.loads((tmp_path / "ray" / "run.json").read_text())
    assert record["backend"] == "ray"


def test_reproduce_is_the_paper_suite(tmp_path, capsys):
    out = tmp_path / "r"
    rc = reproduce.main(
        [
            "--n-uavs",
            "8",
            "--horizon",
            "2",
            "--seeds",
            "1",
            "--workers",
            "1",
            "--no-figures",
            "--quiet",
            "--out",
            str(out),
        ]
    )
    assert rc == 0
    res = json.loads((out / "results.json").read_text())
    assert res["suite"] == "paper"
    assert [p["label"] for p in res["policies"]] == ["smc", "proportional", "zero"]
    assert "Acceptance criteria" in (out / "summary.md").read_text()
    printed = capsys.readouterr().out
    assert "| N | policy |" in printed and "| 8 | smc |" in printed
    assert "[pass]" in printed or "[FAIL]" in printed


def test_three_d_scenario_draws_trajectories(tmp_path):
    out = tmp_path / "d3"
    assert (
        main(
            [
                *TINY,
                "--dim",
                "3",
                "--seeds",
                "1",
                "-p",
                "smc",
                "--workers",
                "1",
                "--no-snapshots",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert (out / "trajectories3d_nominal_smc.png").stat().st_size > 0
    assert "3,8,1," in (out / "results.csv").read_text().splitlines()[1]  # dim, N, pairs


@pytest.mark.parametrize(
    "args, words",
    [
        (["-p", "pid"], ["pid", "smc", "proportional", "zero"]),
        (["-p", "smc:gain=3"], ["gain", "valid gains", "k"]),
        (["-p", "smc:k=-1"], ["k=-1.0", "> 0"]),
        (["-p", "smc", "smc"], ["twice"]),
        (["--set", "n_uav=5"], ["n_uav", "n_uavs"]),
        (["--set", "dim=4"], ["dim=4", "[2, 3]"]),
        (["--delay", "-1"], ["partner_delay=-1"]),
        (["--n-uavs", "8", "--set", "n_uavs=9"], ["n_uavs", "--n-uavs"]),
        (["--scenario", "a:n_uavs=9", "--n-uavs", "8", "9"], ["n_uavs", "grid axis"]),
        (["--video", "x.avi"], [".mp4", ".gif"]),
        (["--preset", "nope"], ["nope", "paper"]),
        (["--seeds", "0"], ["--seeds 0"]),
    ],
)
def test_bad_input_names_argument_and_choices(args, words, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        main([*TINY, "--out", str(tmp_path), *args])
    assert e.value.code == 2
    err = capsys.readouterr().err
    for w in words:
        assert w in err, (w, err)


def test_policy_specs():
    s = parse_policy("smc:k=200,boundary_layer=0.5")
    assert (s.name, dict(s.gains), s.label) == (
        "smc",
        {"k": 200, "boundary_layer": 0.5},
        "smc:k=200,boundary_layer=0.5",
    )
    assert parse_policy("zero").gains == ()
    assert dict(parse_policy("smc:boundary_layer=none").gains) == {"boundary_layer": None}
    with pytest.raises(ValueError, match="expected key=value"):
        parse_policy("smc:k")
    with pytest.raises(ValueError, match="given twice"):
        parse_policy("smc:k=1,k=2")


def test_prefix_policies_take_their_argument_verbatim(monkeypatch, tmp_path):
    """``sb3:<path>`` style entries: everything after the prefix is the path, even with '='
    or ','; an existing relative path is made absolute for workers elsewhere."""
    seen = {}

    def factory(arg, env, **gains):
        seen["arg"] = arg
        return POLICIES["zero"](env, **gains)

    monkeypatch.setitem(POLICIES, "fake:", factory)
    s = parse_policy("fake:dir/k=1,b.zip")
    assert s.name == "fake:dir/k=1,b.zip" and s.gains == () and s.base == "fake"
    model = tmp_path / "m.zip"
    model.write_bytes(b"")
    monkeypatch.chdir(tmp_path)
    assert parse_policy("fake:m.zip").name == f"fake:{model}"
    out = tmp_path / "o"
    assert (
        main([*TINY, "-p", "fake:m.zip", "--workers", "1", "--no-figures", "--out", str(out)]) == 0
    )
    assert seen["arg"] == str(model)
    assert "fake:m.zip" in (out / "results.csv").read_text()


def test_scenario_specs_and_grid():
    assert parse_scenario("delay 5:partner_delay=5") == ("delay 5", {"partner_delay": 5})
    assert parse_scenario("pairs=[[0,1],[2,3]],init=random") == (
        None,
        {"pairs": [[0, 1], [2, 3]], "init": "random"},
    )
    sc = expand_scenarios(
        {"n_uavs": 50}, [("a", {"partner_delay": 2}), (None, {})], {"dt": [0.01, 0.005], "dim": [2]}
    )
    assert [s.label for s in sc] == ["a, dt=0.01", "a, dt=0.005", "dt=0.01", "dt=0.005"]
    assert sc[1].override_dict == {"n_uavs": 50, "partner_delay": 2, "dt": 0.005, "dim": 2}
    assert slug("N=50") == "n50" and slug("smc:k=200") == "smc-k200"
    assert slug("noise y 0.3 m") == "noisey0.3m" and slug("sb3:runs/a/m.zip") == "sb3-runs-a-m-zip"


def test_replot_redraws_from_files(figure_run):
    png = figure_run / "pair_error.png"
    png.unlink()
    assert main(["--replot", str(figure_run), "--no-snapshots"]) == 0
    assert png.stat().st_size > 0


def _result_files(out: Path) -> dict[str, bytes]:
    """The result set in ``out`` (run.json aside: it holds timestamps)."""
    return {p.name: p.read_bytes() for p in out.iterdir() if p.is_file() and p.name != "run.json"}


def test_a_killed_rerun_leaves_the_old_set_or_a_marked_folder(tmp_path):
    """SIGKILL a rerun into a finished folder while it writes: the folder holds the old set
    untouched (or, had it got that far, the new set), never new results beside an old
    summary; a later run cleans up after the killed one."""
    out = tmp_path / "res"
    assert main([*TINY, "-p", "smc", "--workers", "1", "--out", str(out)]) == 0
    old = _result_files(out)
    rerun = [*TINY, "-p", "smc", "zero", "--seeds", "3", "--workers", "1", "--out", str(out)]
    env = dict(os.environ, OMP_NUM_THREADS="1", MPLBACKEND="Agg")
    proc = subprocess.Popen(
        [sys.executable, "-m", "baselines.benchmark", *rerun],
        cwd=tmp_path,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.time() + 120
        while time.time() < deadline and proc.poll() is None and not list(out.glob(".partial-*")):
            time.sleep(0.005)
        proc.send_signal(signal.SIGKILL)  # it has started writing its results
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == -signal.SIGKILL, "the rerun finished before it could be killed"
    killed, leftover = _result_files(out), list(out.glob(".partial-*"))
    assert main(rerun) == 0
    new = _result_files(out)
    assert new != old
    assert killed in (old, new) or "INCOMPLETE" in killed
    if killed == old:  # killed while writing aside: its hidden staging folder is left
        assert leftover
    assert not list(out.glob(".partial-*")) and "INCOMPLETE" not in new


def test_an_interrupted_swap_marks_the_folder_incomplete(tmp_path, monkeypatch, capsys):
    """If the swap of the new set into the folder fails midway, ``INCOMPLETE`` says so (and
    --replot refuses the folder) until a run completes."""
    out = tmp_path / "res"
    assert main([*TINY, "-p", "smc", "--workers", "1", "--out", str(out)]) == 0
    replace = os.replace

    def failing_replace(src, dst):
        into_folder = ".partial-" in str(src) and ".partial-" not in str(dst)
        if into_folder and Path(dst).name == "summary.md":  # the swap, half done
            raise OSError("disk full")
        return replace(src, dst)

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OSError, match="disk full"):
        main([*TINY, "-p", "smc", "zero", "--workers", "1", "--out", str(out)])
    monkeypatch.setattr(os, "replace", replace)
    assert "rewritten by process" in (out / "INCOMPLETE").read_text()
    with pytest.raises(SystemExit):
        main(["--replot", str(out)])
    assert "INCOMPLETE" in capsys.readouterr().err
    assert main([*TINY, "-p", "smc", "zero", "--workers", "1", "--out", str(out)]) == 0
    assert not (out / "INCOMPLETE").exists()
    figs = {p.name for p in out.glob("*.png")}
    assert "snapshots_nominal_smc.png" in figs
    listed = json.loads((out / "run.json").read_text())["outputs"]
    assert sorted(p.name for p in out.iterdir() if p.is_file() and p.name != "run.json") == listed


def test_set_values_are_numbers_as_written():
    """The benchmark's and the quadrotor experiment's --set read ``1e-3``/``5e1`` as numbers
    (the parser every CLI shares, :func:`baselines.evaluation.specs.parse_value`)."""
    parser = build_parser()
    args = parser.parse_args([*TINY, "-p", "smc", "--set", "dt=1e-2,5e-3", "--set", "d_m=5e0"])
    plan = resolve(args, parser)
    assert [c.dt for c in plan.configs] == [0.01, 0.005] and plan.configs[0].d_m == (5.0,)
    args = quad_parser().parse_args(["--set", "quad_motor_time_constant=2e-2", "--seeds", "1"])
    overrides, _ = _settings(args)
    assert overrides == {"quad_motor_time_constant": 0.02}
