"""``python -m train``: see :mod:`train.cli`."""

import sys

from baselines.evaluation.parallel import pin_threads

pin_threads()  # before numpy and torch load

from train.cli import main  # noqa: E402

sys.exit(main())
