"""The episode recording format: a folder of growing ``.npy`` arrays and a JSON manifest.

Format ``pairflock-recording``, version 1. One recording is one episode of one swarm::

    run.pfrec/
        manifest.json            what is recorded (see below), rewritten atomically
        positions.npy            (T, N, dim) one row per recorded step
        velocities.npy           (T, N, dim)
        ...                      every per-step array listed in manifest["arrays"]
        info.<key>.npy           (T,) float64, one per per-swarm info key
        pairs.npy                (M, 2) int32, static: agent m is the pair pairs[m]
        pair_target.npy          (M,) float32, static: d_m of each pair (m)

Why this container: every file is a plain ``.npy``, so numpy alone reads a recording (no h5py,
no zip: a zip or HDF5 file cut off by a crash loses its index, a ``.npy`` does not); arrays
are written as they grow and memory-mapped when read, so neither side holds an episode in
memory (10,000 UAVs x 5,000 steps is 2.4 GB of positions and velocities in float32).

Written incrementally: the writer buffers at most ``flush_steps`` steps, then appends them to
every array file, rewrites each file's fixed-width header with the new step count, and last
replaces ``manifest.json`` (write to a temporary file, then rename). A process killed at any
point leaves every step of the last completed flush readable; ``complete`` stays ``false``
until :meth:`RecordingWriter.close` ends the episode.

Read with numpy alone::

    import json, numpy as np
    man = json.load(open("run.pfrec/manifest.json"))
    q = np.load("run.pfrec/positions.npy", mmap_mode="r")     # (T, N, dim)
    T = min(np.load(f"run.pfrec/{a['file']}", mmap_mode="r").shape[0]
            for a in man["arrays"].values())                    # >= man["steps"]
    man["complete"]   # False: the writer was stopped before the episode ended

Manifest keys: ``format``, ``version``, ``complete``, ``stopped`` (why an incomplete recording
stopped, or null), ``steps`` (steps committed when the manifest was last written), ``num_uavs``
N, ``dim``, ``num_pairs`` M, ``dt`` (s per env step), ``every`` (one recorded step per
``every`` env steps; the ``step`` array gives each one's index), ``seed``, ``controller``,
``config`` (a JSON dict), ``safety_scope`` (``"agent"``: safety arrays per pair, or ``"uav"``),
``float_dtype``, ``metadata``, ``arrays`` (name: file, dtype, per-step shape, scope, unit,
description) and ``static`` (the same for ``pairs`` and ``pair_target``).

Precision: positions, velocities and the per-UAV / per-pair quantities are stored in float32 by
default (about 1 mm at 10 km from the origin: enough to replay and measure a run, not to
restart one bit for bit; pass ``float_dtype="float64"`` for that). ``time`` and the infos are
float64. Size per UAV-step at dim = 3 in float32: 28 bytes (positions 12, velocities 12,
closest distance 4) plus 2.5 per UAV of per-pair arrays, and 5 per UAV or pair for the safety
filter's ``safety_active`` (bool) and ``safety_correction``.

Versioning: ``version`` is an integer raised whenever a reader of the old version would
misread a new recording (a renamed or re-meant array); new optional arrays or manifest keys do
not raise it, and readers ignore what they do not know. :func:`open_recording` refuses a
version newer than :data:`VERSION`.
"""

from __future__ import annotations

import json
import math
import os
import time as _time
from collections.abc import Mapping
from typing import Any

import numpy as np

from pairflock_env.recording._npy import GrowingNpy, read_npy_header
from pairflock_env.recording.schema import (
    STEP_ARRAYS,
    check_config,
    check_pairs,
    check_path,
    check_scalar,
    json_safe,
)

__all__ = ["FORMAT", "VERSION", "Recording", "RecordingWriter", "open_recording"]

FORMAT = "pairflock-recording"
VERSION = 1
MANIFEST = "manifest.json"
_BUFFER_BYTES = 8 << 20  # default flush: when the buffered steps reach 8 MiB ...
_MAX_FLUSH_STEPS = 1024  # ... or this many steps ...
_FLUSH_SECONDS = 2.0  # ... or this long since the last flush


class RecordingWriter:
    """Writes one episode of one swarm, step by step, with bounded memory.

    Args:
        path: the recording folder to create (must not exist, or be empty).
        num_uavs: N; dim: 2 or 3; dt: seconds per env step.
        pairs: (M, 2) UAV indices of each agent's pair (agent UAV, partner); None: no pairs.
        pair_target: d_m, a scalar or (M,) in m.
        config, seed, controller, metadata: stored as they are (JSON).
        every: record one env step in ``every`` (see :meth:`wants`).
        safety_scope: ``"agent"`` (safety arrays (M,)) or ``"uav"`` ((N,)).
        float_dtype: ``"float32"`` or ``"float64"`` for the per-UAV and per-pair arrays.
        flush_steps: steps buffered before a flush (default: about 8 MiB of steps, <= 1024);
            ``flush_seconds``: a flush also happens when the last one is older than this.
        fsync: also force each flush to the disk (survives a power cut, not only a kill).

    Use as a context manager: leaving it normally closes the recording as complete, leaving
    it by an exception (Ctrl-C included) flushes what is buffered and marks it incomplete.
    """

    def __init__(
        self,
        path: str | os.PathLike,
        *,
        num_uavs: int,
        dim: int,
        dt: float,
        pairs: Any = None,
        pair_target: Any = None,
        config: Mapping[str, Any] | None = None,
        seed: Any = None,
        controller: str | None = None,
        every: int = 1,
        safety_scope: str = "agent",
        float_dtype: str = "float32",
        flush_steps: int | None = None,
        flush_seconds: float = _FLUSH_SECONDS,
        fsync: bool = False,
        metadata: Mapping[str, Any] | None = None,
    ):
        self.num_uavs = check_scalar("num_uavs", num_uavs, int, low=1)
        self.dim = check_scalar("dim", dim, int, choices=(2, 3))
        self.dt = check_scalar("dt", dt, float, low=0.0, open_low=True)
        self.every = check_scalar("every", every, int, low=1)
        if safety_scope not in ("agent", "uav"):
            raise ValueError(f"safety_scope={safety_scope!r}; valid: 'agent' or 'uav'")
        if float_dtype not in ("float32", "float64"):
            raise ValueError(f"float_dtype={float_dtype!r}; valid: 'float32' or 'float64'")
        if controller is not None and not isinstance(controller, str):
            raise TypeError(f"controller={controller!r}: expected a str or None")
        self.pairs, self.pair_target = check_pairs(pairs, pair_target, self.num_uavs)
        self.num_pairs = len(self.pairs)
        self.path = check_path(path)
        self._fsync = bool(fsync)
        self._flush_seconds = check_scalar("flush_seconds", flush_seconds, float, low=0.0)
        if flush_steps is None:  # ~ 4 arrays of (N, dim) float64 per step, in _BUFFER_BYTES
            per_step = 4 * self.num_uavs * self.dim * 8
            flush_steps = max(1, min(_MAX_FLUSH_STEPS, _BUFFER_BYTES // per_step))
        self._chunk = check_scalar("flush_steps", flush_steps, int, low=1)
        self.manifest = self._new_manifest(
            seed=json_safe(seed, "seed"),
            controller=controller,
            config=check_config(config),
            safety_scope=safety_scope,
            float_dtype=float_dtype,
            metadata=json_safe(dict(metadata or {}), "metadata"),
        )
        self._files: dict[str, GrowingNpy] = {}
        self._buffers: dict[str, np.ndarray] = {}
        self._info_keys: list[str] = []
        self._info_bufs: dict[str, np.ndarray] = {}  # key: its buffer
        self._fill = 0  # steps in the buffers
        self._last_step: int | None = None
        self._last_flush = _time.monotonic()
        self.closed = False
        os.makedirs(self.path, exist_ok=True)
        self._write_static()
        self._write_manifest()

    def _new_manifest(self, **given: Any) -> dict[str, Any]:
        return {
            "format": FORMAT,
            "version": VERSION,
            "complete": False,
            "stopped": None,
            "steps": 0,
            "num_uavs": self.num_uavs,
            "dim": self.dim,
            "num_pairs": self.num_pairs,
            "dt": self.dt,
            "every": self.every,
            **given,
            "created": _time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "arrays": {},
            "static": {},
        }

    # -- what a step holds -------------------------------------------------------------------
    def _row_shape(self, scope: str, vector: bool | int) -> tuple[int, ...]:
        if scope == "safety":
            scope = self.manifest["safety_scope"]
        lead = {"step": (), "uav": (self.num_uavs,), "agent": (self.num_pairs,)}[scope]
        if vector is True:
            return (*lead, self.dim)
        return (*lead, int(vector)) if vector else lead

    def _dtype(self, kind: str) -> np.dtype:
        return np.dtype(self.manifest["float_dtype"] if kind == "float" else kind)

    def _add_array(self, name: str, file: str, dtype: np.dtype, row: tuple, spec: dict) -> None:
        grow = GrowingNpy(os.path.join(self.path, file), dtype, row)
        self._files[name] = grow
        self.manifest["arrays"][name] = {
            "file": file,
            "dtype": dtype.str,
            "shape": list(row),
            **spec,
        }
        self._buffers[name] = np.empty((self._chunk, *row), dtype)

    def _open_arrays(self, given: Mapping[str, Any], infos: Mapping[str, Any]) -> None:
        for name, (scope, vector, kind, unit, text) in STEP_ARRAYS.items():
            if name in given:
                spec = {"scope": scope if scope != "safety" else self.manifest["safety_scope"]}
                spec.update(unit=unit, description=text)
                row = self._row_shape(scope, vector)
                self._add_array(name, f"{name}.npy", self._dtype(kind), row, spec)
        self._step_buffers = dict(self._buffers)  # the step arrays (the infos come and go)
        for key in infos:
            self._add_info(key)

    def _add_info(self, key: str) -> None:
        if not isinstance(key, str) or not key or any(c in key for c in '/\\:*?"<>|'):
            raise ValueError(f"infos key {key!r}: expected a non-empty name usable in a file name")
        spec = {"scope": "step", "unit": "", "description": f"per-swarm info {key!r}"}
        self._add_array(f"info.{key}", f"info.{key}.npy", np.dtype(np.float64), (), spec)
        self._info_keys.append(key)
        self._info_bufs[key] = self._buffers[f"info.{key}"]
        if self.manifest["steps"]:  # a key first given after the first flush: NaN before
            self._files[f"info.{key}"].append(np.full(self.manifest["steps"], np.nan))
        self._buffers[f"info.{key}"][: self._fill] = np.nan

    # -- writing ----------------------------------------------------------------------------
    def wants(self, step: int) -> bool:
        """Whether :meth:`append` records env step ``step`` (one in ``every``)."""
        return step % self.every == 0

    def append(
        self,
        step: int,
        *,
        time: float,
        positions: Any,
        velocities: Any,
        infos: Mapping[str, Any] | None = None,
        force: bool = False,
        **arrays: Any,
    ) -> bool:
        """Record env step ``step`` if :meth:`wants` it (or ``force``, for an episode's last
        step); return whether it was recorded.

        Args:
            time: simulated time (s); positions, velocities: (N, dim).
            infos: per-swarm scalars, any keys (a key missing at a step records NaN).
            arrays: the optional per-step arrays of ``STEP_ARRAYS`` (``leader_position``,
                ``leader_velocity`` (dim,); ``pair_distance``, ``pair_error`` (M,);
                ``safety_active``, ``safety_correction`` (M,) or (N,) by ``safety_scope``;
                ``closest_distance`` (N,)). Those given at the first recorded step must be
                given at every one.
        """
        if self.closed:
            raise ValueError(f"recording {self.path!r} is closed")
        if type(step) is not int or step < 0:
            step = check_scalar("step", step, int, low=0)
        if not (force or step % self.every == 0) or step == self._last_step:
            return False
        given = {"step": step, "time": time, "positions": positions, "velocities": velocities}
        given.update(arrays)
        if not self._files or given.keys() != self._step_buffers.keys():
            unknown = sorted(set(given) - set(STEP_ARRAYS))
            if unknown:
                raise TypeError(f"unknown recording arrays {unknown}; valid: {sorted(STEP_ARRAYS)}")
        infos = {} if infos is None else infos
        if not self._files:
            self._open_arrays(given, infos)
        self._put(given, infos)
        self._last_step = step
        self._fill += 1
        full = self._fill == self._chunk
        if full or _time.monotonic() - self._last_flush >= self._flush_seconds:
            self.flush()
        return True

    def _put(self, given: dict[str, Any], infos: Mapping[str, Any]) -> None:
        steps = self._step_buffers
        if given.keys() != steps.keys():
            raise ValueError(
                f"step arrays {sorted(given)} differ from those of the first recorded step "
                f"{sorted(steps)}"
            )
        row = self._fill
        for name, value in given.items():
            buf = steps[name]
            shape = value.shape if type(value) is np.ndarray else np.shape(value)
            if shape != buf.shape[1:]:
                raise ValueError(f"{name} of shape {shape}; expected {buf.shape[1:]}")
            buf[row] = value
        for key in infos:
            if key not in self._info_bufs:
                self._add_info(key)
        for key, buf in self._info_bufs.items():
            buf[row] = _info_value(infos.get(key, math.nan), key)

    def flush(self) -> None:
        """Append the buffered steps to the files and commit them (headers, then manifest)."""
        if self._fill:
            for name, grow in self._files.items():
                grow.append(self._buffers[name][: self._fill])
            for grow in self._files.values():
                grow.commit(self._fsync)
            self.manifest["steps"] += self._fill
            self._fill = 0
            self._write_manifest()
        self._last_flush = _time.monotonic()

    def close(self, complete: bool = True, stopped: str | None = None) -> None:
        """Flush and close; ``complete``: the episode was recorded to its end."""
        if self.closed:
            return
        self.flush()
        for grow in self._files.values():
            grow.close()
        self.manifest["complete"] = bool(complete)
        self.manifest["stopped"] = None if complete else (stopped or "closed early")
        self._write_manifest()
        self.closed = True

    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(complete=exc_type is None, stopped=exc_type and exc_type.__name__)

    def _write_static(self) -> None:
        for name, arr, unit, text in (
            ("pairs", self.pairs, "", "agent m flies the pair (pairs[m, 0], pairs[m, 1])"),
            ("pair_target", self.pair_target, "m", "target distance d_m of each pair"),
        ):
            np.save(os.path.join(self.path, f"{name}.npy"), arr)
            self.manifest["static"][name] = {
                "file": f"{name}.npy",
                "dtype": arr.dtype.str,
                "shape": list(arr.shape),
                "unit": unit,
                "description": text,
            }

    def _write_manifest(self) -> None:
        final = os.path.join(self.path, MANIFEST)
        tmp = final + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            json.dump(self.manifest, f, indent=1, allow_nan=False)
            if self._fsync:
                f.flush()
                os.fsync(f.fileno())
        os.replace(tmp, final)


def _info_value(value: Any, key: str) -> float:
    if type(value) in (float, int, bool, np.float64, np.float32, np.int64, np.bool_):
        return float(value)
    arr = np.asarray(value)
    if arr.size != 1 or arr.dtype.kind not in "biuf":
        raise ValueError(f"infos[{key!r}] = {value!r}: expected one real number or bool")
    return float(arr.reshape(()))


class Recording:
    """A recording opened for reading (see :func:`open_recording`); arrays are memory maps.

    Attributes:
        manifest: the manifest dict; steps: the recorded steps readable (T);
        complete: whether the writer closed the episode normally, with every step committed.
    """

    def __init__(self, path: str | os.PathLike):
        self.path = os.fspath(path)
        try:
            with open(os.path.join(self.path, MANIFEST), encoding="utf-8") as f:
                self.manifest = json.load(f)
        except FileNotFoundError:
            raise ValueError(f"{self.path!r} is not a recording: it has no {MANIFEST}") from None
        if self.manifest.get("format") != FORMAT:
            raise ValueError(
                f"{self.path!r}: format {self.manifest.get('format')!r}, not {FORMAT!r}"
            )
        version = self.manifest.get("version")
        if not isinstance(version, int) or version > VERSION:
            raise ValueError(
                f"{self.path!r}: format version {version!r}; this reader reads up to {VERSION}"
            )
        rows = [self._rows(a) for a in self.arrays_meta.values()]
        self.steps = min(rows, default=0)
        self.complete = bool(self.manifest["complete"]) and self.steps == self.manifest["steps"]

    def _rows(self, meta: Mapping[str, Any]) -> int:
        """Rows of an array file that its header counts and its data holds (a file cut short
        by a full disk holds fewer)."""
        dtype, shape, offset = read_npy_header(self._file(meta))
        row = dtype.itemsize * math.prod(shape[1:])
        held = (os.path.getsize(self._file(meta)) - offset) // row if row else shape[0]
        return min(shape[0], held)

    def _file(self, meta: Mapping[str, Any]) -> str:
        return os.path.join(self.path, meta["file"])

    @property
    def arrays_meta(self) -> dict[str, dict[str, Any]]:
        return self.manifest["arrays"]

    def __getattr__(self, key: str) -> Any:  # num_uavs, dim, dt, every, seed, ...
        manifest = self.__dict__.get("manifest", {})
        if key in manifest:
            return manifest[key]
        raise AttributeError(key)

    def __contains__(self, name: str) -> bool:
        return name in self.arrays_meta

    def __getitem__(self, name: str) -> np.ndarray:
        """The per-step array ``name`` (T, ...), read-only memory map (KeyError if absent)."""
        meta = self.arrays_meta[name]
        dtype, shape, offset = read_npy_header(self._file(meta))
        shape = (self.steps, *shape[1:])
        if self.steps == 0 or 0 in shape:  # numpy cannot map zero bytes
            return np.empty(shape, dtype)
        return np.memmap(self._file(meta), dtype, "r", offset, shape)

    def rows(self, name: str, index: Any, dtype: Any = None) -> np.ndarray:
        """A copy of the rows ``index`` (an int, slice or array of recorded steps) of the
        per-step array ``name``. The file is mapped only during the call, so reading a large
        recording block by block keeps this process's resident memory to one block."""
        arr = self[name]
        try:
            return np.array(arr[index], dtype=dtype)
        finally:
            del arr  # unmaps the file

    def get(self, name: str, default: Any = None) -> Any:
        """The per-step array ``name``, or ``default`` if the recording has none."""
        if name in self:
            return self[name]
        return default

    @property
    def infos(self) -> dict[str, np.ndarray]:
        """Per-swarm infos, key: (T,) float64."""
        return {n[5:]: self[n] for n in self.arrays_meta if n.startswith("info.")}

    @property
    def pairs(self) -> np.ndarray:
        return np.load(self._file(self.manifest["static"]["pairs"]))

    @property
    def pair_target(self) -> np.ndarray:
        return np.load(self._file(self.manifest["static"]["pair_target"]))

    def __repr__(self) -> str:
        state = "complete" if self.complete else "INCOMPLETE"
        return (
            f"Recording({self.path!r}, N={self.num_uavs}, dim={self.dim}, steps={self.steps}, "
            f"{state})"
        )


def open_recording(path: str | os.PathLike) -> Recording:
    """Open the recording folder ``path`` for reading (ValueError if it is not one)."""
    return Recording(path)
