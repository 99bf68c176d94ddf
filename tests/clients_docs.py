"""The runnable examples of docs/clients.md, by section (shared by the client tests)."""

from __future__ import annotations

import re
from pathlib import Path

CLIENTS_MD = Path(__file__).resolve().parents[1] / "docs" / "clients.md"


def examples(section: str) -> list[str]:
    """The python blocks under the ``## <section>`` heading of docs/clients.md."""
    text = CLIENTS_MD.read_text()
    parts = re.split(r"^## ", text, flags=re.M)
    for part in parts[1:]:
        title, _, body = part.partition("\n")
        if title.strip() == section:
            return re.findall(r"```python\n(.*?)```", body, flags=re.S)
    raise KeyError(f"docs/clients.md has no section {section!r}")


def run_example(section: str, index: int = 0) -> dict:
    """Execute one example; returns its namespace."""
    ns: dict = {"__name__": "clients_example"}
    code = examples(section)[index]
    exec(compile(code, f"docs/clients.md ({section} #{index})", "exec"), ns)
    return ns
