"""``python -m train.imitate`` / ``pairflock-imitate``:
clone an analytic controller into a run's policy network (:mod:`train.imitate.cli`),
on one thread per process."""

import sys
from collections.abc import Sequence

from baselines.runtime.threads import pin_threads


def main(argv: Sequence[str] | None = None) -> int:
    """Pin the threads, then run the command; returns the exit status."""
    pin_threads()  # before numpy and torch load
    from train.imitate.cli import main as run

    return run(argv)


if __name__ == "__main__":
    sys.exit(main())
