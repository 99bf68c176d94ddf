"""What a recorded step holds, and the checks of the writer's arguments."""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["STEP_ARRAYS", "check_config", "check_pairs", "check_path", "check_scalar", "json_safe"]

#: the per-step arrays a recording may hold: name: (scope, per item a vector of dim (True), of
#: that many values (an int) or one value (False), dtype, unit, description). Scope "step": one
#: per step; "uav": (N,); "agent": (M,), one per pair; "safety": "agent" or "uav" by the
#: writer's ``safety_scope``. dtype "float" is the writer's
#: ``float_dtype``. ``step``, ``time``, ``positions`` and ``velocities`` are always present.
STEP_ARRAYS: dict[str, tuple[str, bool | int, str, str, str]] = {
    "step": ("step", False, "int64", "", "index of the env step (0: the reset)"),
    "time": ("step", False, "float64", "s", "simulated time"),
    "positions": ("uav", True, "float", "m", "position of each UAV"),
    "velocities": ("uav", True, "float", "m/s", "velocity of each UAV"),
    "leader_position": ("step", True, "float", "m", "virtual leader position"),
    "leader_velocity": ("step", True, "float", "m/s", "virtual leader velocity"),
    "pair_distance": ("agent", False, "float", "m", "distance between the pair's UAVs"),
    "pair_error": ("agent", False, "float", "m", "pair distance - d_m"),
    "safety_active": ("safety", False, "bool", "", "the safety filter changed the command"),
    "safety_correction": (
        "safety",
        False,
        "float",
        "m/s^2",
        "norm of the safety filter's change to the command",
    ),
    "closest_distance": (
        "uav",
        False,
        "float",
        "m",
        "distance from each UAV to its nearest neighbour, as the env measures separation",
    ),
    "setpoint": (
        "uav",
        10,
        "float",
        "",
        "the setpoint row each UAV flew during the step that ended here, for a vehicle fed "
        "setpoints (the Crazyflie's cmdFullState, CMD_FIELDS; 0 at a reset)",
    ),
}


def check_scalar(
    name: str,
    value: Any,
    kind: type,
    *,
    low: float | None = None,
    open_low: bool = False,
    choices: tuple | None = None,
) -> Any:
    """``value`` as an int or a finite float, or TypeError/ValueError naming ``name``."""
    ok = (np.integer,) if kind is int else (np.integer, np.floating, int, float)
    if isinstance(value, bool) or not isinstance(value, (int, *ok)):
        raise TypeError(f"{name}={value!r}: expected {'an int' if kind is int else 'a number'}")
    value = kind(value)
    bad = (
        (kind is float and not math.isfinite(value))
        or (low is not None and (value <= low if open_low else value < low))
        or (choices is not None and value not in choices)
    )
    if bad:
        valid = (
            f"one of {choices}"
            if choices
            else f"{'>' if open_low else '>='} {low}"
            if low is not None
            else "finite"
        )
        raise ValueError(f"{name}={value!r}: expected {valid}")
    return value


def check_pairs(pairs: Any, pair_target: Any, num_uavs: int) -> tuple[np.ndarray, np.ndarray]:
    """``pairs`` as (M, 2) int32 of distinct UAVs in [0, N), ``pair_target`` as (M,) float32."""
    p = np.zeros((0, 2), np.int32) if pairs is None else np.asarray(pairs)
    if p.size == 0:
        p = p.reshape(0, 2)
    if p.dtype.kind not in "iu" or p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"pairs of dtype {p.dtype} and shape {p.shape}: expected (M, 2) ints")
    if p.size and (p.min() < 0 or p.max() >= num_uavs or np.unique(p).size != p.size):
        raise ValueError(f"pairs {p.tolist()[:8]}...: expected distinct UAVs in [0, {num_uavs})")
    d = np.broadcast_to(np.asarray(0.0 if pair_target is None else pair_target, float), len(p))
    if pair_target is None and len(p):
        raise ValueError("pair_target=None with pairs: give d_m, a scalar or (M,) in m")
    if not np.all(np.isfinite(d)) or np.any(d < 0):
        raise ValueError(f"pair_target={pair_target!r}: expected finite distances >= 0 (m)")
    return p.astype(np.int32), d.astype(np.float32)


def check_path(path: Any) -> str:
    """``path`` as a str, if it names no file and no non-empty folder."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path={path!r}: expected a str or os.PathLike folder name")
    path = os.fspath(path)
    if os.path.isfile(path) or (os.path.isdir(path) and os.listdir(path)):
        raise FileExistsError(f"path={path!r} exists; a recording needs a new or empty folder")
    return path


def json_safe(value: Any, name: str) -> Any:
    """``value`` in JSON types: numpy scalars and arrays as numbers and lists, tuples and sets
    as lists, a non-finite float as the string "inf", "-inf" or "nan" (strict JSON has none).
    TypeError names ``name`` for anything else (keys must be str)."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    elif isinstance(value, np.generic):
        value = value.item()
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if isinstance(value, Mapping):
        if not all(isinstance(k, str) for k in value):
            raise TypeError(f"{name} has keys that are not str: {list(value)[:8]}")
        return {k: json_safe(v, f"{name}[{k!r}]") for k, v in value.items()}
    if isinstance(value, (list, tuple, set, frozenset)):
        items = sorted(value) if isinstance(value, (set, frozenset)) else value
        return [json_safe(v, f"{name}[{i}]") for i, v in enumerate(items)]
    raise TypeError(f"{name}={value!r} of type {type(value).__name__} is not JSON-representable")


def check_config(config: Mapping[str, Any] | None) -> dict[str, Any]:
    """The config as a JSON dict (a dataclass or an object with ``to_dict`` also works)."""
    if config is None:
        return {}
    if hasattr(config, "to_dict"):
        config = config.to_dict()
    elif dataclasses.is_dataclass(config) and not isinstance(config, type):
        config = dataclasses.asdict(config)
    if not isinstance(config, Mapping):
        raise TypeError(f"config={config!r}: expected a dict (or None)")
    return json_safe(dict(config), "config")
