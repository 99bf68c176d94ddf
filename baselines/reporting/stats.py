"""Statistics over seeds and runs, in one place: the bootstrap, the interquartile mean (IQM)
and McNemar's exact test.

* :func:`resample` and :func:`percentile_interval` - the bootstrap of the paired
  comparisons (``python -m baselines.quadrotor_compare``, ``python -m
  baselines.safety_compare``): runs drawn with replacement by an explicit generator, and the
  95 % percentile interval of a statistic over the resamples (:func:`bootstrap_ci`);
* :func:`iqm_ci` - the IQM over training seeds with the stratified-bootstrap interval of
  ``rliable`` (Agarwal et al., "Deep RL at the Edge of the Statistical Precipice", NeurIPS
  2021), for sweeps and imitation; reproducible (seeded);
* :func:`mcnemar_exact` - runs that fail on one side of a paired comparison only.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from baselines.runtime import optional

__all__ = [
    "bootstrap_ci",
    "iqm_ci",
    "mcnemar_exact",
    "percentile_interval",
    "resample",
]


def resample(rng: np.random.Generator, n: int, reps: int) -> np.ndarray:
    """Bootstrap indices: ``reps`` draws of ``n`` runs out of ``n`` with replacement, shape
    ``(reps, n)`` (``values[resample(...)]`` is the resampled data, one row per draw)."""
    return rng.integers(0, n, size=(reps, n))


def percentile_interval(samples: np.ndarray, percent: float = 95.0) -> tuple[float, float]:
    """The percentile interval holding ``percent`` % of the bootstrap ``samples`` (95: the
    2.5th and the 97.5th percentile)."""
    tail = (100.0 - percent) / 2.0
    lo, hi = np.percentile(samples, [tail, 100.0 - tail])
    return float(lo), float(hi)


def bootstrap_ci(
    values: np.ndarray,
    statistic: Callable[..., np.ndarray],
    rng: np.random.Generator,
    reps: int,
    percent: float = 95.0,
) -> tuple[float, float]:
    """Percentile interval of ``statistic(resampled, axis=1)`` (e.g. ``np.median``) over
    ``reps`` resamples of the runs ``values``."""
    values = np.asarray(values)
    boot = statistic(values[resample(rng, values.size, reps)], axis=1)
    return percentile_interval(boot, percent)


def _iqm_columns(x: np.ndarray) -> np.ndarray:
    """rliable's IQM (25 % trimmed mean) of every column at once (for the bootstrap)."""
    trim_mean = optional.load("scipy.stats", "the IQM").trim_mean
    return np.atleast_1d(trim_mean(x, 0.25, axis=0))


def _seeded_bootstrap(scores: np.ndarray, seed: int) -> Any:
    """rliable's stratified bootstrap (runs resampled within each column), drawing from its
    own seeded generator: rliable 1.2 draws the indices from NumPy's global generator and
    ignores ``random_state``, so a summary would change from one call to the next."""
    library = optional.load("rliable.library", "the IQM's confidence interval")

    class SeededStratifiedBootstrap(library.StratifiedBootstrap):
        def update_indices(self):
            runs = self.generator.integers(self._num_items, size=self._args_shape)
            return (runs, *self._strata_indices)

    return SeededStratifiedBootstrap(scores, seed=np.random.default_rng(seed))


def iqm_ci(
    scores: np.ndarray, reps: int = 2000, seed: int = 0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """IQM over runs and its 95 % stratified-bootstrap CI, per column of ``scores``
    (shape ``(runs, columns)``): ``(point, low, high)``, each of shape ``(columns,)``. With
    fewer than four runs the IQM trims nothing (it is the mean)."""
    metrics = optional.load("rliable.metrics", "the IQM")
    scores = np.asarray(scores, dtype=float)
    if scores.ndim != 2 or scores.shape[0] < 1:
        raise ValueError(f"scores of shape {scores.shape} are invalid: (runs >= 1, columns)")
    point = np.array([metrics.aggregate_iqm(scores[:, j]) for j in range(scores.shape[1])])
    ci = _seeded_bootstrap(scores, seed).conf_int(
        _iqm_columns, reps=reps, size=0.95, method="percentile"
    )
    return point, ci[0], ci[1]


def mcnemar_exact(only_a: int, only_b: int) -> float:
    """Two-sided exact McNemar p for ``only_a`` and ``only_b`` discordant pairs: twice the
    smaller binomial(n, 1/2) tail, at most 1 (1 when there are none). The tests check it
    against scipy's ``binomtest``."""
    for name, v in (("only_a", only_a), ("only_b", only_b)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
            raise ValueError(f"{name}={v!r} is invalid: must be an integer >= 0")
    n, k = int(only_a) + int(only_b), min(int(only_a), int(only_b))
    if n == 0:
        return 1.0
    tail = sum(math.comb(n, i) for i in range(k + 1)) / 2.0**n
    return min(1.0, 2.0 * tail)
