"""``python -m baselines.reproduce`` / ``pairflock-reproduce``:
the paper's Sec. VI-A, the benchmark's paper suite
(:mod:`baselines.experiments.benchmark.reproduce`), on one thread per process."""

import sys
from collections.abc import Sequence

from baselines.runtime.threads import pin_threads


def main(argv: Sequence[str] | None = None) -> int:
    """Pin the threads, then run the command; returns the exit status."""
    pin_threads()  # before numpy loads
    from baselines.experiments.benchmark.reproduce import main as run

    return run(argv)


if __name__ == "__main__":
    sys.exit(main())
