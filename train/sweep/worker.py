"""``python -m train.sweep.worker SWEEP_DIR TRIAL_NAME``: one trial of a local sweep in a
worker process (:func:`train.sweep.trial.worker_main`), on one thread."""

import sys
from collections.abc import Sequence

from baselines.runtime.threads import pin_threads


def main(argv: Sequence[str] | None = None) -> int:
    """Pin the threads, then run the trial; returns the exit status."""
    pin_threads()  # before numpy and torch load
    from train.sweep.trial import worker_main

    return worker_main(argv)


if __name__ == "__main__":
    sys.exit(main())
