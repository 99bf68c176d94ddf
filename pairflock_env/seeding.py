"""Seeds: one validator for every view, and the per-swarm generators a seed gives.

A *seed* is ``None``, an integer >= 0 (Python or numpy, not ``bool``) or a
:class:`numpy.random.SeedSequence`, in every view (core, PettingZoo, Gymnasium, vector, SB3).
Anything else is a ``TypeError`` (``seed="1"``, ``1.5``, ``True``), a negative integer a
``ValueError``; both name the argument and say what is valid.

Two rules turn one seed into the generators of B swarms:

* the core's (:func:`swarm_generators`): an int or SeedSequence ``s`` gives swarm b the
  generator of child b of ``SeedSequence(s)`` (``SeedSequence(s).spawn(B)[b]``); a sequence
  of B seeds gives swarm b ``np.random.default_rng(seeds[b])``;
* the vector views' (:func:`offset_seeds`, as Gymnasium's ``SyncVectorEnv``): an int ``s``
  gives sub-env b the seed ``s + b``, a SeedSequence gives it child b, so sub-env b equals a
  single env reset with that seed.

Children are computed from the SeedSequence's entropy and spawn key without advancing it, so
passing the same SeedSequence object twice gives the same episodes (as the same int does).
No global random state is read or changed.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = [
    "SeedLike",
    "check_seed",
    "check_seed_list",
    "offset_seeds",
    "spawn",
    "swarm_generators",
]

SeedLike = int | np.integer | np.random.SeedSequence | None

_VALID = "None, an int >= 0 or a numpy SeedSequence"


def check_seed(seed: Any, name: str = "seed") -> int | np.random.SeedSequence | None:
    """One validated seed: ``None``, a Python int >= 0 or the given SeedSequence.

    Raises:
        TypeError: ``seed`` is of another type (``bool``, float, str, ...).
        ValueError: ``seed`` is a negative integer.
    """
    if seed is None or isinstance(seed, np.random.SeedSequence):
        return seed
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)):
        raise TypeError(f"{name}={seed!r} is invalid: must be {_VALID}, got {type(seed).__name__}")
    if seed < 0:
        raise ValueError(f"{name}={seed!r} is invalid: must be {_VALID}")
    return int(seed)


def _entries(seeds: Any) -> list | None:
    """The entries of a sequence of seeds (a list, tuple or 1-D numpy array), else None."""
    if isinstance(seeds, np.ndarray) and seeds.ndim == 1:
        return seeds.tolist() if seeds.dtype.kind in "iu" else list(seeds)
    if isinstance(seeds, Sequence) and not isinstance(seeds, (str, bytes)):
        return list(seeds)
    return None


def check_seed_list(seeds: Any, n: int, name: str = "seed") -> list:
    """A sequence of exactly ``n`` seeds (one per swarm), each validated by :func:`check_seed`.

    Raises:
        TypeError: ``seeds`` is not a sequence (a str is not), or an entry is of a wrong type.
        ValueError: the length is not ``n``, or an entry is negative.
    """
    entries = _entries(seeds)
    if entries is None:
        raise TypeError(
            f"{name}={seeds!r} is invalid: must be a seed ({_VALID}) or a sequence of {n} seeds"
        )
    seeds = entries
    if len(seeds) != n:
        raise ValueError(f"{name} has {len(seeds)} entries, expected {n} (one per swarm)")
    return [check_seed(s, f"{name}[{i}]") for i, s in enumerate(seeds)]


def spawn(seed: int | np.random.SeedSequence | None, n: int) -> list[np.random.SeedSequence]:
    """The ``n`` children that ``SeedSequence(seed).spawn(n)`` gives, without advancing a
    SeedSequence passed in (``None``: fresh OS entropy)."""
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    first = ss.n_children_spawned
    return [
        np.random.SeedSequence(
            ss.entropy, spawn_key=(*ss.spawn_key, first + i), pool_size=ss.pool_size
        )
        for i in range(n)
    ]


def swarm_generators(seed: Any, n: int, name: str = "seed") -> list[np.random.Generator | None]:
    """Generators for ``n`` swarms under the core's rule (see the module docstring).

    ``None`` or an int/SeedSequence gives ``n`` children (``None``: from OS entropy); a
    sequence of ``n`` seeds gives one generator per entry, ``None`` where an entry is None
    (that swarm keeps its generator).
    """
    if _entries(seed) is None:
        return [np.random.default_rng(c) for c in spawn(check_seed(seed, name), n)]
    return [None if s is None else np.random.default_rng(s) for s in check_seed_list(seed, n, name)]


def offset_seeds(seed: Any, n: int, name: str = "seed") -> list | None:
    """Per-sub-env seeds under the vector views' rule: ``None`` -> None, an int ``s`` ->
    ``[s, s + 1, ..., s + n - 1]``, a SeedSequence -> its ``n`` children, a sequence (list,
    tuple or 1-D array) of ``n`` seeds -> those seeds (validated)."""
    if _entries(seed) is not None:
        return check_seed_list(seed, n, name)
    s = check_seed(seed, name)
    if s is None:
        return None
    if isinstance(s, np.random.SeedSequence):
        return spawn(s, n)
    return [s + i for i in range(n)]
