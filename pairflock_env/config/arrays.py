"""The one check of the arrays users hand to the env: actions, reset positions and velocities.

What counts as a real array (every view, every form, actions and reset states alike):

* real numbers of any numeric dtype (float, int, uint, including ``float16`` and
  ``longdouble``), Python numbers (int of any size, float, ``fractions.Fraction``), or lists of
  these; bool, complex, strings and other objects are a ``TypeError``;
* NaN and inf are a ``ValueError``;
* finite values are accepted whatever their size: a value beyond the float64 range (a huge
  Python int, a ``longdouble`` such as ``1e400``) is saturated to +-``float64`` max, and the
  core then clips every component to [-1, 1] like any other out-of-range value (reported as
  ``action_clipped``);
* a numpy masked array is read through its data when nothing is masked; a masked entry is a
  missing value, so any masked entry is a ``ValueError`` naming the entries (like NaN).
"""

from __future__ import annotations

import math
import numbers
from typing import Any

import numpy as np

__all__ = ["real_array"]

_F64_MAX = float(np.finfo(np.float64).max)


def real_array(x: Any, name: str, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """``x`` as a float64 array: the one check behind every view's actions.

    Args:
        x: array-like of real numbers (see the module docstring for what is accepted).
        name: how error messages name ``x`` (e.g. ``"action of uav_0"``).
        shape: when given, the exact shape ``x`` must have; then non-finite values are
            rejected too (without it the caller checks finiteness with its own message).

    Returns:
        A float64 ndarray (``x`` itself when it already is one). Finite values beyond the
        float64 range are saturated to +-``float64`` max; NaN and inf are kept as they are.

    Raises:
        TypeError: ``x`` is not made of real numbers (bool, complex, str, objects).
        ValueError: ``x`` has masked entries, another shape than ``shape``, or (with
            ``shape``) a NaN or inf.
    """
    if not (type(x) is np.ndarray and x.dtype.kind in "fiu" and x.dtype.itemsize <= 8):
        x = _to_float64(x, name)
    if shape is not None:
        if x.shape != shape:
            raise ValueError(f"{name} has shape {x.shape}, expected {shape}")
        if not np.isfinite(x).all():
            bad = np.argwhere(~np.isfinite(x))[0].tolist()
            raise ValueError(
                f"{name} contains NaN or inf (first at index {bad}); it must be finite"
            )
    return x.astype(np.float64, copy=False)


def _to_float64(x: Any, name: str) -> np.ndarray:
    """Any accepted form of ``x`` as a float64 (or narrower real) plain ndarray."""
    if isinstance(x, np.ma.MaskedArray):
        masked = np.ma.getmaskarray(x)
        if masked.any():
            where = np.argwhere(masked)
            first = [idx.tolist() for idx in where[:5]]
            more = f" and {len(where) - 5} more" if len(where) > 5 else ""
            raise ValueError(
                f"{name} is a masked array with masked entries at {first}{more}; masked "
                "values are missing values: give every entry a value"
            )
        x = x.data
    try:
        x = np.asarray(x)
    except (TypeError, ValueError, OverflowError):
        raise TypeError(f"{name} must be a numeric array, got {type(x).__name__}") from None
    kind = x.dtype.kind
    if kind == "O":
        return _objects_to_float64(x, name)
    if kind not in "fiu":
        raise TypeError(f"{name} has dtype {x.dtype}; expected a real (float or int) dtype")
    if x.dtype.itemsize > 8 and kind == "f":  # longdouble: finite values may exceed float64
        finite = np.isfinite(x)
        x = np.where(finite, np.clip(x, -_F64_MAX, _F64_MAX), x)
    return x


def _objects_to_float64(x: np.ndarray, name: str) -> np.ndarray:
    """An object array of Python/numpy real numbers (e.g. ints too large for int64)."""
    out = np.empty(x.shape, np.float64)
    flat = out.reshape(-1)
    for k, v in enumerate(x.reshape(-1)):
        if isinstance(v, bool) or not isinstance(v, numbers.Real):
            raise TypeError(
                f"{name} holds {v!r} ({type(v).__name__}); expected real numbers (float or int)"
            )
        flat[k] = _saturating_float(v)
    return out


def _saturating_float(v: numbers.Real) -> float:
    """``float(v)``, with finite values beyond the float64 range saturated to +-max."""
    try:
        f = float(v)
    except OverflowError:  # only finite values (ints, fractions) overflow a conversion
        return _F64_MAX if v > 0 else -_F64_MAX
    if math.isinf(f) and abs(v) != math.inf:
        return math.copysign(_F64_MAX, f)
    return f
