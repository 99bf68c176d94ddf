"""``python -m baselines.quadrotor_experiment`` / ``pairflock-quadrotor``:
the Sec. VI-B quadrotor experiment
(:mod:`baselines.experiments.quadrotor.experiment`), on one thread per process."""

import sys
from collections.abc import Sequence

from baselines.runtime.threads import pin_threads


def main(argv: Sequence[str] | None = None) -> int:
    """Pin the threads, then run the command; returns the exit status."""
    pin_threads()  # before numpy loads
    from baselines.experiments.quadrotor.experiment import main as run

    return run(argv)


if __name__ == "__main__":
    sys.exit(main())
