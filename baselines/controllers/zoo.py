"""Files that ship inside the package, usable by name from an installed wheel.

The committed policies live in ``baselines/models/*.zip`` (a checkout also reaches them as
``models/*.zip``), the training configs in ``train/configs/*.yaml``
(:func:`train.settings.resolve_config`). A value is first read as a path, as given and then
with the suffix added, so a local file always wins; only when no such file exists is a bare
name (no folder part) looked up among the packaged files::

    make_pair_policy("sb3:pair_n20_a50", env)             # the packaged policy, anywhere
    make_pair_policy("sb3:models/pair_n20_a50.zip", env)  # the same file, as a path
    make_pair_policy("sb3:runs/ppo/final_model.zip", env) # any model trained locally
"""

from __future__ import annotations

import atexit
import contextlib
import difflib
import os
from importlib import resources
from pathlib import Path

__all__ = ["MODEL_SUFFIX", "find_packaged", "model_names", "packaged_names", "resolve_model"]

MODEL_SUFFIX = ".zip"

# Packages installed as plain folders give real paths; anything else (a zipped install) is
# copied to a temporary file that lives until the interpreter exits.
_extracted = contextlib.ExitStack()
atexit.register(_extracted.close)


def _packaged_folder(package: str, folder: str):
    return resources.files(package).joinpath(folder)


def packaged_names(package: str, folder: str, suffix: str) -> list[str]:
    """Sorted names, without ``suffix``, of the files ``<package>/<folder>/*<suffix>``."""
    root = _packaged_folder(package, folder)
    if not root.is_dir():
        return []
    return sorted(
        p.name[: -len(suffix)] for p in root.iterdir() if p.is_file() and p.name.endswith(suffix)
    )


def find_packaged(value: str | os.PathLike, *, package: str, folder: str, suffix: str, what: str):
    """The file that ``value`` names: an existing file (``value`` or ``value + suffix``), else
    the packaged file ``<package>/<folder>/<value>[suffix]`` when ``value`` is a bare name.

    Returns a :class:`pathlib.Path`. Raises ``TypeError`` for a value that is not a string or
    path, ``ValueError`` for an empty one and ``FileNotFoundError`` (naming ``what``, the
    value and the packaged names) when neither exists.
    """
    if not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{what} {value!r} is invalid: must be a file path or a packaged name")
    text = os.fspath(value)
    if not text:
        raise ValueError(f"{what} {text!r} is invalid: give a file path or a packaged name")
    path = Path(text)
    for candidate in (path, Path(text + suffix)):
        if candidate.is_file():
            return candidate
    names = packaged_names(package, folder, suffix)
    name = text[: -len(suffix)] if text.endswith(suffix) else text
    bare = os.sep not in text and (os.altsep is None or os.altsep not in text)
    if bare and name in names:
        found = _packaged_folder(package, folder).joinpath(name + suffix)
        if isinstance(found, Path):
            return found
        return _extracted.enter_context(resources.as_file(found))
    if bare:
        hint = difflib.get_close_matches(name, names, n=1)
        why = f"no such file and no packaged {what} of that name"
        why += f" (did you mean {hint[0]!r}?)" if hint else ""
    else:
        why = "no such file"
    raise FileNotFoundError(
        f"{what} {text!r} does not exist: {why}; packaged {what}s (give the bare name): "
        f"{', '.join(names) or 'none'}"
    )


def model_names() -> list[str]:
    """Names of the packaged policies (``baselines/models/*.zip``), e.g. ``pair_n20_a50``."""
    return packaged_names("baselines", "models", MODEL_SUFFIX)


def resolve_model(value: str | os.PathLike) -> Path:
    """The model file of ``value``: a path to a zip saved by ``python -m train`` (``.zip``
    may be left out), or the name of a packaged policy (:func:`model_names`); see the module
    docstring for the order."""
    return find_packaged(
        value, package="baselines", folder="models", suffix=MODEL_SUFFIX, what="model"
    )
