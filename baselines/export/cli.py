"""``pairflock-export sb3:<model> --out DIR`` (also ``python -m baselines.export``).

Writes the export folder (``policy.onnx``, ``pairflock_policy.h``, ``pairflock_policy.c``,
``contract.json``; docs/export.md). ``--check N`` then rolls the policy in its own task for
N observations and compares onnxruntime and the compiled C with stable-baselines3 on them
(exit status 1 beyond 1e-5). Bad input (an unknown model, a policy that is not a trained one,
a model of another algorithm, an existing folder without ``--force``, a missing extra) ends
with one line on stderr, ``pairflock-export: error: ...``, and exit status 2.

The exporter itself (:mod:`baselines.export.build`: stable-baselines3, torch, onnx) loads
through :func:`baselines.runtime.optional.load` when the command runs, so that a missing extra
is reported on that one line too; the errors take the project's one command-line error path
(:mod:`baselines.runtime.cli`).
"""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Sequence
from typing import Any

from baselines.runtime import optional
from baselines.runtime.cli import ArgumentParser, user_errors

__all__ = ["PROG", "build_parser", "main"]

PROG = "pairflock-export"


def build_parser() -> argparse.ArgumentParser:
    p = ArgumentParser(
        prog=PROG,
        description="Export a trained pair policy for a flight controller: policy.onnx (the "
        "network), pairflock_policy.h/.c (observation -> action in C99, float32, no heap) and "
        "contract.json (fields, units, frames, timing; docs/export.md).",
    )
    p.add_argument("policy", help="sb3:<model file or packaged name>, e.g. sb3:pair_n20_a50")
    p.add_argument("--out", required=True, help="the export folder (new or empty)")
    p.add_argument("--force", action="store_true", help="replace the export files in --out")
    p.add_argument("--no-onnx", action="store_true", help="write the C and the contract only")
    p.add_argument("--check", type=int, default=0, metavar="N",
                   help="then compare ONNX and C with SB3 on N observations the policy meets "
                   "in its own task (needs onnxruntime and a C compiler)")  # fmt: skip
    p.add_argument("--cc", default=None, help="C compiler for --check (default: $CC or cc)")
    return p


def _exporter() -> Any:
    """:mod:`baselines.export.build`, or ``ModuleNotFoundError`` naming the extra to install."""
    for package in ("stable_baselines3", "torch", "onnx"):
        optional.load(package, PROG)
    return importlib.import_module("baselines.export.build")


def _run(args: argparse.Namespace) -> int:
    if args.check < 0:
        raise ValueError(f"--check {args.check} is invalid: must be >= 0 observations")
    build = _exporter()
    loaded = build.load_policy(args.policy)
    doc = build.write_export(loaded, args.out, force=args.force, with_onnx=not args.no_onnx)
    net = doc["network"]
    print(
        f"{args.out}: {', '.join(doc['files'])}, {build.CONTRACT} ({loaded.name}: "
        f"{doc['observation']['size']} observation floats -> {net['layers'][0]['inputs']} "
        f"features -> {net['parameters']} parameters -> {doc['action']['size']} action floats)"
    )
    if not args.check:
        return 0
    report = build.check_export(loaded, args.out, args.check, args.cc)
    for key, value in report.items():
        print(f"  {key}: {value:.3g}" if isinstance(value, float) else f"  {key}: {value}")
    return 0 if report["passed"] else 1


def main(argv: Sequence[str] | None = None) -> int:
    """The command line; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    with user_errors(parser, ModuleNotFoundError):
        return _run(args)
    return 2  # pragma: no cover (user_errors exits)
