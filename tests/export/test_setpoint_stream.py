"""Setpoint streams (pairflock_env.recording.setpoints): a recorded Crazyflie episode as one
cmdFullState CSV per UAV at the control rate with a manifest, flown open loop by the Crazyflie
model from the recorded start. With the setpoints the vehicle flew (the array the recorder is
to add, written here the way it would write it) the flight reproduces the recording within
5 cm; the stream derived from the trajectory alone stays within 10 cm (the vehicle's own
tracking error, docs/export.md)."""

from __future__ import annotations

import functools
import tempfile
from pathlib import Path

import numpy as np
import pytest

from baselines import make_pair_policy
from baselines.evaluation.rollout import rollout
from pairflock_env import PairFlockConfig, make_config
from pairflock_env.dynamics.crazyflie import CMD_FIELDS
from pairflock_env.recording import CoreRecorder, RecordingWriter, open_recording
from pairflock_env.recording.setpoints import (
    COLUMNS,
    fly_stream,
    read_setpoints,
    setpoint_stream,
    write_setpoints,
)

STEPS = 500  # 10 s of the crazyflie preset at 50 Hz
_KEEP: list[tempfile.TemporaryDirectory] = []


def _folder() -> Path:
    d = tempfile.TemporaryDirectory(prefix="pairflock-setpoints-")
    _KEEP.append(d)
    return Path(d.name)


@functools.cache
def _recording() -> str:
    """One smc episode of the crazyflie preset (10 Crazyflies), with its setpoints."""
    cfg = make_config("crazyflie", max_cycles=STEPS)
    folder = _folder()
    with CoreRecorder(folder, controller="smc", name="seed{seed}", seeds=[0]) as rec:
        rollout(cfg, make_pair_policy("smc", cfg), [0], on_step=rec)
    return rec.paths[0]


def _fly(stream_dir: Path, recording) -> np.ndarray:
    """Distance (T, N) between the flown and the recorded positions."""
    _, rows = read_setpoints(stream_dir)
    q = np.asarray(recording["positions"], dtype=np.float64)
    cfg = PairFlockConfig.from_dict(recording.config)
    flown = fly_stream(rows, cfg, q[0], np.asarray(recording["velocities"])[0])
    return np.linalg.norm(flown - q, axis=-1)


def test_the_flown_setpoints_reproduce_the_recorded_flight_within_5_cm():
    rec = open_recording(_recording())
    out = _folder() / "stream"
    man = write_setpoints(rec.path, out)  # source "auto": the recorded setpoints
    assert man["source"] == "recorded" and man["rate_hz"] == pytest.approx(50.0)
    err = _fly(out, rec)
    assert err.shape == (STEPS + 1, 10) and err.max() < 0.05
    print(f"recorded setpoints: flown vs recorded, max {err.max():.2e} m")


def test_the_stream_derived_from_the_trajectory_tracks_within_10_cm():
    rec = open_recording(_recording())
    out = _folder() / "derived"
    man = write_setpoints(rec.path, out, source="trajectory", body_rates="flatness")
    assert man["source"] == "trajectory" and man["yaw_rad"] == 0.0
    err = _fly(out, rec)
    assert err.max() < 0.10 and err.mean() < 0.04
    print(f"derived setpoints: flown vs recorded, max {err.max():.4f} m, mean {err.mean():.4f} m")


def test_csv_columns_rows_and_manifest():
    rec = open_recording(_recording())
    out = _folder() / "csv"
    man = write_setpoints(rec.path, out, source="trajectory")
    files = sorted(p.name for p in out.iterdir())
    assert files == ["manifest.json"] + [f"uav_{i:03d}.csv" for i in range(10)]
    header = (out / "uav_000.csv").read_text().splitlines()[0]
    assert header == "t,x,y,z,vx,vy,vz,ax,ay,az,yaw,wx,wy,wz"
    assert [c["name"] for c in man["columns"]] == [c[0] for c in COLUMNS]
    assert [c[0] for c in COLUMNS[1:11]] == list(CMD_FIELDS)
    _, rows = read_setpoints(out)
    q, p = (np.asarray(rec[k], dtype=np.float64) for k in ("positions", "velocities"))
    assert rows.shape == (STEPS, 10, 14)
    t = np.asarray(rec["time"])[:STEPS]
    np.testing.assert_allclose(rows[..., 0], np.broadcast_to(t[:, None], (STEPS, 10)), atol=1e-9)
    np.testing.assert_allclose(rows[..., 1:4], q[:-1], atol=1e-6)
    np.testing.assert_allclose(rows[..., 7:10], (p[1:] - p[:-1]) / 0.02, rtol=1e-6, atol=1e-4)
    assert not rows[..., 11:].any()  # body rates 0 by default
    roles = [u["role"] for u in man["uavs"]]
    assert roles[:2] == ["pair 0", "pair 0"] and set(roles[2:]) == {"flock"}
    with pytest.raises(FileExistsError, match="not empty"):
        write_setpoints(rec.path, out)


def test_flatness_rates_tilt_the_thrust_axis_toward_a_growing_acceleration():
    """Jerk along +x from hover pitches the body about +y at |j| / g (body rate q)."""
    folder = _folder() / "ramp.pfrec"
    t = np.arange(6) * 0.02
    v = np.zeros((6, 1, 3))
    v[:, 0, 0] = 0.5 * t * t  # a = t, j = 1 m/s^3
    q = np.cumsum(v, 0) * 0.02
    with RecordingWriter(folder, num_uavs=1, dim=3, dt=0.02) as w:
        for k in range(6):
            w.append(k, time=t[k], positions=q[k], velocities=v[k])
    rows, _ = setpoint_stream(folder, body_rates="flatness")
    np.testing.assert_allclose(rows[:3, 0, 11:], [[0.0, 1 / 9.81, 0.0]] * 3, atol=1e-3)


def test_what_a_stream_cannot_be_made_from_is_refused(tmp_path):
    rec = open_recording(_recording())
    with pytest.raises(ValueError, match="body_rates"):
        setpoint_stream(rec, body_rates="guess")
    with pytest.raises(ValueError, match="only a 2-D recording"):
        setpoint_stream(rec, source="trajectory", altitude=1.0)
    flat = tmp_path / "flat.pfrec"
    with RecordingWriter(flat, num_uavs=2, dim=2, dt=0.1, every=2) as w:
        for k in range(0, 5, 2):
            w.append(k, time=0.1 * k, positions=np.zeros((2, 2)), velocities=np.zeros((2, 2)))
    with pytest.raises(ValueError, match="every=2"):
        setpoint_stream(flat)
    plane = tmp_path / "plane.pfrec"
    with RecordingWriter(plane, num_uavs=2, dim=2, dt=0.1) as w:
        for k in range(3):
            w.append(k, time=0.1 * k, positions=np.full((2, 2), k), velocities=np.ones((2, 2)))
    with pytest.raises(ValueError, match="altitude"):
        setpoint_stream(plane)
    rows, info = setpoint_stream(plane, altitude=1.5)
    assert info["altitude_m"] == 1.5 and np.all(rows[..., 3] == 1.5) and not rows[..., 6].any()
    with pytest.raises(ValueError, match="no .setpoint. array"):
        setpoint_stream(plane, source="recorded", altitude=1.5)
