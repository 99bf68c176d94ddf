"""The replay page, without a browser: self-contained, its payload decodes (here, in Python)
to the recording within the quantisation, the closest pass is found, the stride obeys the size
budget, and the command line works."""

from __future__ import annotations

import base64
import json
import re
import subprocess
import sys
import zlib

import numpy as np
import pytest

from pairflock_env.recording import RecordingWriter, open_recording
from pairflock_env.replay import build_replay, headless, write_demo
from pairflock_env.replay.cli import main
from pairflock_env.replay.demo import CLOSEST


def read_page(path) -> tuple[dict, dict[str, np.ndarray]]:
    """The header and the decoded sections of a replay page, as the viewer reads them."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    meta = json.loads(re.search(r'id="pf-meta">(.*?)</script>', text, re.S).group(1))
    data = re.search(r'id="pf-data">(.*?)</script>', text, re.S).group(1)
    raw = zlib.decompress(base64.b64decode(data))
    out = {}
    for sec in meta["sections"]:
        buf = raw[sec["offset"] : sec["offset"] + sec["nbytes"]]
        out[sec["name"]] = np.frombuffer(buf, sec["dtype"]).reshape(sec["shape"])
    pos = out["positions"].copy()
    np.cumsum(pos, axis=0, dtype=np.uint16, out=pos)  # undo the differences (mod 2**16)
    scale = np.exp2(out["exp"].astype(np.float64))[:, None, None]
    x = out["origin"][:, None, :] + scale * pos + np.asarray(meta["offset"])
    out["decoded"] = np.where((pos == 65535)[..., :1], np.nan, x)
    return meta, out


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    return write_demo(tmp_path_factory.mktemp("rec") / "demo.pfrec", num_uavs=10, steps=160)


def test_page_is_self_contained(demo, tmp_path):
    info = build_replay(demo, tmp_path / "r.html")
    text = (tmp_path / "r.html").read_text()
    assert "<script src" not in text and "<link" not in text and "import(" not in text
    assert not re.search(r"https?://", text), "the page must need no network"
    assert "MIT licence" in text and "No third-party code" in text
    assert "window.pairflockReplay" in text
    assert info["steps"] == 160 and info["stride"] == 1 and info["bytes"] == len(text.encode())


def test_payload_decodes_to_the_recording(demo, tmp_path):
    build_replay(demo, tmp_path / "r.html")
    meta, s = read_page(tmp_path / "r.html")
    rec = open_recording(demo)
    q = np.asarray(rec["positions"], np.float64)
    quantum = np.exp2(s["exp"].astype(float))[:, None, None]
    assert np.all(np.abs(s["decoded"] - q) <= quantum / 2 + 1e-9)
    assert quantum.max() < 1e-3  # a 60 m formation: sub-millimetre
    np.testing.assert_array_equal(s["pairs"], rec.pairs)
    np.testing.assert_allclose(s["time"], rec["time"])
    np.testing.assert_allclose(s["pair_distance"], rec["pair_distance"], rtol=1e-3)
    np.testing.assert_allclose(s["leader"] + meta["offset"], rec["leader_position"], atol=1e-4)
    on = np.asarray(rec["safety_active"])
    assert np.array_equal(s["safety"] > 0, on) and on.any()
    assert set(meta["infos"]) == {"sim_time", "collisions", "active"}
    assert meta["complete"] and meta["num_uavs"] == 10 and meta["dim"] == 3


def test_closest_pass(demo, tmp_path):
    build_replay(demo, tmp_path / "r.html")
    meta, _ = read_page(tmp_path / "r.html")
    cp = meta["closest_pass"]
    rec = open_recording(demo)
    assert cp["distance"] == pytest.approx(CLOSEST, abs=1e-3)  # the squeezed pair, pair 1
    assert {cp["uav"], cp["other"]} == {2, 3}
    assert cp["time"] == pytest.approx(4.0, abs=rec.dt)
    assert meta["min_separation"][cp["index"]] == pytest.approx(cp["distance"], rel=1e-5)


def test_stride_keeps_the_budget_the_end_and_the_closest_pass(demo, tmp_path):
    info = build_replay(demo, tmp_path / "r.html", max_mb=0.001)
    meta, s = read_page(tmp_path / "r.html")
    assert info["stride"] > 1 and meta["stride"] == info["stride"]
    kept = s["step"].tolist()
    assert kept[-1] == 159 and meta["closest_pass"]["recorded_step"] in kept
    assert build_replay(demo, tmp_path / "s.html", stride=7)["stride"] == 7


def test_2d_incomplete_and_hidden_uavs(tmp_path):
    """A 2-D recording cut off early, one UAV non-finite at a step: the page says so."""
    path = tmp_path / "cut.pfrec"
    w = RecordingWriter(path, num_uavs=3, dim=2, dt=0.1)
    for t in range(4):
        q = np.array([[0.0, 0.0], [1.0, t], [2.0, 0.5]])
        if t == 2:
            q[1] = np.nan
        w.append(t, time=0.1 * t, positions=q, velocities=q)
    w.close(complete=False, stopped="KeyboardInterrupt")
    build_replay(path, tmp_path / "r.html", title="cut <run>")
    text = (tmp_path / "r.html").read_text()
    assert "<title>cut &lt;run&gt;" in text
    meta, s = read_page(tmp_path / "r.html")
    assert not meta["complete"] and meta["stopped"] == "KeyboardInterrupt"
    assert meta["closest_pass"] is None and meta["num_pairs"] == 0
    assert np.isnan(s["decoded"][2, 1]).all() and np.isfinite(s["decoded"][3]).all()
    np.testing.assert_allclose(s["decoded"][3, 1], [1.0, 3.0], atol=1e-4)


def test_cli(demo, tmp_path, capsys):
    out = tmp_path / "cli.html"
    assert main([str(demo), "-o", str(out), "--stride", "2"]) == 0
    assert "bytes per UAV-step" in capsys.readouterr().out and out.exists()
    assert main([str(tmp_path / "nothing"), "-o", str(out)]) == 2
    assert "is not a recording" in capsys.readouterr().err
    assert main([str(demo), "-o", str(out), "--stride", "0"]) == 2


def test_module_runs():
    run = subprocess.run(
        [sys.executable, "-m", "pairflock_env.replay", "--help"], capture_output=True, text=True
    )
    assert run.returncode == 0 and "pairflock-replay" in run.stdout


def test_missing_browser_is_named(monkeypatch, tmp_path):
    """Without a browser the browser tests skip with a message naming the Debian package."""
    monkeypatch.setenv("PAIRFLOCK_CHROMIUM", str(tmp_path / "no-such-browser"))
    why = headless.missing()
    assert why is not None and why.startswith("no browser")
    assert "Debian package chromium (apt-get install -y chromium)" in why
