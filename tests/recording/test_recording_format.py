"""The recording format: round trip, numpy-only reading, bounded buffers, interrupted writers
(an exception, and a SIGKILL of a writing process), and the checks of bad input."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from pairflock_env.recording import STEP_ARRAYS, RecordingWriter, open_recording
from pairflock_env.recording import format as fmt
from pairflock_env.replay.demo import D_M, write_demo

N, DIM = 6, 3


def _step(t: int, n: int = N, dim: int = DIM) -> dict:
    """Deterministic arrays of step t (any step can be checked after the fact)."""
    q = np.arange(n * dim, dtype=np.float64).reshape(n, dim) + 0.25 * t
    return dict(
        time=0.1 * t,
        positions=q,
        velocities=-q,
        leader_position=np.full(dim, float(t)),
        leader_velocity=np.ones(dim),
        pair_distance=np.array([1.0 + t, 2.0 + t]),
        pair_error=np.array([0.5, -0.5]) * t,
        safety_active=np.array([t % 2 == 0, False]),
        safety_correction=np.array([0.1 * t, 0.0]),
        closest_distance=np.full(n, 0.5 + t),
        setpoint=np.arange(n * 10, dtype=np.float64).reshape(n, 10) - t,  # 10 values per UAV
        infos={"sim_time": 0.1 * t, "collisions": t // 3, "diverged": False},
    )


def _writer(path, **kw) -> RecordingWriter:
    base = dict(num_uavs=N, dim=DIM, dt=0.1, pairs=[[0, 1], [2, 3]], pair_target=[1.0, 1.5])
    base.update(config={"preset": "paper", "n_uavs": N}, seed=7, controller="smc")
    return RecordingWriter(path, **(base | kw))


def test_round_trip(tmp_path):
    path = tmp_path / "run.pfrec"
    with _writer(path, flush_steps=4) as w:
        for t in range(11):
            assert w.append(t, **_step(t))
    rec = open_recording(path)
    assert rec.complete and rec.steps == 11 and rec.manifest["stopped"] is None
    assert (rec.num_uavs, rec.dim, rec.num_pairs, rec.seed, rec.controller) == (N, 3, 2, 7, "smc")
    assert rec.config == {"preset": "paper", "n_uavs": N}
    np.testing.assert_array_equal(rec.pairs, [[0, 1], [2, 3]])
    np.testing.assert_allclose(rec.pair_target, [1.0, 1.5])
    np.testing.assert_array_equal(rec["step"], np.arange(11))
    for t in (0, 5, 10):
        want = _step(t)
        for name in set(STEP_ARRAYS) - {"step"}:
            np.testing.assert_allclose(rec[name][t], want[name], rtol=1e-6, err_msg=name)
    assert rec["positions"].dtype == np.float32 and rec["time"].dtype == np.float64
    assert sorted(rec.infos) == ["collisions", "diverged", "sim_time"]
    np.testing.assert_array_equal(rec.infos["collisions"], np.arange(11) // 3)


def test_readable_with_numpy_alone(tmp_path):
    """The format's promise: json + numpy.load read everything, no package code."""
    path = tmp_path / "run.pfrec"
    with _writer(path, flush_steps=3) as w:
        for t in range(7):
            w.append(t, **_step(t))
    man = json.loads((path / "manifest.json").read_text())
    assert (man["format"], man["version"], man["complete"], man["steps"]) == (
        "pairflock-recording",
        1,
        True,
        7,
    )
    for name, meta in man["arrays"].items():
        arr = np.load(path / meta["file"])
        assert arr.shape == (7, *meta["shape"]), name
        assert arr.dtype == np.dtype(meta["dtype"]), name
    np.testing.assert_allclose(np.load(path / "positions.npy")[6], _step(6)["positions"])
    assert np.load(path / man["static"]["pairs"]["file"]).shape == (2, 2)


def test_every_kth_step_and_forced_last(tmp_path):
    path = tmp_path / "run.pfrec"
    with _writer(path, every=4) as w:
        kept = [t for t in range(10) if w.append(t, force=t == 9, **_step(t))]
        assert not w.append(9, force=True, **_step(9))  # already recorded
    assert kept == [0, 4, 8, 9]
    rec = open_recording(path)
    np.testing.assert_array_equal(rec["step"], kept)
    assert rec.every == 4


def test_info_keys_may_come_and_go(tmp_path):
    path = tmp_path / "run.pfrec"
    with _writer(path, flush_steps=2) as w:
        for t in range(5):
            infos = {"a": t} | ({"late": 10.0 * t} if t >= 3 else {})
            q = np.zeros((N, DIM))
            w.append(t, time=t, positions=q, velocities=q, infos=infos)
    infos = open_recording(path).infos
    np.testing.assert_array_equal(infos["a"], np.arange(5))
    np.testing.assert_array_equal(infos["late"], [np.nan, np.nan, np.nan, 30.0, 40.0])


def test_bounded_buffers_at_10000_uavs(tmp_path):
    """Memory stays bounded: the buffers hold at most ~8 MiB of steps, whatever the episode."""
    n = 10_000
    pairs = np.arange(n).reshape(-1, 2)
    w = RecordingWriter(tmp_path / "big", num_uavs=n, dim=3, dt=0.05, pairs=pairs, pair_target=1)
    q = np.zeros((n, 3))
    for t in range(40):
        w.append(t, time=t, positions=q, velocities=q, closest_distance=np.ones(n))
    held = sum(b.nbytes for b in w._buffers.values())
    assert held <= 9 << 20, held
    assert w.manifest["steps"] >= 40 - w._chunk  # earlier steps are on disk already
    w.close()
    assert open_recording(tmp_path / "big").steps == 40


def test_exception_keeps_steps_and_marks_incomplete(tmp_path):
    path = tmp_path / "run.pfrec"
    with pytest.raises(KeyboardInterrupt), _writer(path, flush_steps=100) as w:
        for t in range(5):
            w.append(t, **_step(t))
        raise KeyboardInterrupt
    rec = open_recording(path)
    assert not rec.complete and rec.steps == 5
    assert rec.manifest["stopped"] == "KeyboardInterrupt"
    assert "INCOMPLETE" in repr(rec)


_CHILD = textwrap.dedent(
    """
    import sys, time
    import numpy as np
    from pairflock_env.recording import RecordingWriter
    n = 50
    w = RecordingWriter(sys.argv[1], num_uavs=n, dim=3, dt=0.1, flush_steps=5,
                        flush_seconds=1e9)
    t = 0
    while True:  # until killed
        q = np.full((n, 3), float(t))
        w.append(t, time=0.1 * t, positions=q, velocities=q, infos={"t": t})
        t += 1
        if t % 5 == 0:
            print(w.manifest["steps"], flush=True)
            time.sleep(0.01)
    """
)


def test_sigkill_leaves_every_flushed_step(tmp_path):
    path = tmp_path / "killed.pfrec"
    root = Path(fmt.__file__).resolve().parents[2]  # the folder holding pairflock_env
    path_var = os.pathsep.join([str(root), os.environ.get("PYTHONPATH", "")])
    env = dict(os.environ, PYTHONPATH=path_var)
    child = subprocess.Popen(
        [sys.executable, "-c", _CHILD, str(path)], stdout=subprocess.PIPE, text=True, env=env
    )
    try:
        for _ in range(7):  # at least 7 flushes, 35 steps, then kill it mid-recording
            flushed = int(child.stdout.readline())
        child.send_signal(signal.SIGKILL)
        child.wait(timeout=30)
    finally:
        child.kill()
        child.stdout.close()
    assert child.returncode == -signal.SIGKILL
    rec = open_recording(path)
    assert not rec.complete and rec.manifest["stopped"] is None
    assert rec.steps >= flushed >= 35 and rec.steps % 5 == 0
    np.testing.assert_array_equal(rec["step"], np.arange(rec.steps))
    np.testing.assert_array_equal(rec["positions"][:, 0, 0], np.arange(rec.steps))
    np.testing.assert_array_equal(rec.infos["t"], np.arange(rec.steps))
    assert np.load(path / "positions.npy").shape[0] >= rec.steps  # numpy alone reads it too


def test_reader_trims_a_file_cut_short(tmp_path):
    path = tmp_path / "run.pfrec"
    with _writer(path) as w:
        for t in range(6):
            w.append(t, **_step(t))
    f = path / "velocities.npy"
    f.write_bytes(f.read_bytes()[: -N * DIM * 4 * 2 - 5])  # 2 rows and a bit gone
    rec = open_recording(path)
    assert rec.steps == 3 and not rec.complete


def test_demo_recording(tmp_path):
    rec = open_recording(write_demo(tmp_path / "demo", num_uavs=11, steps=50, dim=2))
    assert rec.steps == 50 and rec.complete and rec.num_pairs == 5
    d = np.asarray(rec["pair_distance"])
    q = np.asarray(rec["positions"], np.float64)
    p = rec.pairs
    np.testing.assert_allclose(np.linalg.norm(q[:, p[:, 1]] - q[:, p[:, 0]], axis=2), d, rtol=1e-5)
    np.testing.assert_allclose(rec["pair_error"], d - D_M, atol=1e-6)


@pytest.mark.parametrize(
    ("kwargs", "error", "words"),
    [
        (dict(num_uavs=0), ValueError, "num_uavs=0"),
        (dict(num_uavs=2.5), TypeError, "num_uavs=2.5"),
        (dict(dim=4), ValueError, "dim=4"),
        (dict(dt=-1.0), ValueError, "dt=-1.0"),
        (dict(every=0), ValueError, "every=0"),
        (dict(pairs=[[0, 9]]), ValueError, "pairs"),
        (dict(pairs=[[0, 1]], pair_target=None), ValueError, "pair_target"),
        (dict(safety_scope="pair"), ValueError, "safety_scope='pair'"),
        (dict(float_dtype="float16"), ValueError, "float_dtype"),
        (dict(config={"f": object()}), TypeError, "config['f']"),
    ],
)
def test_bad_arguments(tmp_path, kwargs, error, words):
    with pytest.raises(error, match=words.replace("[", r"\[").replace("(", r"\(")):
        _writer(tmp_path / "x", **kwargs)


def test_bad_steps(tmp_path):
    w = _writer(tmp_path / "run.pfrec")
    with pytest.raises(ValueError, match=r"positions of shape \(5, 3\)"):
        w.append(0, **(_step(0) | {"positions": np.zeros((5, 3))}))
    w2 = _writer(tmp_path / "run2.pfrec")
    w2.append(0, **_step(0))
    with pytest.raises(ValueError, match="differ from those of the first recorded step"):
        w2.append(1, time=0.1, positions=np.zeros((N, 3)), velocities=np.zeros((N, 3)))
    with pytest.raises(TypeError, match="unknown recording arrays"):
        w2.append(2, **_step(2), speed=1.0)
    with pytest.raises(ValueError, match=r"infos\['x'\]"):
        w2.append(3, **(_step(3) | {"infos": {"x": [1, 2]}}))
    with pytest.raises(FileExistsError, match="exists"):
        _writer(tmp_path / "run2.pfrec")


def test_reader_refuses_what_it_cannot_read(tmp_path):
    with pytest.raises(ValueError, match=r"no manifest\.json"):
        open_recording(tmp_path)
    path = tmp_path / "run.pfrec"
    _writer(path).close()
    man = json.loads((path / "manifest.json").read_text())
    (path / "manifest.json").write_text(json.dumps(man | {"version": 99}))
    with pytest.raises(ValueError, match="version 99"):
        open_recording(path)
