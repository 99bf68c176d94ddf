"""Recording the episodes of a :class:`~pairflock_env.core.PairFlockCore`: one recording per
swarm and episode, whichever view (or rollout loop) drives the core.

:class:`CoreRecorder` turns what a core does into recordings: a reset of swarm ``b`` opens
``<folder>/swarm{b}_ep{n}.pfrec`` and records its step 0; every core step then appends one
step in ``every`` (and always the episode's last); the step where the swarm is terminated or
truncated closes the recording as complete. It reads the core's state right after each
``step``/``reset_rows`` returns, so a view's auto-reset (which calls ``reset_rows`` after
the step) starts the next episode's recording only after the ended one was written.

Two ways to feed it:

* :func:`record_core` (what :class:`~pairflock_env.envs.record.RecordEpisode` uses) replaces
  ``core.step`` and ``core.reset_rows`` on that one core object with wrappers that call the
  original and then the recorder; every view, the AEC env included, resets and steps through
  these two methods (``core.reset`` calls ``reset_rows``), so one hook serves them all.
  :meth:`CoreRecorder.close` puts the methods back.
* A rollout loop that builds its own core passes the recorder as its per-step callback
  (``recorder(k, core, result, live)``: k = 0 after the reset, then after every step), e.g.
  ``baselines.evaluation.rollout(..., on_step=recorder)``.

Memory: every open recording buffers at most its share of ``buffer_mb`` (and at most
``flush_seconds`` of steps) before writing them out. An exception that is not an ``Exception``
(Ctrl-C's ``KeyboardInterrupt``) inside a hooked call flushes every open recording before it
propagates, and recordings still open when the process exits are closed as incomplete, so an
interrupted run leaves readable recordings that say they are incomplete.
"""

from __future__ import annotations

import contextlib
import os
import string
import weakref
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from pairflock_env.recording.format import RecordingWriter
from pairflock_env.recording.schema import check_scalar, json_safe

__all__ = ["DEFAULT_NAME", "CoreRecorder", "record_core"]

#: the file name of a recording (without the ``.pfrec`` suffix); fields: swarm, episode, seed
DEFAULT_NAME = "swarm{swarm}_ep{episode}"
_FIELDS = {"swarm", "episode", "seed"}
_ENDED_EARLY = "closed before the episode ended"


def _seed_entry(seed: Any, k: int, n: int) -> Any:
    """What row ``k`` of a ``reset_rows`` of ``n`` rows was seeded with, as JSON (see
    :meth:`PairFlockCore.reset <pairflock_env.core.PairFlockCore.reset>` for the rules)."""

    def one(s: Any) -> Any:
        if isinstance(s, np.random.SeedSequence):
            return {"entropy": s.entropy, "spawn_key": list(s.spawn_key)}
        return json_safe(s, "seed")

    if seed is None:
        return None
    if isinstance(seed, (Sequence, np.ndarray)) and not isinstance(seed, str):
        return one(seed[k])
    return {"spawned_from": one(seed), "child": k, "children": n}


def _check_name(name: Any) -> str:
    if not isinstance(name, str):
        raise TypeError(f"name={name!r}: expected a str such as {DEFAULT_NAME!r}")
    fields = {f for _, f, _, _ in string.Formatter().parse(name) if f is not None}
    if not fields or not fields <= _FIELDS:
        raise ValueError(
            f"name={name!r}: expected a format string of the fields {{swarm}}, {{episode}} "
            f"and {{seed}} that tells the recordings apart, such as {DEFAULT_NAME!r}"
        )
    return name


def _check_folder(folder: Any, allow_existing: bool) -> str:
    if not isinstance(folder, (str, os.PathLike)):
        raise TypeError(f"path={folder!r}: expected a str or os.PathLike folder name")
    folder = os.fspath(folder)
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise ValueError(f"path={folder!r} is a file; expected a folder for the recordings")
    if os.path.isdir(folder) and not allow_existing:
        old = sorted(e for e in os.listdir(folder) if e.endswith(".pfrec"))
        if old:
            raise ValueError(
                f"path={folder!r} already holds recordings ({', '.join(old[:3])}"
                f"{', ...' if len(old) > 3 else ''}); expected a new folder or one without any "
                "(or allow_existing=True)"
            )
    return folder


class CoreRecorder:
    """Writes one recording per swarm and episode of a core (see the module docstring).

    Args:
        path: the folder of the recordings (created if missing; must hold no ``.pfrec`` yet
            unless ``allow_existing``: several recorders filling one folder, with names
            that differ, e.g. one per seed).
        controller: the name of what chose the pair actions (``"smc"``, ``"sb3:..."``).
        every: record one core step in ``every`` (the last step of an episode always).
        swarms: the swarms to record (default: all).
        max_episodes: record at most this many episodes per swarm (default: all).
        name: the file name of a recording, a format string of ``swarm``, ``episode`` and
            ``seed`` (``".pfrec"`` is appended); a name given twice is a ``FileExistsError``
            when the second recording opens (``"seed{seed}"`` suits one episode per seed).
        seeds: one seed per swarm, stored with episodes whose reset the recorder did not see
            (a rollout callback, which gets the core after its reset).
        buffer_mb: memory for buffered steps, shared by the open recordings.
        float_dtype, flush_seconds, fsync, metadata: as in
            :class:`~pairflock_env.recording.format.RecordingWriter`.

    Attributes:
        paths: the recordings written or being written, in the order they were opened.
    """

    def __init__(
        self,
        path: str | os.PathLike,
        *,
        controller: str | None = None,
        every: int = 1,
        swarms: Iterable[int] | None = None,
        max_episodes: int | None = None,
        name: str = DEFAULT_NAME,
        seeds: Sequence[Any] | None = None,
        buffer_mb: float = 64.0,
        float_dtype: str = "float32",
        flush_seconds: float = 2.0,
        fsync: bool = False,
        metadata: Mapping[str, Any] | None = None,
        allow_existing: bool = False,
    ) -> None:
        self.folder = _check_folder(path, bool(allow_existing))
        if controller is not None and not isinstance(controller, str):
            raise TypeError(f"controller={controller!r}: expected a str (its name) or None")
        self.controller = controller
        self.every = check_scalar("every", every, int, low=1)
        if max_episodes is not None:
            max_episodes = check_scalar("max_episodes", max_episodes, int, low=1)
        self.max_episodes = max_episodes
        self.name = _check_name(name)
        self._swarms = None if swarms is None else _check_swarms(swarms)
        self._seeds = None if seeds is None else list(seeds)
        self._budget = check_scalar("buffer_mb", buffer_mb, float, low=0.0, open_low=True) * 1e6
        if float_dtype not in ("float32", "float64"):
            raise ValueError(f"float_dtype={float_dtype!r}; valid: 'float32' or 'float64'")
        self._writer_kw = dict(
            float_dtype=float_dtype,
            flush_seconds=check_scalar("flush_seconds", flush_seconds, float, low=0.0),
            fsync=bool(fsync),
        )
        self._metadata = json_safe(dict(metadata or {}), "metadata")
        self.paths: list[str] = []
        self.core: Any = None
        self._hooked: Any = None
        #: open recordings by swarm; shared with the exit finalizer, as is the state
        self._open: dict[int, RecordingWriter] = {}
        self._state: dict[str, Any] = {"stopped": None}
        self._finalizer = weakref.finalize(self, _close_open, self._open, self._state)

    # ------------------------------------------------------------------ binding
    def bind(self, core: Any) -> CoreRecorder:
        """Read what every recording of ``core`` shares (its config and pairs); the first
        reset or step seen binds the core too. A recorder serves one core."""
        if self.core is core:
            return self
        if self.core is not None:
            raise ValueError("this recorder already records another core; make a new one")
        B = core.num_swarms
        if self._swarms is not None and max(self._swarms) >= B:
            raise ValueError(f"swarms={sorted(self._swarms)}: the core has swarms 0..{B - 1}")
        if self._seeds is not None and len(self._seeds) != B:
            raise ValueError(f"seeds has {len(self._seeds)} entries; the core has {B} swarms")
        cfg = core.config
        self.core = core
        self._pairs = np.asarray(core.agent_uavs).reshape(-1, 2)  # agents A0, B0, A1, B1, ...
        self._swarm_keys: list[str] | None = None
        self._pair_target = np.asarray(cfg.d_m_array, float)
        self._safety = cfg.safety_filter != "none"
        # a vehicle fed setpoints (the Crazyflie) shows the rows it flew
        self._setpoints = getattr(core.vehicle, "setpoint", None) is not None
        self._config = cfg.to_dict()
        self._episodes = np.zeros(B, np.int64)
        self._seed_given: list[Any] = [None] * B
        self._since_seed = np.zeros(B, np.int64)
        recorded = B if self._swarms is None else len(self._swarms)
        itemsize = 4 if self._writer_kw["float_dtype"] == "float32" else 8
        per_step = cfg.n_uavs * (2 * cfg.dim * itemsize + itemsize + 1 + itemsize) + 256
        self._flush_steps = int(max(1, min(1024, self._budget / recorded / per_step)))
        return self

    def attach(self, core: Any) -> CoreRecorder:
        """Bind ``core`` and hook its ``step`` and ``reset_rows`` (this object only): every
        reset and step from now on is recorded. :meth:`close` unhooks them."""
        self.bind(core)
        if self._hooked is not None:
            return self
        step, reset_rows = core.step, core.reset_rows

        def hooked_step(actions: Any) -> Any:
            res = self._guarded(step, actions)
            self.on_step(res)
            return res

        def hooked_reset_rows(rows: Any, seed: Any = None, options: Any = None) -> Any:
            res = self._guarded(reset_rows, rows, seed=seed, options=options)
            self.on_reset(np.asarray(rows, np.int64).reshape(-1), res, seed)
            return res

        core.step, core.reset_rows = hooked_step, hooked_reset_rows
        self._hooked = (hooked_step, hooked_reset_rows)
        return self

    def _guarded(self, method: Any, *args: Any, **kwargs: Any) -> Any:
        try:
            return method(*args, **kwargs)
        except Exception:
            raise
        except BaseException as exc:  # Ctrl-C (or SystemExit) in the middle of a step
            self._state["stopped"] = type(exc).__name__
            for w in self._open.values():
                w.flush()
            raise

    def _detach(self) -> None:
        core, hooked = self.core, self._hooked
        if hooked is None:
            return
        for attr, fn in zip(("step", "reset_rows"), hooked, strict=True):
            if core.__dict__.get(attr) is fn:
                del core.__dict__[attr]
        self._hooked = None

    # ------------------------------------------------------------------ events
    def _recorded(self, b: int) -> bool:
        return self._swarms is None or b in self._swarms

    def on_reset(self, rows: np.ndarray, res: Any, seed: Any = None) -> None:
        """Swarms ``rows`` were reset (``res``: the core's result, ``seed``: the argument of
        ``reset_rows``): close their open recordings, open new ones at step 0."""
        core = self.core
        for k, b in enumerate(rows.tolist()):
            if not self._recorded(b):
                continue
            entry = _seed_entry(seed, k, len(rows))
            if seed is not None:
                self._seed_given[b], self._since_seed[b] = entry, 0
            else:
                self._since_seed[b] += 1
            old = self._open.pop(b, None)
            if old is not None:
                old.close(complete=False, stopped="reset before the episode ended")
            if self.max_episodes is not None and self._episodes[b] >= self.max_episodes:
                continue
            self._open[b] = self._new_writer(b, entry)
            self._episodes[b] += 1
        self._append(rows.tolist(), res, np.zeros(core.num_swarms, bool))

    def _new_writer(self, b: int, seed: Any) -> RecordingWriter:
        core, n = self.core, int(self._episodes[b])
        if seed is None and self._seeds is not None and n == 0:
            seed = json_safe(self._seeds[b], "seeds")
        file = self.name.format(swarm=b, episode=n, seed=seed) + ".pfrec"
        path = os.path.join(self.folder, file)
        meta = dict(self._metadata, swarm=b, episode=n, num_swarms=core.num_swarms)
        if seed is None:  # continued the swarm's generator: say from which seed
            meta.update(seeded=self._seed_given[b], resets_since_seed=int(self._since_seed[b]))
        os.makedirs(self.folder, exist_ok=True)
        writer = RecordingWriter(
            path,
            num_uavs=core.config.n_uavs,
            dim=core.config.dim,
            dt=core.config.dt,
            pairs=self._pairs,
            pair_target=self._pair_target,
            config=self._config,
            seed=seed,
            controller=self.controller,
            every=self.every,
            safety_scope="uav",
            flush_steps=self._flush_steps,
            metadata=meta,
            **self._writer_kw,
        )
        self.paths.append(path)
        return writer

    def on_step(self, res: Any) -> None:
        """The core stepped (``res``: its result): record the open swarms' step when due,
        and close the recordings of the swarms whose episode ended."""
        if not self._open:
            return
        done = np.asarray(res.terminated) | np.asarray(res.truncated)
        rows = sorted(self._open)
        self._append(rows, res, done)
        for b in [b for b in rows if done[b]]:
            w = self._open.pop(b)
            w.manifest["metadata"]["ended_by"] = "terminated" if res.terminated[b] else "truncated"
            w.close(complete=True)

    def _append(self, rows: list[int], res: Any, done: np.ndarray) -> None:
        core, every, writers = self.core, self.every, self._open
        steps, ended = core.steps.tolist(), done.tolist()
        due = [b for b in rows if b in writers and (steps[b] % every == 0 or ended[b])]
        if not due:
            return
        info = res.info
        if self._swarm_keys is None:  # the per-swarm infos: (B,) arrays
            B = core.num_swarms
            self._swarm_keys = [k for k, v in info.items() if np.ndim(v) == 1 and len(v) == B]
        lq, lp = core.leader_state()
        closest = core.closest_distance
        t = core.t.tolist()
        for b in due:
            arrays = dict(
                leader_position=lq[b],
                leader_velocity=lp[b],
                pair_distance=info["pair_distance"][b, ::2],  # the A agent of each pair
                pair_error=info["pair_error"][b, ::2],
                closest_distance=closest[b],
            )
            if self._safety:
                arrays.update(self._safety_per_uav(info, b))
            if self._setpoints:
                arrays["setpoint"] = core.vehicle.setpoint[b]
            writers[b].append(
                steps[b],
                force=ended[b],
                time=t[b],
                positions=core.q[b],
                velocities=core.p[b],
                infos={k: info[k][b] for k in self._swarm_keys},
                **arrays,
            )

    def _safety_per_uav(self, info: Mapping[str, np.ndarray], b: int) -> dict[str, np.ndarray]:
        """The safety stage's per-agent infos of swarm ``b`` on the UAVs (0 elsewhere)."""
        n, au = self.core.config.n_uavs, self.core.agent_uavs
        active, corr = np.zeros(n, bool), np.zeros(n)
        active[au] = info["safety_active"][b]
        corr[au] = info["safety_correction"][b]
        return dict(safety_active=active, safety_correction=corr)

    def __call__(self, k: int, core: Any, res: Any, live: Any = None) -> None:
        """A rollout's per-step callback: ``k = 0`` after the reset of every swarm (seeded
        as ``seeds``), then after every step."""
        self.bind(core)
        if k == 0:
            self.on_reset(np.arange(core.num_swarms), res, None)
        else:
            self.on_step(res)

    # ------------------------------------------------------------------ closing
    def flush(self) -> None:
        """Write every buffered step of the open recordings to disk."""
        for w in self._open.values():
            w.flush()

    def close(self, stopped: str | None = None) -> None:
        """Close the open recordings as incomplete (their episode has not ended; ``stopped``
        says why, default: closed before the episode ended) and unhook the core."""
        self._detach()
        reason = stopped or self._state["stopped"] or _ENDED_EARLY
        while self._open:
            self._open.popitem()[1].close(complete=False, stopped=reason)

    @property
    def closed(self) -> bool:
        return self._hooked is None and not self._open

    def __enter__(self) -> CoreRecorder:
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        self.close(stopped=None if exc_type is None else exc_type.__name__)


def _check_swarms(swarms: Iterable[int]) -> frozenset[int]:
    if isinstance(swarms, (str, bytes)) or not isinstance(swarms, Iterable):
        raise TypeError(f"swarms={swarms!r}: expected swarm indices (ints) or None")
    out = [check_scalar("swarms", s, int, low=0) for s in swarms]
    if not out:
        raise ValueError("swarms=[]: expected at least one swarm index (or None for all)")
    return frozenset(out)


def _close_open(writers: dict[int, RecordingWriter], state: dict[str, Any]) -> None:
    """At exit (or when the recorder is collected): close what is still open, incomplete."""
    reason = state["stopped"] or "the process ended before the episode ended"
    while writers:
        writer = writers.popitem()[1]
        with contextlib.suppress(OSError):  # its folder was removed meanwhile: nothing to mark
            writer.close(complete=False, stopped=reason)


def record_core(core: Any, path: str | os.PathLike, **options: Any) -> CoreRecorder:
    """Record every episode ``core`` runs from now on into the folder ``path`` (one recording
    per swarm and episode); ``options`` are :class:`CoreRecorder`'s. Returns the recorder:
    close it (or use it in a ``with`` block) when the run is over.

    >>> import tempfile
    >>> from pairflock_env import PairFlockCore
    >>> core = PairFlockCore(preset="paper", n_uavs=6, max_cycles=3)
    >>> folder = tempfile.mkdtemp()
    >>> with record_core(core, folder, controller="zero") as rec:
    ...     res = core.reset(seed=0)
    ...     for _ in range(3):
    ...         res = core.step(np.zeros((1, core.n_agents, 2)))
    >>> [os.path.basename(p) for p in rec.paths]
    ['swarm0_ep0.pfrec']
    """
    return CoreRecorder(path, **options).attach(core)
