"""A recording turned into the replay's compact payload: a JSON header and binary sections.

Positions are quantised per replayed step k to ``origin_k + 2**exp_k * v`` with ``v`` a uint16
(65535 marks a non-finite position): ``exp_k`` is the smallest power of two whose 65534 steps
span the swarm, so the resolution is extent / 65534 or better (1 mm for a 65 m swarm) and
changes rarely. ``v`` is stored as its difference from the previous step (mod 2**16, exact),
which deflate compresses to 2-3 bytes per UAV-step at dim = 3. Per UAV-step also: the safety
level (uint8: 0 inactive, 1..255 the correction's share of the run's largest) and the closest
distance (float16); per pair-step the pair distance and error (float16). The sections are read
from the recording's memory maps a block of steps at a time, so memory stays bounded.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np

__all__ = ["BLOCK", "Payload", "plan_steps"]

BLOCK = 64  # replayed steps read per block
HIDDEN = 65535  # the uint16 code of a non-finite position
_LEVELS = 254  # safety levels 1..255


def _bytes_per_step(rec: Any) -> int:
    n, m, d = rec.num_uavs, rec.num_pairs, rec.dim
    s = (n if rec.safety_scope == "uav" else m) if "safety_active" in rec else 0
    return n * d * 2 + s + 2 * n * ("closest_distance" in rec) + 4 * m + 8 * d + 24


def plan_steps(rec: Any, stride: int | None, max_bytes: int, keep: tuple[int, ...] = ()):
    """The recorded steps to replay: one in ``stride`` (by default the smallest stride whose
    decoded payload fits ``max_bytes``), plus the last one and those in ``keep``."""
    if rec.steps == 0:
        raise ValueError(f"recording {rec.path!r} holds no step")
    if stride is None:
        stride = max(1, math.ceil(rec.steps * _bytes_per_step(rec) / max_bytes))
    idx = set(range(0, rec.steps, stride)) | {rec.steps - 1} | set(keep)
    return np.array(sorted(idx), dtype=np.int64), stride


def _blocks(idx: np.ndarray) -> Iterator[np.ndarray]:
    for start in range(0, len(idx), BLOCK):
        yield idx[start : start + BLOCK]


class Payload:
    """The replay payload of recording ``rec`` at the recorded steps ``idx``.

    ``sections`` describes the binary sections (name, dtype, shape, offset, bytes) for the
    page's JSON header; :meth:`chunks` yields them in order, each padded to 8 bytes.
    """

    def __init__(self, rec: Any, idx: np.ndarray):
        self.rec, self.idx = rec, idx
        self.dim, self.n = rec.dim, rec.num_uavs
        self._quantiser()
        self.safety_max = 0.0
        self.sections: list[dict[str, Any]] = []
        self._producers: list[Any] = []
        self._plan()

    def _quantiser(self) -> None:
        lo = np.zeros((len(self.idx), self.dim))
        span = np.zeros(len(self.idx))
        for k0, block in zip(range(0, len(self.idx), BLOCK), _blocks(self.idx), strict=True):
            x = self.rec.rows("positions", block, np.float64)
            x[~np.isfinite(x).all(axis=2)] = np.nan
            with warnings.catch_warnings():  # a step whose every UAV is non-finite
                warnings.simplefilter("ignore", RuntimeWarning)
                a, b = np.nanmin(x, axis=1), np.nanmax(x, axis=1)
            a, b = np.nan_to_num(a), np.nan_to_num(b)
            lo[k0 : k0 + len(block)], span[k0 : k0 + len(block)] = a, (b - a).max(axis=1)
        self.exp = np.ceil(np.log2(np.maximum(span, 1e-9) / (HIDDEN - 1))).astype(np.int8)
        self.origin = lo
        self.offset = lo[0].copy()  # the scene origin: the viewer works relative to it

    def _add(self, name: str, dtype: str, shape: tuple[int, ...], producer: Any) -> None:
        offset = self.sections[-1]["end"] if self.sections else 0
        nbytes = int(np.prod(shape)) * np.dtype(dtype).itemsize
        self.sections.append(
            dict(name=name, dtype=dtype, shape=list(shape), offset=offset, nbytes=nbytes)
        )
        self.sections[-1]["end"] = offset + -(-nbytes // 8) * 8
        self._producers.append(producer)

    def _plan(self) -> None:
        rec, K, n, d = self.rec, len(self.idx), self.n, self.dim
        self._add("time", "float64", (K,), lambda: [self._take("time", np.float64)])
        self._add("step", "int32", (K,), lambda: [self._take("step", np.int32)])
        self._add("origin", "float64", (K, d), lambda: [self.origin - self.offset])
        self._add("exp", "int8", (K,), lambda: [self.exp])
        self._add("positions", "uint16", (K, n, d), self._positions)
        self._add("pairs", "int32", (rec.num_pairs, 2), lambda: [rec.pairs])
        self._add("pair_target", "float32", (rec.num_pairs,), lambda: [rec.pair_target])
        if "leader_position" in rec:
            self._add("leader", "float32", (K, d), self._leader)
        if "safety_active" in rec or "safety_correction" in rec:
            width = n if rec.safety_scope == "uav" else rec.num_pairs
            self._add("safety", "uint8", (K, width), self._safety)
            self.safety_max = self._largest_correction()
        for name in ("closest_distance", "pair_distance", "pair_error"):
            if name in rec:
                width = n if name == "closest_distance" else rec.num_pairs
                self._add(name, "float16", (K, width), self._halves(name))

    def _take(self, name: str, dtype: Any) -> np.ndarray:
        return self.rec.rows(name, self.idx, dtype)

    def _positions(self) -> Iterator[np.ndarray]:
        prev = None
        for k0, block in zip(range(0, len(self.idx), BLOCK), _blocks(self.idx), strict=True):
            x = self.rec.rows("positions", block, np.float64)
            sl = slice(k0, k0 + len(block))
            scale = np.exp2(self.exp[sl].astype(np.float64))[:, None, None]
            with np.errstate(invalid="ignore"):
                v = np.rint((x - self.origin[sl, None, :]) / scale)
            v[~np.isfinite(v).all(axis=2)] = HIDDEN
            v = np.clip(v, 0, HIDDEN).astype(np.uint16)
            delta = v.copy()
            delta[1:] -= v[:-1]  # uint16 arithmetic wraps: exact mod 2**16
            if prev is not None:
                delta[0] -= prev
            prev = v[-1].copy()
            yield delta

    def _leader(self) -> Iterator[np.ndarray]:
        yield self.rec.rows("leader_position", self.idx, np.float64) - self.offset

    def _largest_correction(self) -> float:
        top = 0.0
        if "safety_correction" in self.rec:
            for block in _blocks(self.idx):
                c = self.rec.rows("safety_correction", block, np.float64)
                c = np.nan_to_num(np.abs(c), posinf=0.0)
                top = max(top, float(c.max(initial=0.0)))
        return top

    def _safety(self) -> Iterator[np.ndarray]:
        rec, top = self.rec, self.safety_max
        has_corr = "safety_correction" in rec
        for block in _blocks(self.idx):
            c = rec.rows("safety_correction", block, np.float64) if has_corr else None
            on = rec.rows("safety_active", block, bool) if "safety_active" in rec else c > 0
            if c is None or top == 0.0:
                yield np.where(on, 255, 0).astype(np.uint8)
                continue
            c = np.nan_to_num(np.abs(c), posinf=top)
            level = 1 + np.rint(_LEVELS * np.clip(c / top, 0.0, 1.0))
            yield np.where(on, level, 0).astype(np.uint8)

    def _halves(self, name: str):
        def produce() -> Iterator[np.ndarray]:
            for block in _blocks(self.idx):
                yield self.rec.rows(name, block, np.float16)

        return produce

    def chunks(self) -> Iterator[bytes]:
        """The binary payload: every section's bytes in order, each padded to 8 bytes."""
        for sec, produce in zip(self.sections, self._producers, strict=True):
            size = 0
            for arr in produce():
                raw = np.ascontiguousarray(arr, dtype=sec["dtype"]).tobytes()
                size += len(raw)
                yield raw
            if size != sec["nbytes"]:
                raise RuntimeError(f"section {sec['name']}: {size} bytes, planned {sec['nbytes']}")
            yield bytes(sec["end"] - sec["offset"] - size)
