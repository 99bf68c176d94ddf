"""The replay of a recording: one self-contained HTML page (``pairflock-replay FILE -o
replay.html``, or :func:`build_replay`)."""

from pairflock_env.replay.build import build_replay, closest_pass
from pairflock_env.replay.demo import write_demo

__all__ = ["build_replay", "closest_pass", "write_demo"]
