"""Build the self-contained replay page of a recording: one HTML file, every script inside.

The page holds the viewer (``assets/``: HTML, CSS and the JavaScript, all this project's own
code under its MIT licence; no third-party script), a JSON header (``#pf-meta``) and the
payload of :mod:`.encode`, deflated and base64-encoded (``#pf-data``). The browser inflates it
with its built-in ``DecompressionStream``, so the page needs no network and no library.
"""

from __future__ import annotations

import base64
import html
import json
import math
import os
import zlib
from collections.abc import Iterator
from importlib import resources
from typing import Any

import numpy as np

from pairflock_env.recording import Recording, open_recording
from pairflock_env.replay.encode import BLOCK, Payload, plan_steps

__all__ = ["DEFAULT_MAX_MB", "build_replay", "closest_pass"]

DEFAULT_MAX_MB = 200  # decoded payload the page is allowed to hold (the browser's memory)
PAYLOAD_VERSION = 1
_SCRIPTS = ("math.js", "data.js", "render.js", "controls.js", "viewer.js", "ui.js")
_LICENCE = (
    "pairflock_env replay viewer. Copyright (c) pairflock_env developers. MIT licence: "
    "permission is granted, free of charge, to use, copy, modify, merge, publish and "
    "distribute this software, provided this notice is kept; it is provided as is, "
    "without warranty of any kind. No third-party code."
)


def _asset(name: str) -> str:
    return (resources.files(__package__) / "assets" / name).read_text(encoding="utf-8")


def closest_pass(rec: Recording) -> tuple[np.ndarray, dict[str, Any] | None]:
    """Each recorded step's smallest ``closest_distance`` (T,) and the run's closest pass:
    its recorded step, UAV, the UAV it passed (the one at that distance) and the distance.
    (NaN, None) without ``closest_distance``."""
    if "closest_distance" not in rec:
        return np.full(rec.steps, np.nan), None
    per_step = np.full(rec.steps, np.inf)
    who = np.zeros(rec.steps, dtype=np.int64)
    for t0 in range(0, rec.steps, BLOCK):
        block = rec.rows("closest_distance", slice(t0, t0 + BLOCK), np.float64)
        block = np.where(np.isfinite(block), block, np.inf)
        who[t0 : t0 + len(block)] = block.argmin(axis=1)
        per_step[t0 : t0 + len(block)] = block.min(axis=1)
    if not np.isfinite(per_step).any():
        return per_step, None
    t = int(per_step.argmin())
    i, dist = int(who[t]), float(per_step[t])
    q = rec.rows("positions", t, np.float64)
    gap = np.abs(np.linalg.norm(q - q[i], axis=1) - dist)  # the UAV at that distance from i
    gap[i] = np.inf
    j = int(np.nan_to_num(gap, nan=np.inf).argmin())
    return per_step, {"recorded_step": t, "uav": i, "other": j, "distance": dist}


def _finite_list(values: np.ndarray, digits: int = 6) -> list[float | None]:
    return [float(f"{v:.{digits}g}") if math.isfinite(v) else None for v in values.tolist()]


def _header(rec: Recording, payload: Payload, stride: int, per_step: np.ndarray, closest):
    idx = payload.idx
    if closest is not None:
        closest = dict(closest, index=int(np.searchsorted(idx, closest["recorded_step"])))
        closest["time"] = float(rec.rows("time", closest["recorded_step"]))
    infos = {k: _finite_list(np.asarray(v[idx], np.float64)) for k, v in rec.infos.items()}
    return {
        "payload_version": PAYLOAD_VERSION,
        "title": os.path.basename(os.path.normpath(rec.path)),
        "num_uavs": rec.num_uavs,
        "dim": rec.dim,
        "num_pairs": rec.num_pairs,
        "dt": rec.dt,
        "every": rec.every,
        "stride": stride,
        "recorded_steps": rec.steps,
        "steps": len(idx),
        "complete": rec.complete,
        "stopped": rec.manifest.get("stopped"),
        "controller": rec.manifest.get("controller"),
        "seed": rec.manifest.get("seed"),
        "config": rec.manifest.get("config", {}),
        "safety_scope": rec.safety_scope if "safety" in _names(payload) else None,
        "safety_max": payload.safety_max,
        "offset": payload.offset.tolist(),
        "min_separation": _finite_list(per_step[idx]),
        "closest_pass": closest,
        "infos": infos,
        "sections": payload.sections,
    }


def _names(payload: Payload) -> set[str]:
    return {s["name"] for s in payload.sections}


def _base64_deflated(chunks: Iterator[bytes], level: int) -> Iterator[tuple[str, int]]:
    """base64 text of the zlib stream of ``chunks``, piece by piece, with the raw size."""
    z = zlib.compressobj(level)
    carry = b""
    for raw in chunks:
        carry += z.compress(raw)
        cut = len(carry) // 3 * 3
        if cut:
            yield base64.b64encode(carry[:cut]).decode("ascii"), len(raw)
            carry = carry[cut:]
        else:
            yield "", len(raw)
    yield base64.b64encode(carry + z.flush()).decode("ascii"), 0


def _json_script(value: Any) -> str:
    return json.dumps(value, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")


def build_replay(
    recording: str | os.PathLike | Recording,
    output: str | os.PathLike,
    *,
    stride: int | None = None,
    max_mb: float = DEFAULT_MAX_MB,
    title: str | None = None,
    level: int = 6,
) -> dict[str, Any]:
    """Write the replay page of ``recording`` to ``output``; return what was written.

    Args:
        stride: replay one recorded step in ``stride`` (default: the smallest that keeps the
            decoded payload under ``max_mb`` MB); the last step and the closest pass are kept.
        title: the page title (default: the recording folder's name).
        level: zlib compression level, 0..9.

    Returns:
        dict of ``path``, ``bytes`` (the page), ``payload_bytes`` (before deflate),
        ``steps`` (replayed), ``stride``, ``bytes_per_uav_step`` (page bytes / (N x steps)).
    """
    rec = recording if isinstance(recording, Recording) else open_recording(recording)
    if stride is not None and (isinstance(stride, bool) or not isinstance(stride, int)):
        raise TypeError(f"stride={stride!r}: expected an int >= 1 or None")
    if (stride is not None and stride < 1) or not (max_mb > 0):
        raise ValueError(f"stride={stride!r}, max_mb={max_mb!r}: expected stride >= 1, max_mb > 0")
    per_step, closest = closest_pass(rec)
    keep = () if closest is None else (closest["recorded_step"],)
    idx, stride = plan_steps(rec, stride, int(max_mb * 1e6), keep)
    payload = Payload(rec, idx)
    header = _header(rec, payload, stride, per_step, closest)
    if title is not None:
        header["title"] = str(title)
    page = _asset("viewer.html").replace("{{TITLE}}", html.escape(header["title"]))
    head, rest = page.split("{{DATA}}")
    script = "\n".join(_asset(name) for name in _SCRIPTS)
    head = head.replace("{{STYLE}}", _asset("viewer.css")).replace("{{META}}", _json_script(header))
    rest = rest.replace("{{LICENCE}}", _LICENCE).replace("{{SCRIPT}}", script)
    raw = 0
    with open(output, "w", encoding="utf-8", newline="\n") as f:
        f.write(head)
        for text, n in _base64_deflated(payload.chunks(), level):
            f.write(text)
            raw += n
        f.write(rest)
    size = os.path.getsize(output)
    return {
        "path": os.fspath(output),
        "bytes": size,
        "payload_bytes": raw,
        "steps": len(idx),
        "stride": stride,
        "bytes_per_uav_step": size / (rec.num_uavs * len(idx)),
    }
