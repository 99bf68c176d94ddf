"""``python -m train.sweep`` / ``pairflock-sweep``:
training runs over seeds and settings (:mod:`train.sweep.cli`),
on one thread per process."""

import sys
from collections.abc import Sequence

from baselines.runtime.threads import pin_threads


def main(argv: Sequence[str] | None = None) -> int:
    """Pin the threads, then run the command; returns the exit status."""
    pin_threads()  # before numpy and torch load
    from train.sweep.cli import main as run

    return run(argv)


if __name__ == "__main__":
    sys.exit(main())
