"""``python -m baselines.safety_compare`` (the documented command).

Runs :mod:`baselines.experiments.safety_compare`.
"""

import sys

from baselines.experiments import safety_compare as _impl

__all__ = list(_impl.__all__)


def __getattr__(name: str):
    return getattr(_impl, name)


if __name__ == "__main__":
    sys.exit(_impl.main())
