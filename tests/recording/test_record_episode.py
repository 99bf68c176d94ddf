"""RecordEpisode on every view (PettingZoo parallel and AEC, Gymnasium single and vector): the
reader sees the recorded steps, and they hold the core's state at each of them; an auto-reset
starts the next recording after the ended one is written; Ctrl-C (inside a step, and as a
real SIGINT to a running process) leaves readable recordings marked incomplete; bad
arguments are named."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from gymnasium.vector import VectorWrapper

import pairflock_env as pf
from pairflock_env.envs import PairFlockGymEnv, PairFlockGymVectorEnv
from pairflock_env.envs.record import RecordEpisode, find_core
from pairflock_env.recording import open_recording

SMALL = dict(n_uavs=6, max_cycles=8)
ROOT = Path(__file__).resolve().parents[2]


class Tape:
    """The core's state after every view call: (swarm, step) -> positions, velocities,
    closest distances, sim time (of the first time the step was seen)."""

    def __init__(self, env):
        self.core = find_core(env)
        self.seen: dict[tuple[int, int], tuple] = {}

    def __call__(self) -> None:
        c = self.core
        closest = c.closest_distance
        for b in range(c.num_swarms):
            state = (c.q[b].copy(), c.p[b].copy(), closest[b], c.t[b])
            self.seen.setdefault((b, int(c.steps[b])), state)  # the first episode's


def check_recording(path, tape: Tape, swarm: int, steps, complete: bool = True) -> None:
    """The recording at ``path`` holds exactly ``steps`` and the tape's state at each."""
    rec = open_recording(path)
    assert rec.complete == complete, rec.manifest["stopped"]
    np.testing.assert_array_equal(rec["step"], steps)
    for k, step in enumerate(steps):
        if (swarm, step) not in tape.seen:
            continue  # a step inside a decision (the tape sees the view's steps)
        q, p, closest, t = tape.seen[swarm, step]
        np.testing.assert_allclose(rec["positions"][k], q, rtol=1e-6, atol=1e-4)
        np.testing.assert_allclose(rec["velocities"][k], p, rtol=1e-6, atol=1e-4)
        np.testing.assert_allclose(rec["closest_distance"][k], closest, rtol=1e-6)
        assert rec["time"][k] == pytest.approx(t)
        assert rec.infos["sim_time"][k] == pytest.approx(t)
    q = np.asarray(rec["positions"], float)
    pairs = rec.pairs
    gap = np.linalg.norm(q[:, pairs[:, 0]] - q[:, pairs[:, 1]], axis=-1)
    np.testing.assert_allclose(rec["pair_distance"], gap, rtol=1e-5, atol=1e-5)
    assert rec.num_uavs == 6 and rec.controller == "zero"


def test_parallel(tmp_path):
    env = RecordEpisode(pf.parallel_env(**SMALL), tmp_path, controller="zero")
    assert isinstance(env, RecordEpisode) and isinstance(env, pf.envs.parallel.ParallelEnv)
    tape = Tape(env)
    env.reset(seed=3)
    tape()
    while env.agents:
        env.step({a: env.action_space(a).sample() * 0 for a in env.agents})
        tape()
    env.close()
    assert [os.path.basename(p) for p in env.recorder.paths] == ["swarm0_ep0.pfrec"]
    check_recording(tmp_path / "swarm0_ep0.pfrec", tape, 0, range(9))
    rec = open_recording(tmp_path / "swarm0_ep0.pfrec")
    assert rec.seed == 3 and rec.manifest["metadata"]["ended_by"] == "truncated"
    assert rec.config["n_uavs"] == 6 and rec.dt == env.unwrapped.config.dt
    assert {"collisions", "largest_component", "diverged"} <= set(rec.infos)


def test_aec_records_what_the_parallel_env_does(tmp_path):
    par = RecordEpisode(pf.parallel_env(**SMALL), tmp_path / "par", controller="zero")
    par.reset(seed=5)
    while par.agents:
        par.step({a: np.full(2, 0.3, np.float32) for a in par.agents})
    par.close()
    aec = RecordEpisode(pf.env(**SMALL), tmp_path / "aec", controller="zero")
    aec.reset(seed=5)
    for _agent in aec.agent_iter():
        *_, term, trunc, _ = aec.last()
        aec.step(None if term or trunc else np.full(2, 0.3, np.float32))
    aec.close()
    a = open_recording(tmp_path / "aec" / "swarm0_ep0.pfrec")
    b = open_recording(tmp_path / "par" / "swarm0_ep0.pfrec")
    assert a.complete and a.steps == b.steps == 9
    np.testing.assert_array_equal(a["positions"], b["positions"])


def test_gym_every_kth_step(tmp_path):
    env = RecordEpisode(PairFlockGymEnv(**SMALL), tmp_path, every=3, controller="zero")
    tape = Tape(env)
    env.reset(seed=1)
    tape()
    done = False
    while not done:
        *_, term, trunc, _ = env.step(np.zeros(env.action_space.shape, np.float32))
        tape()
        done = term or trunc
    env.reset()  # the next episode's recording, cut off by close()
    env.step(np.zeros(env.action_space.shape, np.float32))
    env.close()
    check_recording(tmp_path / "swarm0_ep0.pfrec", tape, 0, [0, 3, 6, 8])
    nxt = open_recording(tmp_path / "swarm0_ep1.pfrec")
    assert not nxt.complete and nxt.manifest["stopped"] == "closed before the episode ended"
    assert nxt.seed is None and nxt.manifest["metadata"]["seeded"] == 1


@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_vector_auto_reset(tmp_path, mode):
    venv = PairFlockGymVectorEnv(2, autoreset_mode=mode, interface="world", **SMALL)
    env = RecordEpisode(venv, tmp_path, controller="zero")
    assert isinstance(env, VectorWrapper)
    tape = Tape(env)
    env.reset(seed=10)
    tape()
    zero = np.zeros(env.action_space.shape, np.float32)
    for _ in range(12):
        env.step(zero)
        if _ < 8:  # the first episode's steps (before any auto-reset moved the state on)
            tape()
    env.close()
    names = sorted(os.listdir(tmp_path))
    assert names == [f"swarm{b}_ep{n}.pfrec" for b in (0, 1) for n in (0, 1)]
    for b in (0, 1):
        check_recording(tmp_path / f"swarm{b}_ep0.pfrec", tape, b, range(9))
        assert open_recording(tmp_path / f"swarm{b}_ep0.pfrec").seed == 10 + b
        second = open_recording(tmp_path / f"swarm{b}_ep1.pfrec")
        assert not second.complete and second["step"][0] == 0
        assert second.steps == (4 if mode == "NextStep" else 5)


def test_swarms_and_max_episodes_and_names(tmp_path):
    venv = PairFlockGymVectorEnv(3, interface="world", **SMALL)
    env = RecordEpisode(venv, tmp_path, swarms=[1], max_episodes=1, name="run_s{swarm}_e{episode}")
    env.reset(seed=0)
    for _ in range(20):
        env.step(np.zeros(env.action_space.shape, np.float32))
    env.close()
    assert os.listdir(tmp_path) == ["run_s1_e0.pfrec"]
    assert open_recording(tmp_path / "run_s1_e0.pfrec").complete


def test_safety_filter_activity_is_recorded_per_uav(tmp_path):
    env = RecordEpisode(pf.parallel_env(n_uavs=6, max_cycles=30, safety_filter="cbf"), tmp_path)
    q0 = np.array([[0.0, 0.0], [1.6, 0.0], [0, 30], [10, 30], [20, 30], [30, 30]])
    p0 = np.zeros((6, 2))
    p0[0, 0], p0[1, 0] = 2.0, -2.0  # the pair flies at each other: the filter steps in
    env.reset(seed=0, options={"positions": q0, "velocities": p0})
    while env.agents:
        env.step({a: np.array([1.0 if a == "uav_0" else -1.0, 0.0]) for a in env.agents})
    env.close()
    rec = open_recording(tmp_path / "swarm0_ep0.pfrec")
    assert rec.safety_scope == "uav" and rec["safety_active"].shape == (31, 6)
    active = np.asarray(rec["safety_active"])
    assert active[:, :2].any() and not active[:, 2:].any()
    assert (np.asarray(rec["safety_correction"])[active] > 0).all()


def test_ctrl_c_inside_a_step_flushes(tmp_path, monkeypatch):
    env = RecordEpisode(PairFlockGymEnv(n_uavs=6), tmp_path, flush_seconds=1e9)
    env.reset(seed=0)
    core = find_core(env)
    advance = core.vehicle.advance
    calls = []

    def interrupted(*args):
        calls.append(1)
        if len(calls) == 5:
            raise KeyboardInterrupt
        return advance(*args)

    monkeypatch.setattr(core.vehicle, "advance", interrupted)
    with pytest.raises(KeyboardInterrupt):
        for _ in range(10):
            env.step(np.zeros(env.action_space.shape, np.float32))
    rec = open_recording(tmp_path / "swarm0_ep0.pfrec")  # before close: flushed already
    assert rec.steps == 5 and not rec.complete
    env.close()
    rec = open_recording(tmp_path / "swarm0_ep0.pfrec")
    assert rec.steps == 5 and rec.manifest["stopped"] == "KeyboardInterrupt"


_CHILD = textwrap.dedent(
    """
    import signal
    import sys
    # Ctrl-C raises KeyboardInterrupt even where this test runs in the background (a shell
    # starts background jobs with SIGINT ignored, and the child would inherit that)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import numpy as np
    import pairflock_env as pf
    from pairflock_env.envs.record import RecordEpisode
    env = RecordEpisode(pf.parallel_env(n_uavs=6, max_cycles=10**6), sys.argv[1],
                        flush_seconds=0.05)
    env.reset(seed=0)
    zero = {a: np.zeros(2) for a in env.agents}
    n = 0
    while True:  # until Ctrl-C
        env.step(zero)
        n += 1
        if n == 200:
            print("running", flush=True)
    """
)


def test_sigint_leaves_a_readable_incomplete_recording(tmp_path):
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    )
    child = subprocess.Popen(
        [sys.executable, "-c", _CHILD, str(tmp_path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert child.stdout.readline().strip() == "running"
        child.send_signal(signal.SIGINT)
        _, err = child.communicate(timeout=60)
    finally:
        child.kill()
    assert "KeyboardInterrupt" in err
    rec = open_recording(tmp_path / "swarm0_ep0.pfrec")
    assert not rec.complete and rec.steps >= 200
    assert rec.manifest["stopped"] in (
        "KeyboardInterrupt",
        "the process ended before the episode ended",
    )
    np.testing.assert_array_equal(rec["step"], np.arange(rec.steps))


@pytest.mark.parametrize(
    ("make", "kwargs", "error", "words"),
    [
        (lambda: object(), {}, TypeError, "env=<object"),
        (lambda: pf.parallel_env(n_uavs=6), dict(every=0), ValueError, "every=0"),
        (lambda: pf.parallel_env(n_uavs=6), dict(every=1.5), TypeError, "every=1.5"),
        (lambda: pf.parallel_env(n_uavs=6), dict(controller=3), TypeError, "controller=3"),
        (lambda: pf.parallel_env(n_uavs=6), dict(swarms=[4]), ValueError, r"swarms=\[4\]"),
        (lambda: pf.parallel_env(n_uavs=6), dict(swarms="0"), TypeError, "swarms='0'"),
        (lambda: pf.parallel_env(n_uavs=6), dict(max_episodes=0), ValueError, "max_episodes=0"),
        (lambda: pf.parallel_env(n_uavs=6), dict(name="ep{number}"), ValueError, "name="),
        (lambda: pf.parallel_env(n_uavs=6), dict(buffer_mb=-1), ValueError, "buffer_mb=-1"),
        (lambda: pf.parallel_env(n_uavs=6), dict(float_dtype="f2"), ValueError, "float_dtype"),
    ],
)
def test_bad_arguments(tmp_path, make, kwargs, error, words):
    with pytest.raises(error, match=words):
        RecordEpisode(make(), tmp_path / "rec", **kwargs)


def test_bad_paths(tmp_path):
    (tmp_path / "file").write_text("")
    with pytest.raises(TypeError, match="path=3"):
        RecordEpisode(pf.parallel_env(n_uavs=6), 3)
    with pytest.raises(ValueError, match="is a file"):
        RecordEpisode(pf.parallel_env(n_uavs=6), tmp_path / "file")
    (tmp_path / "old" / "swarm0_ep0.pfrec").mkdir(parents=True)
    with pytest.raises(ValueError, match="already holds recordings"):
        RecordEpisode(pf.parallel_env(n_uavs=6), tmp_path / "old")


def test_close_unhooks_the_core(tmp_path):
    inner = pf.parallel_env(**SMALL)
    env = RecordEpisode(inner, tmp_path)
    core = find_core(env)
    assert "step" in core.__dict__
    env.close()
    assert "step" not in core.__dict__ and "reset_rows" not in core.__dict__
