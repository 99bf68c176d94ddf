"""``python -m pairflock_env.replay FILE -o replay.html`` (the same as ``pairflock-replay``)."""

import sys

from pairflock_env.replay.cli import main

if __name__ == "__main__":  # importing this module (a walk over the package) runs nothing
    sys.exit(main())
