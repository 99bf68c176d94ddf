"""MkDocs hook: a page line ``<!-- cli-help: package.module:build_parser -->`` is replaced by
the ``--help`` text of that argparse parser, so the command-line reference cannot go stale."""

from __future__ import annotations

import importlib
import os
import re
from typing import Any

_MARKER = re.compile(r"^<!-- cli-help: ([\w.]+):(\w+) -->$", flags=re.M)
_WIDTH = "100"  # argparse wraps at $COLUMNS; fixed so that the page does not depend on a terminal


def _help(match: re.Match[str]) -> str:
    module, factory = match.group(1), match.group(2)
    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = _WIDTH
    try:
        text = getattr(importlib.import_module(module), factory)().format_help()
    finally:
        if previous is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = previous
    return f"```text\n{text.rstrip()}\n```"


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    """Expand every cli-help marker of a page (MkDocs event)."""
    return _MARKER.sub(_help, markdown)
