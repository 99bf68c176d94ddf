"""``python -m train``: see :mod:`train.cli`."""

import os
import sys

# one BLAS/OpenMP thread before numpy and torch load (SB3 is ~3x faster so on 2 cores)
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

from train.cli import main

sys.exit(main())
