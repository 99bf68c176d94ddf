"""Two quadrotor-experiment runs compared seed by seed: per-run criterion misses, discordant
pairs with an exact McNemar test, and the paired change of each criterion's metric.

The Sec. VI-B criteria must hold on every seed of a set, so one run in 50 decides a set; this
module counts runs instead, on the seeds both runs share (``python -m
baselines.quadrotor_compare``, docs/safety-results.md "Per run rather than per set").
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from baselines.experiments.quadrotor.criteria import (
    CRITERIA_KEYS,
    QUADROTOR,
    QuadrotorCriteria,
    run_outcomes,
)
from baselines.reporting.stats import bootstrap_ci, mcnemar_exact

__all__ = ["compare_runs", "paired_lines"]


def _metric(rows, name: str, key: str, seeds: np.ndarray) -> np.ndarray:
    by_seed = {
        int(float(r["seed"])): float(r[key])
        for r in rows
        if r["dynamics"] == "quadrotor" and r["policy"] == name
    }
    return np.array([by_seed[int(s)] for s in seeds])


def _outcomes(label: str, rows, name: str, criteria: QuadrotorCriteria) -> dict[str, Any]:
    """:func:`run_outcomes` of one side; ``ValueError`` naming the side when it has no run of
    ``name`` or a seed twice."""
    got = run_outcomes(rows, name, criteria)
    if not got:
        there = sorted({r["policy"] for r in rows if r["dynamics"] == "quadrotor"})
        raise ValueError(
            f"run {label} has no quadrotor rows of policy {name!r}; it has {there or 'none'}"
        )
    seen, counts = np.unique(got["seed"], return_counts=True)
    if (counts > 1).any():
        raise ValueError(
            f"run {label} has seed {int(seen[counts > 1][0])} more than once: pool "
            "folders of distinct seeds"
        )
    return got


def compare_runs(
    rows_a: Sequence[Mapping[str, Any]],
    rows_b: Sequence[Mapping[str, Any]],
    policy_a: str = "smc",
    policy_b: str | None = None,
    *,
    criteria: QuadrotorCriteria = QUADROTOR,
    rng: np.random.Generator,
    n_boot: int = 4000,
) -> dict[str, Any]:
    """Run A (``policy_a`` in ``rows_a``) against run B (``policy_b``, default the same name,
    in ``rows_b``) on the quadrotor seeds both have.

    Returns ``seeds`` (the shared seeds), ``misses`` {criterion: (A, B)} runs that miss,
    ``all_pass`` (A, B) runs that meet every criterion both runs have, ``all_discordant``
    (runs that miss one of them in A only, in B only, exact McNemar p), ``discordant``
    {criterion: (A only, B only, exact two-sided McNemar p)} and ``change`` {metric: (median
    of B - A, bootstrap 95 % CI low, high)} over the seeds, resampled with ``rng``.
    Raises ``ValueError`` naming what is missing when the runs share no seed.
    """
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng={rng!r} is invalid: must be a numpy.random.Generator")
    if isinstance(n_boot, bool) or not isinstance(n_boot, int) or n_boot < 1:
        raise ValueError(f"n_boot={n_boot!r} is invalid: must be an integer >= 1")
    policy_b = policy_a if policy_b is None else policy_b
    a = _outcomes("A", rows_a, policy_a, criteria)
    b = _outcomes("B", rows_b, policy_b, criteria)
    seeds = np.intersect1d(a["seed"], b["seed"])
    if seeds.size == 0:
        raise ValueError("the two runs share no seed: nothing to pair")
    ia = np.searchsorted(a["seed"], seeds)  # run_outcomes gives the seeds in order
    ib = np.searchsorted(b["seed"], seeds)
    keys = [k for k in CRITERIA_KEYS if k in a and k in b]
    out: dict[str, Any] = {"seeds": seeds, "misses": {}, "discordant": {}, "change": {}}
    for k in keys:
        pa, pb = a[k][ia], b[k][ib]
        out["misses"][k] = (int((~pa).sum()), int((~pb).sum()))
        only_a, only_b = int((~pa & pb).sum()), int((pa & ~pb).sum())
        out["discordant"][k] = (only_a, only_b, mcnemar_exact(only_a, only_b))
    every_a = np.all([a[k][ia] for k in keys], axis=0)
    every_b = np.all([b[k][ib] for k in keys], axis=0)
    out["all_pass"] = (int(every_a.sum()), int(every_b.sum()))
    only_a, only_b = int((~every_a & every_b).sum()), int((every_a & ~every_b).sum())
    out["all_discordant"] = (only_a, only_b, mcnemar_exact(only_a, only_b))
    metrics = dict.fromkeys(CRITERIA_KEYS[k] for k in keys if k != "no_crash")
    for m in metrics:
        d = _metric(rows_b, policy_b, m, seeds) - _metric(rows_a, policy_a, m, seeds)
        out["change"][m] = (float(np.median(d)), *bootstrap_ci(d, np.median, rng, n_boot))
    out["turn_peak_by_filter"] = _turn_peak_by_filter(rows_a, rows_b, policy_a, policy_b, seeds)
    return out


#: a filter action this close before run B's turn peak (s) counts as recent
RECENT_ACTION = 1.5


def _turn_peak_by_filter(rows_a, rows_b, policy_a, policy_b, seeds) -> list[tuple] | None:
    """Where run B has the safety filter's timing (``turn_peak_since_filter``): the seeds
    split by whether B's filter acted within RECENT_ACTION s before B's turn peak; per group
    (name, runs, turn-peak misses A, misses B, median turn peak A, B). None otherwise."""
    has = [
        r
        for r in rows_b
        if r["dynamics"] == "quadrotor"
        and r["policy"] == policy_b
        and "turn_peak_since_filter" in r
        and r.get("safety_active_steps", "") != ""  # written only with the filter on
    ]
    if not has:
        return None
    since = {int(float(r["seed"])): float(r["turn_peak_since_filter"] or "nan") for r in has}
    s = np.array([since.get(int(k), np.nan) for k in seeds])
    pa = _metric(rows_a, policy_a, "turn_peak_error", seeds)
    pb = _metric(rows_b, policy_b, "turn_peak_error", seeds)
    lim = QUADROTOR.turn_peak_max
    groups = []
    recent = s <= RECENT_ACTION  # NaN (no action before the peak) is not recent
    for name, m in (
        (f"filter acted within {RECENT_ACTION:g} s before the peak", recent),
        ("filter did not", ~recent),
    ):
        if m.any():
            groups.append(
                (
                    name,
                    int(m.sum()),
                    int((pa[m] > lim).sum()),
                    int((pb[m] > lim).sum()),
                    float(np.median(pa[m])),
                    float(np.median(pb[m])),
                )
            )
    return groups


def paired_lines(result: Mapping[str, Any], label_a: str = "A", label_b: str = "B") -> list[str]:
    """Markdown tables of :func:`compare_runs`' result."""
    n = len(result["seeds"])
    lines = [
        f"{n} seeds in both runs; runs that miss each criterion, and the runs that miss it "
        "in one of the two only (exact McNemar p, two-sided):",
        "",
        f"| criterion | {label_a}: misses | {label_b}: misses | {label_a} only | "
        f"{label_b} only | p |",
        "|---|---|---|---|---|---|",
    ]
    for k, (ma, mb) in result["misses"].items():
        oa, ob, p = result["discordant"][k]
        lines.append(f"| {k} | {ma} | {mb} | {oa} | {ob} | {p:.3g} |")
    pa, pb = result["all_pass"]
    oa, ob, p = result["all_discordant"]
    lines += [f"| any criterion | {n - pa} | {n - pb} | {oa} | {ob} | {p:.3g} |"]
    lines += [f"| runs meeting all | {pa} | {pb} | | | |", ""]
    lines += [
        f"Paired change {label_b} - {label_a} of each criterion's metric (median over seeds, "
        "bootstrap 95 % CI):",
        "",
        "| metric | median change | 95 % CI |",
        "|---|---|---|",
    ]
    for m, (med, lo, hi) in result["change"].items():
        lines.append(f"| {m} | {med:+.4f} | [{lo:+.4f}, {hi:+.4f}] |")
    groups = result.get("turn_peak_by_filter")
    if groups:
        lines += [
            "",
            f"Turn peaks by when {label_b}'s safety filter last acted before them:",
            "",
            f"| runs | count | {label_a}: turn-peak misses | {label_b}: turn-peak misses | "
            f"{label_a}: median turn peak (m) | {label_b}: median turn peak (m) |",
            "|---|---|---|---|---|---|",
        ]
        for name, n_, ma, mb, med_a, med_b in groups:
            lines.append(f"| {name} | {n_} | {ma} | {mb} | {med_a:.3f} | {med_b:.3f} |")
    return lines
