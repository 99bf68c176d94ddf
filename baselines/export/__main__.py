"""``python -m baselines.export sb3:<model> --out DIR`` (the same as ``pairflock-export``)."""

import sys

from baselines.export.cli import main

sys.exit(main())
