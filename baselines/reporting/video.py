"""Episode videos (mp4 through imageio-ffmpeg, or gif) from a recorded trajectory; headless.

Frames are drawn with :class:`pairflock_env.render.SwarmRenderer` (the same picture as the
env's ``render_mode="rgb_array"``). The view follows the swarm: it is fitted to every frame
and low-pass filtered so that it glides instead of jumping.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from baselines.runtime import optional
from baselines.runtime.files import atomic_path
from pairflock_env.render import SwarmRenderer, fit_limits

__all__ = ["VIDEO_FORMATS", "write_episode_video"]

VIDEO_FORMATS = (".mp4", ".gif")


def _view_limits(positions: np.ndarray, leader: np.ndarray, smoothing: float) -> np.ndarray:
    """Per-frame (xmin, xmax, ymin, ymax), each fitted then exponentially smoothed; the
    smoothed box is widened where needed so that no UAV leaves the picture."""
    raw = np.array([fit_limits(q, lq) for q, lq in zip(positions, leader, strict=False)])
    out = np.empty_like(raw)
    out[0] = raw[0]
    for k in range(1, len(raw)):
        out[k] = smoothing * out[k - 1] + (1.0 - smoothing) * raw[k]
        out[k, 0] = min(out[k, 0], raw[k, 0])
        out[k, 2] = min(out[k, 2], raw[k, 2])
        out[k, 1] = max(out[k, 1], raw[k, 1])
        out[k, 3] = max(out[k, 3], raw[k, 3])
    # keep the aspect square after widening
    half = 0.5 * np.maximum(out[:, 1] - out[:, 0], out[:, 3] - out[:, 2])
    cx, cy = 0.5 * (out[:, 0] + out[:, 1]), 0.5 * (out[:, 2] + out[:, 3])
    return np.stack([cx - half, cx + half, cy - half, cy + half], axis=1)


def write_episode_video(
    path: str | Path,
    t: np.ndarray,
    positions: np.ndarray,
    velocities: np.ndarray,
    leader_positions: np.ndarray,
    pairs,
    d_m,
    *,
    fps: int = 25,
    speed: float = 5.0,
    title: str = "",
    size_px: tuple[int, int] = (640, 640),
    smoothing: float = 0.9,
    pair_error: np.ndarray | None = None,
    error_t: np.ndarray | None = None,
) -> Path:
    """Write an animation of one recorded episode to ``path`` (.mp4 or .gif), atomically.

    Args:
        t: sample times (T,) of ``positions``/``velocities`` (T, N, dim) and
            ``leader_positions`` (T, dim); 3-D states are drawn in the x-y plane.
        fps: frames per second of the file.  speed: simulated seconds per video second;
            frames are the samples nearest to ``k * speed / fps``.
        pair_error, error_t: optional error series of pair 0 shown in each frame's title.
    Returns the path written.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in VIDEO_FORMATS:
        raise ValueError(
            f"video path {str(path)!r} is invalid: the extension must be one of "
            f"{', '.join(VIDEO_FORMATS)}"
        )
    if isinstance(fps, bool) or not isinstance(fps, (int, np.integer)) or fps < 1:
        raise ValueError(f"fps={fps!r} is invalid: must be an integer >= 1")
    if not np.isfinite(speed) or speed <= 0:
        raise ValueError(f"speed={speed!r} is invalid: must be a number > 0")
    t = np.asarray(t, dtype=float)
    if len(t) != len(positions):
        raise ValueError(f"t has {len(t)} samples but positions has {len(positions)}")
    want = np.arange(t[0], t[-1] + 1e-9, speed / fps)
    idx = np.unique(np.searchsorted(t, want).clip(0, len(t) - 1))
    limits = _view_limits(np.asarray(positions)[idx], np.asarray(leader_positions)[idx], smoothing)
    renderer = SwarmRenderer(pairs, d_m, "rgb_array", size_px=size_px)
    frames = []
    for n, k in enumerate(idx):
        text = f"{title}\nt = {t[k]:5.1f} s" if title else f"t = {t[k]:5.1f} s"
        if pair_error is not None and error_t is not None:
            e = float(np.interp(t[k], error_t, pair_error))
            text += f"   pair error = {e:+.2f} m"
        frames.append(
            renderer.rgb_array(
                positions[k], velocities[k], leader_positions[k], text, limits=tuple(limits[n])
            )
        )
    renderer.close()
    return _write_frames(path, frames, fps)


def _write_frames(path: Path, frames: list[np.ndarray], fps: int) -> Path:
    imageio = optional.load("imageio.v2", "--video")
    kwargs: dict[str, Any]
    if path.suffix.lower() == ".mp4":
        optional.load("imageio_ffmpeg", "mp4 video (or write a .gif)")
        kwargs = dict(
            format="FFMPEG",
            fps=fps,
            codec="libx264",
            quality=6,
            pixelformat="yuv420p",
            macro_block_size=16,
            ffmpeg_log_level="error",
        )
    else:
        kwargs = dict(format="GIF", duration=1000.0 / fps, loop=0)
    with atomic_path(path) as tmp, imageio.get_writer(tmp, **kwargs) as w:
        for f in frames:
            w.append_data(f)
    return path
