"""Atomic result files, result folders and run records (config, seeds, versions, commit).

A *result folder* (a benchmark's, the quadrotor experiment's, an evaluation's ``--out``) is
always either complete and consistent, or visibly marked: :func:`result_folder` writes the
new set of files aside and swaps it in at the end, and an ``INCOMPLETE`` file marks the
folder for the moment of the swap, so a run killed at any point never leaves new results
next to an old summary unmarked.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterable, Iterator, Mapping, Sequence
from importlib import metadata
from pathlib import Path
from typing import Any

__all__ = [
    "INCOMPLETE_MARKER",
    "atomic_path",
    "atomic_write_bytes",
    "atomic_write_text",
    "dumps_stable",
    "format_value",
    "json_rows",
    "load_results",
    "result_folder",
    "run_record",
    "write_csv",
    "write_json",
]

_PACKAGES = (
    "pairflock-env",
    "numpy",
    "numba",
    "gymnasium",
    "pettingzoo",
    "stable-baselines3",
    "torch",
    "matplotlib",
    "ray",
)


@contextlib.contextmanager
def atomic_path(path: Path) -> Iterator[Path]:
    """A temporary path next to ``path`` (same folder, same suffix) to write to; on a clean
    exit it is renamed onto ``path`` with the usual permissions, on an error it is removed, so
    a reader never sees a half-written file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
    os.close(fd)
    try:
        yield Path(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write_bytes(path: Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_path`), synced to disk."""
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    return Path(path)


def atomic_write_text(path: Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def format_value(v: Any) -> Any:
    """Deterministic text for CSV cells: floats with 6 significant digits, NaN as 'nan'."""
    if isinstance(v, bool):
        return int(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        return f"{v:.6g}"
    return v


def write_csv(
    path: Path, rows: Sequence[Mapping[str, Any]], columns: Iterable[str] | None = None
) -> Path:
    """``rows`` as CSV (cells by :func:`format_value`), atomically; ``columns`` default to
    the keys of the first row."""
    columns = list(columns) if columns is not None else list(rows[0]) if rows else []
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: format_value(r.get(k)) for k in columns})
    return atomic_write_text(path, buf.getvalue())


def load_results(folders: Sequence[str | Path], flag: str) -> list[dict[str, str]]:
    """The ``results.csv`` rows of every folder, pooled; ``SystemExit`` naming ``flag`` (the
    command-line option the folders came from) and the path when a folder has none."""
    rows: list[dict[str, str]] = []
    for folder in folders:
        path = Path(folder) / "results.csv"
        if not path.is_file():
            raise SystemExit(f"{flag}: {str(folder)!r} is invalid: it has no results.csv")
        with path.open(newline="") as fh:
            rows += list(csv.DictReader(fh))
    return rows


def _json_default(o: Any) -> Any:
    try:
        import numpy as np

        if isinstance(o, np.generic):
            return o.item()
        if isinstance(o, np.ndarray):
            return o.tolist()
    except ImportError:  # pragma: no cover
        pass
    if isinstance(o, (set, tuple)):
        return list(o)
    return str(o)


def write_json(path: Path, obj: Any) -> Path:
    """``obj`` as indented JSON (sorted keys; numpy values as numbers), atomically."""
    text = json.dumps(obj, indent=2, sort_keys=True, default=_json_default, allow_nan=True)
    return atomic_write_text(path, text + "\n")


def json_rows(rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Rows for JSON: NaN (a time never reached) becomes null."""
    return [
        {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in r.items()}
        for r in rows
    ]


def dumps_stable(obj: Any) -> str:
    """JSON text that is byte-identical for equal content (sorted keys, fixed layout)."""
    return json.dumps(obj, indent=1, sort_keys=True, default=_json_default, allow_nan=False) + "\n"


def _git_commit() -> str | None:
    here = Path(__file__).resolve().parent
    try:
        out = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, timeout=5
        )
        if out.returncode != 0:
            return None
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=here,
            capture_output=True,
            text=True,
            timeout=5,
        )
        return out.stdout.strip() + ("-dirty" if dirty.stdout.strip() else "")
    except (OSError, subprocess.SubprocessError):
        return None


def run_record(**extra: Any) -> dict[str, Any]:
    """What produced a result: package versions, Python, platform, git commit, command."""
    versions = {}
    for name in _PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return {
        "command": [Path(sys.argv[0]).name, *sys.argv[1:]],
        "python": platform.python_version(),
        "platform": platform.platform(),
        "git_commit": _git_commit(),
        "versions": versions,
        **extra,
    }


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
