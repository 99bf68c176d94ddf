"""Headless rendering helpers and the episode video writer."""

from __future__ import annotations

import numpy as np
import pytest

from baselines.reporting.video import write_episode_video
from pairflock_env.render import SwarmRenderer, fit_limits

RNG = np.random.default_rng(3)
Q = RNG.uniform(-20.0, 30.0, (10, 2))
P = RNG.normal(size=(10, 2))
LEADER = np.array([45.0, -5.0])


def test_fit_limits_is_a_square_around_every_uav_and_the_leader():
    x0, x1, y0, y1 = fit_limits(Q, LEADER)
    assert np.isclose(x1 - x0, y1 - y0)
    pts = np.vstack([Q, LEADER])
    assert np.all((pts[:, 0] > x0) & (pts[:, 0] < x1) & (pts[:, 1] > y0) & (pts[:, 1] < y1))
    # a single point still gets a view of at least min_span metres
    a, b, _, _ = fit_limits(np.zeros((1, 2)), min_span=10.0)
    assert b - a >= 10.0


def test_rgb_array_frames_with_fixed_limits():
    r = SwarmRenderer(((0, 1),), 5.0, "rgb_array", size_px=(320, 240))
    f1 = r.rgb_array(Q, P, LEADER, "frame")
    f2 = r.rgb_array(Q, P, LEADER, "frame", limits=(-200.0, 200.0, -200.0, 200.0))
    assert f1.shape == f2.shape == (240, 320, 3) and f1.dtype == np.uint8
    assert not np.array_equal(f1, f2)  # zoomed out: a different picture
    r.close()


def test_human_mode_without_a_display_warns_instead_of_failing():
    r = SwarmRenderer(((0, 1),), 5.0, "human")
    with pytest.warns(UserWarning, match="rgb_array"):
        assert r.human(Q, P, LEADER) is None
    r.close()


def test_video_writer_checks_its_arguments(tmp_path):

    t = np.arange(3) * 0.1
    pos = np.stack([Q] * 3)
    vel = np.stack([P] * 3)
    lead = np.stack([LEADER] * 3)
    with pytest.raises(ValueError, match=r"\.avi.*\.mp4, \.gif"):
        write_episode_video(tmp_path / "x.avi", t, pos, vel, lead, ((0, 1),), 5.0)
    with pytest.raises(ValueError, match="fps=0"):
        write_episode_video(tmp_path / "x.gif", t, pos, vel, lead, ((0, 1),), 5.0, fps=0)
    with pytest.raises(ValueError, match="t has 2 samples"):
        write_episode_video(tmp_path / "x.gif", t[:2], pos, vel, lead, ((0, 1),), 5.0)
    path = write_episode_video(
        tmp_path / "ok.gif",
        t,
        pos,
        vel,
        lead,
        ((0, 1),),
        5.0,
        fps=10,
        speed=1.0,
        size_px=(160, 160),
    )
    assert path.read_bytes()[:3] == b"GIF"
    assert not list(tmp_path.glob(".*"))  # no temporary file left behind
