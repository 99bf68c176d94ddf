"""Griffe extension for the API reference: docstrings as Python shows them, with links.

* A class whose docstring is built at import time (``__doc__ = TEMPLATE.format(...)``, e.g.
  the PettingZoo env's, whose observation table is generated from the live layout) has no
  docstring for a static reader; it gets the runtime one.
* Doctest examples written as plain ``>>>`` lines (not indented, outside an ``Examples:``
  section) become ``pycon`` code blocks instead of being read as Markdown.
* The docstrings are written for ``help()`` as well as for the site, so they keep the
  ``:class:`~pairflock_env.core.PairFlockCore``` spelling. Markdown has no such roles; each
  becomes an *optional* mkdocs-autorefs cross-reference: a link when the target is rendered
  somewhere on the site, plain code otherwise (never a build warning).
"""

from __future__ import annotations

import importlib
import inspect
import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:class|mod|meth|func|attr|data|obj|exc|const):`(~?)([^`]+)`")
_ROOTS = ("pairflock_env", "baselines", "train")
_DOCTEST = re.compile(r"^>>> .*(?:\n[^\n]+)*", flags=re.M)  # a prompt line up to a blank line


def _runtime_doc(obj: griffe.Object) -> str | None:
    """The ``__doc__`` that the imported class or function really has (None if unknown)."""
    if not (obj.is_class or obj.is_function) or obj.parent is None:
        return None
    try:
        live: Any = importlib.import_module(obj.module.path)
    except ImportError:
        return None
    for name in obj.path[len(obj.module.path) + 1 :].split("."):
        live = getattr(live, name, None)
    own = vars(live).get("__doc__") if isinstance(live, type) else getattr(live, "__doc__", None)
    return inspect.cleandoc(own) if isinstance(own, str) and own.strip() else None


def _target(obj: griffe.Object, name: str) -> str:
    """Full dotted path of ``name`` as written in ``obj``'s docstring (best effort)."""
    if name.startswith("."):  # relative to the package of the object's module
        module = obj.module
        package = module.path if module.is_package else module.path.rsplit(".", 1)[0]
        return f"{package}.{name.lstrip('.')}"
    if name.split(".", 1)[0] in _ROOTS:
        return name
    head, _, rest = name.partition(".")
    try:
        resolved = obj.resolve(head)
    except (griffe.NameResolutionError, KeyError, AttributeError):
        return name
    return f"{resolved}.{rest}" if rest else resolved


def _link_roles(obj: griffe.Object, text: str) -> str:
    def link(match: re.Match[str]) -> str:
        short, name = match.group(1), match.group(2)
        title = name.rsplit(".", 1)[-1] if short else name.lstrip(".")
        return f'<autoref identifier="{_target(obj, name)}" optional><code>{title}</code></autoref>'

    def bare(match: re.Match[str]) -> str:
        short, name = match.group(1), match.group(2)
        return name.rsplit(".", 1)[-1] if short else name.lstrip(".")

    lines, in_code, previous = [], False, ""
    for line in text.split("\n"):
        # Markdown reads 4-space-indented lines after a blank line as a code block, where
        # HTML would show literally: there a role becomes its bare name.
        if not line.strip():
            pass
        elif line.startswith("    ") and (in_code or not previous.strip()):
            in_code = True
        else:
            in_code = False
        lines.append(_ROLE.sub(bare if in_code else link, line))
        previous = line
    return "\n".join(lines)


def _fence_doctests(text: str) -> str:
    return _DOCTEST.sub(lambda m: f"\n```pycon\n{m.group(0)}\n```", text)


def _fix(obj: griffe.Object) -> None:
    if obj.docstring is None:
        doc = _runtime_doc(obj)
        if doc is not None:
            obj.docstring = griffe.Docstring(doc, parent=obj)
    if obj.docstring is not None and ">>> " in obj.docstring.value:
        obj.docstring.value = _fence_doctests(obj.docstring.value)
    if obj.docstring is not None and ":`" in obj.docstring.value:
        obj.docstring.value = _link_roles(obj, obj.docstring.value)
    for member in obj.members.values():
        if not member.is_alias:
            _fix(member)


class RuntimeDocstringsAndRoles(griffe.Extension):
    """Fill import-time docstrings and turn Sphinx roles into links, once per package."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        _fix(pkg)
