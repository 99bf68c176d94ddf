"""Old module paths of :mod:`baselines`, from before its split into layers, kept working.

``import baselines.rollout`` (or ``from baselines.report import stat_cell``) still works: the
import gives a small alias module that warns once (DeprecationWarning) and forwards every
attribute to the modules the code moved to. The command-line modules
(``python -m baselines.benchmark`` etc.) are not aliases but real launchers, since their
paths are the documented commands.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import types
import warnings
from typing import Any

#: old module -> the module(s) its names live in now (looked up in this order)
MOVED: dict[str, tuple[str, ...]] = {
    "baselines.policies": ("baselines.controllers.base", "baselines.controllers.registry"),
    "baselines.sliding_mode": ("baselines.controllers.sliding_mode",),
    "baselines.proportional": ("baselines.controllers.proportional",),
    "baselines.sb3_policy": ("baselines.controllers.sb3",),
    "baselines.rollout": ("baselines.evaluation.rollout",),
    "baselines.sweep": ("baselines.evaluation.jobs", "baselines.evaluation.parallel"),
    "baselines.specs": ("baselines.evaluation.specs",),
    "baselines.io": ("baselines.evaluation.io",),
    "baselines.report": (
        "baselines.reporting.tables",
        "baselines.reporting.criteria",
        "baselines.reporting.benchmark_figures",
        "baselines.evaluation.io",
    ),
    "baselines.figures": ("baselines.reporting.figures",),
    "baselines.quadrotor_figures": ("baselines.reporting.quadrotor_figures",),
    "baselines.video": ("baselines.reporting.video",),
}


class _AliasLoader(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds the old names of :data:`MOVED` and makes forwarding modules for them."""

    def find_spec(self, fullname: str, path: Any = None, target: Any = None):
        if fullname not in MOVED:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec):
        return None  # a plain module

    def exec_module(self, module: types.ModuleType) -> None:
        new = MOVED[module.__name__]
        warnings.warn(
            f"{module.__name__} is deprecated; import from {' or '.join(new)} instead",
            DeprecationWarning,
            stacklevel=2,  # the importing line (warnings skips importlib's own frames)
        )
        targets = [importlib.import_module(n) for n in new]

        def __getattr__(name: str) -> Any:
            for t in targets:
                if hasattr(t, name):
                    return getattr(t, name)
            raise AttributeError(f"module {module.__name__!r} has no attribute {name!r}")

        module.__doc__ = f"Deprecated alias of {', '.join(new)}."
        module.__getattr__ = __getattr__  # type: ignore[attr-defined]
        module.__all__ = sorted({n for t in targets for n in getattr(t, "__all__", ())})


def install_aliases() -> None:
    """Put the alias finder first on ``sys.meta_path`` (once per process)."""
    if not any(isinstance(f, _AliasLoader) for f in sys.meta_path):
        sys.meta_path.insert(0, _AliasLoader())
