"""``python -m train.evaluate`` / ``pairflock-evaluate``:
a trained policy on held-out seeds, next to the analytic controllers (:mod:`train.evaluate.cli`),
on one thread per process."""

import sys
from collections.abc import Sequence

from baselines.runtime.threads import pin_threads


def main(argv: Sequence[str] | None = None) -> int:
    """Pin the threads, then run the command; returns the exit status."""
    pin_threads()  # before numpy and torch load
    from train.evaluate.cli import main as run

    return run(argv)


if __name__ == "__main__":
    sys.exit(main())
