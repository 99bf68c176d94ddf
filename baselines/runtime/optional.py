"""The optional dependencies, imported on first use: the one place that knows which extra of
``pairflock-env`` provides each, so that a missing one says how to install it.

Every other module imports at its top; a module that needs an optional package asks here
when it needs it::

    ray = optional.load("ray")                       # ModuleNotFoundError: ... [ray]
    save_util = optional.load("stable_baselines3.common.save_util")
"""

from __future__ import annotations

import importlib
from types import ModuleType

__all__ = ["EXTRAS", "load"]

#: top-level package -> the extra of pairflock-env that installs it
EXTRAS = {
    "stable_baselines3": "train",
    "torch": "train",
    "yaml": "train",
    "ray": "ray",
    "imageio": "video",
    "imageio_ffmpeg": "video",
    "rliable": "sweep",
    "scipy": "sweep",
    "optuna": "sweep",
    "onnx": "export",
    "onnxruntime": "export",
}


def load(name: str, purpose: str = "") -> ModuleType:
    """The module ``name`` (a package of :data:`EXTRAS` or one of its submodules).

    A missing package raises ``ModuleNotFoundError`` naming it, what needed it (``purpose``,
    e.g. ``"--backend ray"``) and the install command; an error inside the package itself
    propagates unchanged.
    """
    top = name.partition(".")[0]
    if top not in EXTRAS:
        raise ValueError(f"name={name!r} is invalid: not an optional dependency ({sorted(EXTRAS)})")
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as e:
        if (e.name or "").partition(".")[0] != top:
            raise
        what = f"{purpose} needs" if purpose else "this needs"
        raise ModuleNotFoundError(
            f"{what} {top}: pip install 'pairflock-env[{EXTRAS[top]}]'", name=e.name
        ) from None
