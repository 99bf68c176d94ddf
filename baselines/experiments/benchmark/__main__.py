"""``python -m baselines.experiments.benchmark`` (same as ``python -m baselines.benchmark``)."""

import sys

from baselines.experiments.benchmark import main

sys.exit(main())
