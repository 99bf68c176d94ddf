"""``python -m baselines.quadrotor_invariants`` (the documented command).

Runs :mod:`baselines.experiments.quadrotor_invariants`, and gives its names (the old import path).
"""

import sys

from baselines.experiments import quadrotor_invariants as _impl

__all__ = list(_impl.__all__)


def __getattr__(name: str):
    return getattr(_impl, name)


if __name__ == "__main__":
    sys.exit(_impl.main())
