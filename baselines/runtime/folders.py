"""Result folders: complete and consistent, or visibly marked.

A *result folder* (a benchmark's, the quadrotor experiment's, an evaluation's ``--out``) is
always either complete and consistent, or visibly marked: :func:`result_folder` writes the
new set of files aside and swaps it in at the end, and an ``INCOMPLETE`` file marks the
folder for the moment of the swap, so a run killed at any point never leaves new results
next to an old summary unmarked. :func:`load_results` reads the rows of such folders back.
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
import shutil
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path

from baselines.runtime.files import atomic_write_text

__all__ = ["INCOMPLETE_MARKER", "load_results", "result_folder"]


def load_results(folders: Sequence[str | Path], flag: str) -> list[dict[str, str]]:
    """The ``results.csv`` rows of every folder, pooled; ``FileNotFoundError`` naming ``flag``
    (the command-line option the folders came from) and the path when a folder has none."""
    rows: list[dict[str, str]] = []
    for folder in folders:
        path = Path(folder) / "results.csv"
        if not path.is_file():
            raise FileNotFoundError(f"{flag}: {str(folder)!r} is invalid: it has no results.csv")
        with path.open(newline="") as fh:
            rows += list(csv.DictReader(fh))
    return rows


#: name of the file that marks a result folder as being rewritten (or interrupted doing so)
INCOMPLETE_MARKER = "INCOMPLETE"
_STAGE_PREFIX = ".partial-"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process
        return True
    return True


def _remove_dead_stages(out: Path) -> None:
    """Staging folders left by runs that were killed before they finished writing."""
    for stage in out.glob(f"{_STAGE_PREFIX}*"):
        pid = stage.name[len(_STAGE_PREFIX) :]
        if stage.is_dir() and not (pid.isdigit() and _alive(int(pid))):
            shutil.rmtree(stage, ignore_errors=True)


def _previous_outputs(out: Path) -> list[str]:
    """The files of the set in ``out`` now, as its ``run.json`` lists them."""
    try:
        outputs = json.loads((out / "run.json").read_text(encoding="utf-8")).get("outputs", [])
    except (OSError, ValueError, AttributeError):
        return []
    return [o for o in outputs if isinstance(o, str) and not Path(o).is_absolute()]


def _commit(stage: Path, out: Path) -> None:
    """Replace the set in ``out`` by the files in ``stage`` (``run.json`` last), under the
    ``INCOMPLETE`` marker."""
    marker = out / INCOMPLETE_MARKER
    atomic_write_text(
        marker,
        f"This folder is being rewritten by process {os.getpid()} "
        f"({' '.join([Path(sys.argv[0]).name, *sys.argv[1:]])}). If that process is not "
        "running, it was interrupted: the files here may mix two runs; run the command again.\n",
    )
    new = sorted(str(p.relative_to(stage)) for p in stage.rglob("*") if p.is_file())
    for old in _previous_outputs(out):
        if old not in new and (out / old).is_file():
            (out / old).unlink()
    for name in sorted(new, key=lambda n: n == "run.json"):
        (out / name).parent.mkdir(parents=True, exist_ok=True)
        os.replace(stage / name, out / name)
    marker.unlink()
    shutil.rmtree(stage, ignore_errors=True)


@contextlib.contextmanager
def result_folder(out: Path) -> Iterator[Path]:
    """A staging folder to write a result set to; on a clean exit it replaces ``out``'s set.

    Until the swap a reader of ``out`` sees the previous set, complete (a crash or kill before
    it leaves that set as it was, plus a hidden ``.partial-<pid>`` folder the next run
    removes); during the swap ``out/INCOMPLETE`` marks the folder. Files of the previous set
    (listed in its ``run.json`` under ``outputs``) that the new set lacks are removed; other
    files in ``out`` are left alone. Write ``run.json`` with an ``outputs`` list.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    _remove_dead_stages(out)
    stage = out / f"{_STAGE_PREFIX}{os.getpid()}"
    if stage.exists():
        shutil.rmtree(stage)
    stage.mkdir()
    try:
        yield stage
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
    _commit(stage, out)
