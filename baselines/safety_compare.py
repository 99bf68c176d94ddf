"""``python -m baselines.safety_compare`` / ``pairflock-safety-compare``:
a controller with the safety filter off and on, run by run
(:mod:`baselines.experiments.safety.compare`), on one thread per process."""

import sys
from collections.abc import Sequence

from baselines.runtime.threads import pin_threads


def main(argv: Sequence[str] | None = None) -> int:
    """Pin the threads, then run the command; returns the exit status."""
    pin_threads()  # before numpy loads
    from baselines.experiments.safety.compare import main as run

    return run(argv)


if __name__ == "__main__":
    sys.exit(main())
