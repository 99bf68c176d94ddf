"""A result folder as the experiment commands write it, for tests of the commands that read
them back (``quadrotor_compare``, ``safety_compare``)."""

from __future__ import annotations

import csv
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any


def write_results(folder: Path, rows: Sequence[Mapping[str, Any]]) -> Path:
    """A new ``folder`` with ``results.csv`` holding ``rows`` (columns of the first row)."""
    folder.mkdir(parents=True)
    with (folder / "results.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return folder
