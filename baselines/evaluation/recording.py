"""Recordings of the command lines' runs (``--record``), for the browser replay.

The benchmark, the evaluation and the quadrotor experiment take the options of
:func:`add_record_options`; with ``--record`` every run (one episode of one seed) is written
to ``<out>/recordings/<run>/seed<k>.pfrec``, where ``<run>`` names the combination the
command varies (the benchmark: ``<scenario>_<policy>``; the evaluation:
``n<N>_<init>_<policy>``; the quadrotor experiment: ``<vehicle>_<policy>``).
``pairflock-replay FILE -o replay.html`` turns one into a page (docs/replay.md).

Each job records its own seeds as it runs them: :func:`recorded_rollout` passes a
:class:`~pairflock_env.recording.CoreRecorder` (named ``seed{seed}``, sharing the run's folder
with the jobs of the other seed blocks) as the rollout's per-step callback, so a worker
process writes its runs' recordings itself and nothing of them crosses processes. A job
first removes the recordings of the seeds it is about to run, so a command run again into
the same ``--out`` replaces them (an interrupted run's incomplete ones included) and leaves
the recordings of other runs and seeds alone.

The recordings are written while the runs go, not through the result folder's swap
(:mod:`baselines.runtime.folders`): each says itself whether it is complete, and the
command's ``run.json`` lists the ones it wrote under ``recordings``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import shutil
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

from baselines.evaluation.rollout import Trace, rollout
from baselines.evaluation.specs import slug
from baselines.runtime.cli import at_least
from pairflock_env.recording import CoreRecorder

__all__ = [
    "FOLDER",
    "RecordOptions",
    "add_record_options",
    "check_run_names",
    "record_options",
    "recorded_rollout",
    "report_line",
    "run_name",
    "written",
]

#: the folder of the recordings inside a command's ``--out``
FOLDER = "recordings"
#: the file name of a run's recording (``.pfrec`` appended), one per seed
NAME = "seed{seed}"


def add_record_options(parser: argparse.ArgumentParser) -> None:
    """``--record``, ``--record-every`` and ``--record-seeds``, in a group of their own (the
    latter two absent from the namespace unless given, which :func:`record_options` reads)."""
    g = parser.add_argument_group("recording (replay one in a browser: pairflock-replay FILE)")
    g.add_argument(
        "--record",
        action="store_true",
        help=f"write one recording per run (episode) to <out>/{FOLDER}/<run>/seed<k>.pfrec",
    )
    g.add_argument(
        "--record-every",
        type=at_least(1),
        default=argparse.SUPPRESS,
        metavar="K",
        help="with --record: record one control step in K, the last always (default 1)",
    )
    g.add_argument(
        "--record-seeds",
        type=int,
        nargs="+",
        default=argparse.SUPPRESS,
        metavar="SEED",
        help="with --record: record only these of the seeds run (default: all)",
    )


@dataclasses.dataclass(frozen=True)
class RecordOptions:
    """What to record: every ``every``-th control step of ``seeds`` (None: all) into
    ``folder``; :meth:`run` gives one run's options (its folder, controller and metadata)."""

    folder: str
    every: int = 1
    seeds: tuple[int, ...] | None = None
    controller: str | None = None
    metadata: tuple[tuple[str, Any], ...] = ()

    def run(self, name: str, controller: str, **metadata: Any) -> RecordOptions:
        """The options of the run ``name`` (a folder name, see :func:`run_name`)."""
        return dataclasses.replace(
            self,
            folder=os.path.join(self.folder, name),
            controller=controller,
            metadata=tuple(sorted({"run": name, **metadata}.items())),
        )

    def recorded(self, seeds: Iterable[int]) -> list[int]:
        """The seeds of ``seeds`` that are recorded."""
        return [int(s) for s in seeds if self.seeds is None or int(s) in self.seeds]

    def paths(self, seeds: Iterable[int]) -> list[str]:
        """The recordings of ``seeds`` (the recorded ones) in this run's folder."""
        return [
            os.path.join(self.folder, f"{NAME.format(seed=s)}.pfrec") for s in self.recorded(seeds)
        ]

    def recorder(self, seeds: Sequence[int]) -> CoreRecorder | None:
        """A rollout callback recording this run's swarms (one per seed of ``seeds``), after
        removing their previous recordings; None when none of them is recorded."""
        seeds = [int(s) for s in seeds]
        chosen = set(self.recorded(seeds))
        if not chosen:
            return None
        for path in self.paths(seeds):
            if os.path.isdir(path):
                shutil.rmtree(path)
        return CoreRecorder(
            self.folder,
            controller=self.controller,
            every=self.every,
            swarms=[b for b, s in enumerate(seeds) if s in chosen],
            name=NAME,
            seeds=seeds,
            metadata=dict(self.metadata),
            allow_existing=True,  # the run's other seed blocks, other jobs
        )


def record_options(
    args: argparse.Namespace, out: Path, seeds: Sequence[int]
) -> RecordOptions | None:
    """The recording options of a command that runs ``seeds`` into ``out`` (None without
    ``--record``); ``ValueError`` naming the option when one is bad."""
    every, chosen = getattr(args, "record_every", None), getattr(args, "record_seeds", None)
    if not args.record:
        for flag, given in (("--record-every", every), ("--record-seeds", chosen)):
            if given is not None:
                raise ValueError(f"{flag} is invalid without --record: add --record")
        return None
    if chosen is not None:
        valid = f"{seeds[0]}" if len(seeds) == 1 else f"{seeds[0]}-{seeds[-1]}"
        for s in chosen:
            if s not in seeds:
                raise ValueError(
                    f"--record-seeds {s} is invalid: must be one of the seeds run ({valid})"
                )
        chosen = tuple(sorted(set(chosen)))
    return RecordOptions(str(Path(out) / FOLDER), every or 1, chosen)


def run_name(*labels: Any) -> str:
    """The folder name of a run: its labels as file-name-safe text, joined by ``_``."""
    return "_".join(slug(str(label)) for label in labels)


def check_run_names(runs: Iterable[RecordOptions]) -> None:
    """``ValueError`` naming ``--record`` when two runs would share a folder (labels that
    differ only in characters a file name drops)."""
    seen: set[str] = set()
    for run in runs:
        if run.folder in seen:
            raise ValueError(
                f"--record is invalid here: two runs would share the folder {run.folder}; "
                "give them labels that differ in letters or digits"
            )
        seen.add(run.folder)


def written(runs: Iterable[RecordOptions | None], seeds: Sequence[int], out: Path) -> list[str]:
    """The recordings of ``runs`` (each over ``seeds``; None: a run not recorded), as paths
    relative to ``out``: the ``recordings`` list of a command's ``run.json``."""
    return [os.path.relpath(p, out) for r in runs if r is not None for p in r.paths(seeds)]


def report_line(paths: Sequence[str], out: Path) -> str:
    """What a command prints after writing the recordings ``paths`` (relative to ``out``)."""
    first = Path(out) / paths[0]
    return (
        f"wrote {len(paths)} recordings in {Path(out) / FOLDER}; replay one: "
        f"pairflock-replay {first} -o replay.html"
    )


def _chain(first: Callable[..., None] | None, recorder: CoreRecorder) -> Callable[..., None]:
    if first is None:
        return recorder

    def on_step(k: int, core: Any, res: Any, live: Any) -> None:
        first(k, core, res, live)
        recorder(k, core, res, live)

    return on_step


def recorded_rollout(
    record: RecordOptions | None,
    config: Any,
    policy: Any,
    seeds: Sequence[int],
    *,
    on_step: Callable[..., None] | None = None,
    **kwargs: Any,
) -> Trace:
    """:func:`~baselines.evaluation.rollout.rollout`, writing the recordings of the run
    ``record`` (None: none) as it goes; ``on_step`` and ``kwargs`` are the rollout's."""
    recorder = None if record is None else record.recorder(seeds)
    if recorder is None:
        return rollout(config, policy, seeds, on_step=on_step, **kwargs)
    with recorder:
        return rollout(config, policy, seeds, on_step=_chain(on_step, recorder), **kwargs)
