"""Setpoint streams: a recorded episode as one CSV per UAV of Crazyswarm2 ``cmdFullState``
fields at the control rate, with a manifest (docs/export.md, "Setpoint streams").

Each row k holds what a ground station sends at time t_k and the firmware holds until the
next row (one control period dt later)::

    t, x, y, z, vx, vy, vz, ax, ay, az, yaw, wx, wy, wz

in s, m, m/s, m/s^2 (world frame, z up, gravity excluded), rad and rad/s (body rates, body
frame x forward, y left, z up): :data:`COLUMNS`. Two sources:

``"recorded"``
    the recording holds ``setpoint`` (T, N, 10), the cmdFullState rows (``CMD_FIELDS`` of the
    Crazyflie model) each UAV flew during the step that ended at each recorded step (zeros at
    step 0). Row k of the stream is the row flown from t_k to t_{k+1}. Flown open loop by the
    same vehicle model from the recorded start, it reproduces the recorded Crazyflie run.
    The recorder writes it (array ``setpoint``) for a vehicle fed setpoints (the Crazyflie).
``"trajectory"`` (what every recording allows)
    the recorded state itself: position and velocity at t_k, the acceleration over the
    period (v_{k+1} - v_k) / dt (what the particle model integrated, the mean acceleration for
    any other vehicle), yaw a constant (``crazyflie_yaw`` of a Crazyflie recording, else 0 or
    ``yaw``). A Crazyflie tracks it with its own lag and thrust error (docs/export.md).

Body rates: ``"zero"`` (the default; the Crazyflie model, like drone-controllers, does not use
them) or ``"flatness"``: the rates of a vehicle whose thrust axis follows the acceleration
(differential flatness: h = (j - (z_B . j) z_B) / |a + g e3|, p = -h . y_B, q = h . x_B,
r = 0 at constant yaw; j the finite-difference jerk), for firmware that feeds them forward
(the Crazyflie firmware's Mellinger controller does). A 2-D recording needs ``altitude``.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from pairflock_env.dynamics.crazyflie.data import FIRMWARE
from pairflock_env.dynamics.crazyflie.model import CMD_FIELDS, CrazyflieModel
from pairflock_env.recording.format import Recording, open_recording

__all__ = [
    "COLUMNS",
    "FORMAT",
    "fly_stream",
    "read_setpoints",
    "setpoint_stream",
    "write_setpoints",
]

FORMAT = "pairflock-setpoints"
VERSION = 1
MANIFEST = "manifest.json"
#: (name, unit, meaning) of every CSV column, in order
COLUMNS = (
    ("t", "s", "time the row is sent (the recording's clock)"),
    *((c, "m", f"{c} position, world frame") for c in "xyz"),
    *((f"v{c}", "m/s", f"{c} velocity, world frame") for c in "xyz"),
    *((f"a{c}", "m/s^2", f"{c} acceleration, world frame, gravity excluded") for c in "xyz"),
    ("yaw", "rad", "heading, about world z"),
    *((f"w{c}", "rad/s", f"body rate about body {c}") for c in "xyz"),
)
#: what the recorder must add for the ``"recorded"`` source
_BODY_RATES = ("zero", "flatness")


def _state(rec: Recording, altitude: float | None) -> tuple[np.ndarray, np.ndarray]:
    q = np.asarray(rec["positions"], dtype=np.float64)
    p = np.asarray(rec["velocities"], dtype=np.float64)
    if rec.dim == 3:
        if altitude is not None:
            raise ValueError(f"altitude={altitude!r}: only a 2-D recording takes an altitude")
        return q, p
    if altitude is None or not math.isfinite(altitude):
        raise ValueError(f"altitude={altitude!r}: a 2-D recording needs a finite altitude (m)")
    z = np.zeros((*q.shape[:-1], 1))
    return np.concatenate([q, z + altitude], -1), np.concatenate([p, z], -1)


def _body_rates(acc: np.ndarray, jerk: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """Body rates (..., 3) of the flat outputs: thrust axis along acc + g e3, constant yaw."""
    t = acc + np.array([0.0, 0.0, FIRMWARE["gravity"]])
    thrust = np.linalg.norm(t, axis=-1, keepdims=True)
    zb = t / thrust
    xc = np.stack([np.cos(yaw), np.sin(yaw), np.zeros_like(yaw)], -1)
    yb = np.cross(zb, xc)
    yb /= np.linalg.norm(yb, axis=-1, keepdims=True)
    xb = np.cross(yb, zb)
    h = (jerk - np.sum(zb * jerk, -1, keepdims=True) * zb) / thrust
    return np.stack([-np.sum(h * yb, -1), np.sum(h * xb, -1), np.zeros_like(yaw)], -1)


def _check_rows(rec: Recording) -> int:
    if rec.every != 1:
        raise ValueError(
            f"the recording holds one step in every={rec.every}; a stream at the control rate "
            "needs every step: record with every=1"
        )
    if rec.steps < 2:
        raise ValueError(f"the recording holds {rec.steps} step(s); a stream needs 2 or more")
    return rec.steps - 1


def setpoint_stream(
    recording: str | os.PathLike | Recording,
    *,
    source: str = "auto",
    yaw: float | None = None,
    altitude: float | None = None,
    body_rates: str = "zero",
) -> tuple[np.ndarray, dict[str, Any]]:
    """The stream of ``recording``: rows (T - 1, N, 14) in :data:`COLUMNS` order, and what
    the manifest says about them. ``source``: ``"recorded"``, ``"trajectory"`` or ``"auto"``
    (the recorded setpoints when the recording holds them); ``yaw`` (rad) for the trajectory
    source; ``altitude`` (m) for a 2-D recording; ``body_rates``: ``"zero"`` or
    ``"flatness"``."""
    rec = recording if isinstance(recording, Recording) else open_recording(recording)
    if source not in ("auto", "recorded", "trajectory"):
        raise ValueError(f"source={source!r}: expected 'auto', 'recorded' or 'trajectory'")
    if body_rates not in _BODY_RATES:
        raise ValueError(f"body_rates={body_rates!r}: expected one of {_BODY_RATES}")
    n, dt = _check_rows(rec), float(rec.dt)
    if source == "auto":
        source = "recorded" if "setpoint" in rec else "trajectory"
    if source == "recorded":
        if "setpoint" not in rec:
            raise ValueError(
                "the recording has no 'setpoint' array: it holds the setpoint rows a vehicle "
                'fed setpoints flew (dynamics="crazyflie"); use source="trajectory"'
            )
        cmd = np.asarray(rec["setpoint"], dtype=np.float64)[1:]
        if cmd.shape[-1] != len(CMD_FIELDS):
            raise ValueError(f"setpoint rows hold {cmd.shape[-1]} values, not {len(CMD_FIELDS)}")
    else:
        q, p = _state(rec, altitude)
        if yaw is None:
            yaw = math.radians(rec.config.get("crazyflie_yaw", 0.0) or 0.0)
        a = (p[1:] - p[:-1]) / dt
        cmd = np.concatenate([q[:-1], p[:-1], a, np.full((*a.shape[:-1], 1), float(yaw))], -1)
    acc, heading = cmd[..., 6:9], cmd[..., 9]
    if body_rates == "flatness":
        jerk = np.zeros_like(acc)
        jerk[:-1] = (acc[1:] - acc[:-1]) / dt
        rates = _body_rates(acc, jerk, heading)
    else:
        rates = np.zeros_like(acc)
    t = np.asarray(rec["time"], dtype=np.float64)[:n]
    rows = np.concatenate([np.broadcast_to(t[:, None, None], (n, rec.num_uavs, 1)), cmd, rates], -1)
    info = {"source": source, "body_rates": body_rates, "rows": n, "dt_s": dt}
    if source == "trajectory":
        info |= {"yaw_rad": float(yaw), "altitude_m": altitude}
    return rows, info


def _uavs(rec: Recording, rows: np.ndarray, files: list[str]) -> list[dict[str, Any]]:
    role = {int(u): f"pair {m // 2}" for m, u in enumerate(np.asarray(rec.pairs).reshape(-1))}
    out = []
    for i, name in enumerate(files):
        r = rows[:, i]
        out.append({
            "uav": i,
            "file": name,
            "role": role.get(i, "flock"),
            "start_position_m": r[0, 1:4].tolist(),
            "max_speed_m_s": float(np.linalg.norm(r[:, 4:7], axis=-1).max()),
            "max_accel_m_s2": float(np.linalg.norm(r[:, 7:10], axis=-1).max()),
        })  # fmt: skip
    return out


def write_setpoints(
    recording: str | os.PathLike,
    out: str | os.PathLike,
    *,
    force: bool = False,
    **options: Any,
) -> dict[str, Any]:
    """Write ``out/uav_XXX.csv`` (one per UAV) and ``out/manifest.json`` from ``recording``
    (``options``: those of :func:`setpoint_stream`); returns the manifest. ``out`` must be
    new or empty unless ``force``."""
    rec = open_recording(recording)
    rows, info = setpoint_stream(rec, **options)
    folder = Path(out)
    if folder.is_dir() and any(folder.iterdir()) and not force:
        raise FileExistsError(f"out={str(out)!r} is not empty; pass force=True to overwrite")
    folder.mkdir(parents=True, exist_ok=True)
    width = max(3, len(str(rec.num_uavs - 1)))
    files = [f"uav_{i:0{width}d}.csv" for i in range(rec.num_uavs)]
    header = ",".join(c[0] for c in COLUMNS)
    for i, name in enumerate(files):
        np.savetxt(folder / name, rows[:, i], fmt="%.9g", delimiter=",", header=header,
                   comments="")  # fmt: skip
    keep = ("seed", "controller", "complete", "steps", "dt", "every", "num_uavs", "dim")
    manifest = {
        "format": FORMAT,
        "version": VERSION,
        "command": "Crazyswarm2 cmdFullState(pos, vel, acc, yaw, omega), one row per control "
        "period, held by the firmware until the next",
        "columns": [{"name": n, "unit": u, "meaning": m} for n, u, m in COLUMNS],
        "world_frame": "the recording's: x, y, z with z up (shift it onto the arena)",
        "rate_hz": 1.0 / info["dt_s"],
        "duration_s": info["rows"] * info["dt_s"],
        **info,
        "recording": {k: rec.manifest.get(k) for k in keep}
        | {"dynamics": rec.config.get("dynamics"), "folder": Path(rec.path).name},
        "uavs": _uavs(rec, rows, files),
    }
    (folder / MANIFEST).write_text(json.dumps(manifest, indent=1) + "\n")
    return manifest


def read_setpoints(folder: str | os.PathLike) -> tuple[dict[str, Any], np.ndarray]:
    """(manifest, rows (T, N, 14)) of a folder written by :func:`write_setpoints`."""
    folder = Path(folder)
    manifest = json.loads((folder / MANIFEST).read_text())
    if manifest.get("format") != FORMAT:
        raise ValueError(f"{str(folder)!r} is not a setpoint stream (format {FORMAT!r})")
    cols = [np.loadtxt(folder / u["file"], delimiter=",", skiprows=1, ndmin=2)
            for u in manifest["uavs"]]  # fmt: skip
    return manifest, np.stack(cols, axis=1)


def fly_stream(
    rows: np.ndarray, config: Any, start_positions: np.ndarray, start_velocities: np.ndarray
) -> np.ndarray:
    """Positions (T + 1, N, 3) of Crazyflies (``config``: ``dynamics="crazyflie"`` and its
    fields) started at rest attitude from the given states and flown open loop through
    ``rows`` (T, N, 14) of a stream, one control period (``config.dt``) per row."""
    rows = np.asarray(rows, dtype=np.float64)
    T, N = rows.shape[:2]
    if rows.shape[2:] != (len(COLUMNS),):
        raise ValueError(f"rows have shape {rows.shape}; expected (T, N, {len(COLUMNS)})")
    step = np.diff(rows[:, 0, 0])
    if step.size and not np.allclose(step, config.dt, rtol=1e-6, atol=1e-9):
        raise ValueError(f"the rows are {step.mean():g} s apart; config.dt={config.dt!r}")
    model = CrazyflieModel(config, 1)
    q = np.array(start_positions, dtype=np.float64).reshape(1, N, 3)
    p = np.array(start_velocities, dtype=np.float64).reshape(1, N, 3)
    model.reset_rows(np.array([0]), q, p)
    out = np.empty((T + 1, N, 3))
    out[0] = q[0]
    for k in range(T):
        model.fly_setpoints(q, p, rows[k, :, 1:11][None])
        out[k + 1] = q[0]
    return out
