"""MkDocs hook: a page line ``<!-- module-tree -->`` is replaced by the tree of the project's
packages, one line per module with its code-line count and the first sentence of its
docstring, read from the source (nothing is imported), so the layout page cannot go stale.

``python docs/_hooks/module_tree.py`` prints the same tree."""

from __future__ import annotations

import ast
import re
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("pairflock_env", "baselines", "train")
_MARKER = re.compile(r"^<!-- module-tree -->$", flags=re.M)
_WIDTH = 100


def _summary(tree: ast.Module) -> str:
    doc = ast.get_docstring(tree) or ""
    text = " ".join(doc.split("\n\n")[0].split()).replace("``", "")
    text = re.sub(r":\w+:`~?([\w.]+)`", lambda m: m.group(1).rsplit(".", 1)[-1], text)
    # the first sentence: a full stop or colon before a capital letter, not after "eq."/"Sec."
    m = re.search(r"(?<!\beq)(?<!\bSec)(?<!e\.g)(?<!i\.e)[.:;]\s(?=[A-Z(`*])", text)
    return (text[: m.start()] if m else text).rstrip(".:;")


def _code_lines(src: str, tree: ast.Module) -> int:
    docs: set[int] = set()
    for node in ast.walk(tree):
        value = getattr(node, "value", None)
        if (
            isinstance(node, ast.Expr)
            and isinstance(value, ast.Constant)
            and isinstance(value.value, str)
        ):
            docs.update(range(node.lineno, node.end_lineno + 1))
    return sum(
        1
        for i, line in enumerate(src.splitlines(), 1)
        if line.strip() and not line.strip().startswith("#") and i not in docs
    )


def module_tree(root: Path = ROOT) -> str:
    """The tree as text: ``path  code-lines  summary`` per module."""
    rows = []
    for pkg in PACKAGES:
        for f in sorted((root / pkg).rglob("*.py")):
            src = f.read_text()
            tree = ast.parse(src)
            rel = f.relative_to(root).as_posix()
            rows.append((rel, _code_lines(src, tree), _summary(tree)))
    width = max(len(r[0]) for r in rows) + 2
    out = []
    for rel, n, summary in rows:
        head = f"{rel:<{width}}{n:>4}  "
        room = _WIDTH - len(head)
        if len(summary) > room:
            summary = summary[: room - 3].rstrip() + "..."
        out.append(head + summary)
    return "\n".join(out)


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    """Expand the module-tree marker of a page (MkDocs event)."""
    if not _MARKER.search(markdown):
        return markdown
    block = f"```text\n{module_tree()}\n```"
    return _MARKER.sub(lambda _: block, markdown)


if __name__ == "__main__":
    print(module_tree())
