"""``RecordEpisode(env, path, every=k)``: record the episodes of any view, one recording per
swarm and episode (``<path>/swarm{b}_ep{n}.pfrec``), in the style of Gymnasium's wrappers.

The wrapper works the same for every view because it records the view's
:class:`~pairflock_env.core.PairFlockCore`, not the view: it finds the core (``env.core``, or
through ``unwrapped`` / ``env`` / ``venv``) and hooks that core's ``step`` and ``reset_rows``
(:func:`~pairflock_env.recording.episodes.record_core`), which every view calls: PettingZoo
parallel and AEC, Gymnasium single and vector, and SB3's VecEnv. Each step is read right
after the core returns it, before a view's auto-reset starts the next episode. The object
returned is a wrapper of the view's own family (a ``gymnasium.Wrapper``, a
``gymnasium.vector.VectorWrapper``, a PettingZoo ``BaseParallelWrapper`` or ``BaseWrapper``,
an SB3 ``VecEnvWrapper``), so code that checks the env's type keeps working, and it is an
instance of :class:`RecordEpisode`. ``close()`` closes the env, then the recordings (those
whose episode had not ended are marked incomplete).

>>> import tempfile
>>> import numpy as np
>>> import pairflock_env as pf
>>> folder = tempfile.mkdtemp()
>>> env = RecordEpisode(pf.parallel_env(n_uavs=6, max_cycles=5), folder, controller="zero")
>>> obs, infos = env.reset(seed=0)
>>> while env.agents:
...     obs, *_ = env.step({a: np.zeros(2, np.float32) for a in env.agents})
>>> env.close()
>>> from pairflock_env.recording import open_recording
>>> rec = open_recording(env.recorder.paths[0])
>>> rec.steps, rec.complete, rec.controller
(6, True, 'zero')
"""

from __future__ import annotations

import importlib
import os
import sys
from typing import Any

import gymnasium
from gymnasium.vector import VectorEnv, VectorWrapper
from pettingzoo.utils.env import AECEnv, ParallelEnv
from pettingzoo.utils.wrappers import BaseParallelWrapper, BaseWrapper

from pairflock_env.core import PairFlockCore
from pairflock_env.recording.episodes import CoreRecorder, record_core

__all__ = ["RecordEpisode", "find_core"]

_LINKS = ("core", "unwrapped", "env", "venv")


def find_core(env: Any) -> PairFlockCore:
    """The :class:`~pairflock_env.core.PairFlockCore` behind a view or a wrapped view
    (``TypeError`` naming ``env`` if there is none)."""
    todo, seen = [env], set()
    while todo and len(seen) < 32:
        obj = todo.pop(0)
        if isinstance(obj, PairFlockCore):
            return obj
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        for link in _LINKS:
            try:
                nxt = getattr(obj, link, None)
            except Exception:  # a wrapper that refuses an attribute has no core there
                nxt = None
            if nxt is not None and nxt is not obj:
                todo.append(nxt)
    raise TypeError(
        f"env={env!r} is not a pairflock_env view: no PairFlockCore behind it (looked through "
        f"{', '.join('.' + a for a in _LINKS)})"
    )


class RecordEpisode:
    """Record every episode of ``env``'s swarms into the folder ``path``.

    Args:
        env: any pairflock_env view (PettingZoo parallel or AEC, Gymnasium single or vector,
            SB3 VecEnv), wrapped or not.
        path: the folder of the recordings (created if missing; must hold no ``.pfrec``).
        every: record one control step in ``every`` (an episode's last step always).
        controller: the name of what chooses the actions, stored in each recording.
        options: :class:`~pairflock_env.recording.episodes.CoreRecorder`'s (``swarms``,
            ``max_episodes``, ``name``, ``buffer_mb``, ``float_dtype``, ``flush_seconds``,
            ``fsync``, ``metadata``).

    Attributes:
        recorder: the :class:`~pairflock_env.recording.episodes.CoreRecorder`; its ``paths``
            list the recordings.

    Episodes that began before the wrapper was made are not recorded: recording starts at
    each swarm's next reset. Use the wrapper in a ``with`` block (or call ``close()``) so that
    an interrupted run marks its recordings incomplete at once; otherwise that happens when
    the process exits.
    """

    recorder: CoreRecorder

    def __new__(cls, env: Any, *args: Any, **kwargs: Any) -> RecordEpisode:
        family = _family(env) if cls is RecordEpisode else cls
        return super(RecordEpisode, family).__new__(family)

    def _start(self, env: Any, path: Any, every: int, controller: Any, options: Any) -> None:
        core = find_core(env)
        self.recorder = record_core(core, path, every=every, controller=controller, **options)

    def close(self, **kwargs: Any) -> None:
        """Close the env, then the recordings."""
        try:
            super().close(**kwargs)
        finally:
            self.recorder.close()

    def __enter__(self) -> Any:
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        try:
            super().close()
        finally:
            self.recorder.close(stopped=None if exc_type is None else exc_type.__name__)


class RecordEpisodeEnv(RecordEpisode, gymnasium.Wrapper):
    """:class:`RecordEpisode` of a Gymnasium ``Env``."""

    def __init__(self, env: gymnasium.Env, path: str | os.PathLike, *, every: int = 1,
                 controller: str | None = None, **options: Any) -> None:  # fmt: skip
        gymnasium.Wrapper.__init__(self, env)
        self._start(env, path, every, controller, options)


class RecordEpisodeVector(RecordEpisode, VectorWrapper):
    """:class:`RecordEpisode` of a Gymnasium ``VectorEnv``."""

    def __init__(self, env: VectorEnv, path: str | os.PathLike, *, every: int = 1,
                 controller: str | None = None, **options: Any) -> None:  # fmt: skip
        VectorWrapper.__init__(self, env)
        self._start(env, path, every, controller, options)


class RecordEpisodeParallel(RecordEpisode, BaseParallelWrapper):
    """:class:`RecordEpisode` of a PettingZoo ``ParallelEnv``."""

    def __init__(self, env: ParallelEnv, path: str | os.PathLike, *, every: int = 1,
                 controller: str | None = None, **options: Any) -> None:  # fmt: skip
        BaseParallelWrapper.__init__(self, env)
        self._start(env, path, every, controller, options)


class RecordEpisodeAEC(RecordEpisode, BaseWrapper):
    """:class:`RecordEpisode` of a PettingZoo ``AECEnv`` (the physics runs in its parallel
    env's core, so the records are the same as the parallel env's)."""

    def __init__(self, env: AECEnv, path: str | os.PathLike, *, every: int = 1,
                 controller: str | None = None, **options: Any) -> None:  # fmt: skip
        BaseWrapper.__init__(self, env)
        self._start(env, path, every, controller, options)


_SB3_CLASS: list[type] = []


def _sb3_wrapper_class() -> type:
    """:class:`RecordEpisode` of an SB3 ``VecEnv``, made on first use: its base class comes
    from stable-baselines3, which is loaded only where an SB3 env exists."""
    if not _SB3_CLASS:
        base = importlib.import_module("stable_baselines3.common.vec_env").VecEnvWrapper

        def __init__(self, venv, path, *, every=1, controller=None, **options):
            base.__init__(self, venv)
            self._start(venv, path, every, controller, options)

        def reset(self):
            return self.venv.reset()

        def step_wait(self):
            return self.venv.step_wait()

        doc = ":class:`RecordEpisode` of a stable-baselines3 ``VecEnv``."
        members = dict(__init__=__init__, reset=reset, step_wait=step_wait, __doc__=doc)
        members["__module__"] = __name__
        _SB3_CLASS.append(type("RecordEpisodeVecEnv", (RecordEpisode, base), members))
    return _SB3_CLASS[0]


def _family(env: Any) -> type:
    """The wrapper class for ``env``'s API family."""
    if isinstance(env, VectorEnv):
        return RecordEpisodeVector
    if isinstance(env, gymnasium.Env):
        return RecordEpisodeEnv
    if isinstance(env, ParallelEnv):
        return RecordEpisodeParallel
    if isinstance(env, AECEnv):
        return RecordEpisodeAEC
    sb3 = sys.modules.get("stable_baselines3.common.vec_env")
    if sb3 is not None and isinstance(env, sb3.VecEnv):
        return _sb3_wrapper_class()
    raise TypeError(
        f"env={env!r} is invalid: expected a pairflock_env view (a PettingZoo ParallelEnv or "
        "AECEnv, a Gymnasium Env or VectorEnv, or a stable-baselines3 VecEnv)"
    )
