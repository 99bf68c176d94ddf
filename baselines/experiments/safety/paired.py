"""What the safety filter changes for a controller, run by run: the filter-off and filter-on
runs of a benchmark paired by (scenario, seed, pair).

The safety table (:func:`baselines.reporting.tables.safety_table`) gives each side's median
and worst run. Those are two separate samples: where the filter acts it moves the pair onto
another trajectory, and a controller's steady error on that trajectory can be larger or
smaller than before. This module pairs the runs and reports, per controller and scenario and
for each metric, the change of the median and of the worst run, the change of the 90th
percentile and the median of the per-run ratio on/off (each with a seeded bootstrap 95 % CI
over the runs), and how many runs got more than 10 % worse, more than 10 % better, or stayed
identical (``python -m baselines.safety_compare``, docs/safety-results.md "Run by run").
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from baselines.reporting.figures import save_figure
from baselines.reporting.stats import percentile_interval, resample
from pairflock_env.task.metrics import METRIC_DOCS, SAFETY_METRIC_DOCS

__all__ = ["PAIRED_METRICS", "compare_filter", "paired_figure", "paired_filter_lines"]

Row = Mapping[str, Any]

#: the metrics compared by default: the issue's two costs of the filter for a controller
PAIRED_METRICS = ("ss_mean_error", "band_time")
#: columns that identify a run within a group, or that are the compared axis itself
_RUN_COLUMNS = frozenset({"scenario", "safety_filter", "seed", "pair"})
#: per-run columns that are results, not settings
_RESULT_COLUMNS = (
    frozenset(METRIC_DOCS)
    | frozenset(SAFETY_METRIC_DOCS)
    | {
        "clipped_steps",
        "steps_run",
        "turn_peak_since_filter",
    }
)
#: a run counts as worse (better) when on/off exceeds 1 + this (falls below 1 - this)
CHANGE = 0.10


def _settings(row: Row) -> set[str]:
    return {k for k in row if k not in _RUN_COLUMNS and k not in _RESULT_COLUMNS}


def _value(row: Row, metric: str) -> float:
    """The metric as a float; empty, missing or ``never`` is NaN (e.g. a band never entered)."""
    v = row.get(metric, "")
    if v is None or v == "":
        return math.nan
    try:
        return float(v)
    except ValueError:
        return math.nan


def _side(rows: Sequence[Row], flt: str, keys: Sequence[str], label: str):
    """{(group key, variant): {(seed, pair): row}} of the rows with ``safety_filter == flt``."""
    out: dict[tuple, dict[tuple[int, int], Row]] = {}
    for r in rows:
        if str(r.get("safety_filter", "none")) != flt:
            continue
        group = tuple(str(r[k]) for k in keys)
        variant = tuple(sorted((k, str(r[k])) for k in _settings(r) - set(keys)))
        run = (int(float(r["seed"])), int(float(r.get("pair", 0))))
        runs = out.setdefault((group, variant), {})
        if run in runs:
            raise ValueError(
                f"run {label} has seed {run[0]}, pair {run[1]} twice in the group "
                f"{dict(zip(keys, group, strict=True))} {dict(variant)}: pool folders of "
                "distinct seeds"
            )
        runs[run] = r
    return out


def _ratio_stats(a: np.ndarray, b: np.ndarray, rng: np.random.Generator, n_boot: int):
    """(90th-percentile change, its CI), (median per-run ratio, its CI) of finite pairs."""
    ok = np.isfinite(a) & np.isfinite(b) & (a > 0)
    a, b = a[ok], b[ok]
    if a.size == 0:
        nan = (math.nan, math.nan, math.nan)
        return nan, nan
    idx = resample(rng, a.size, n_boot)
    q_a, q_b = np.percentile(a[idx], 90, axis=1), np.percentile(b[idx], 90, axis=1)
    tail = q_b / q_a - 1.0
    ratio = b / a
    med = np.median(ratio[idx], axis=1)
    p90 = float(np.percentile(b, 90) / np.percentile(a, 90) - 1.0)
    return (
        (p90, *percentile_interval(tail)),
        (float(np.median(ratio)), *percentile_interval(med)),
    )


def _change(a: float, b: float) -> float:
    return b / a - 1.0 if a > 0 and math.isfinite(a) and math.isfinite(b) else math.nan


def _line_stats(a: np.ndarray, b: np.ndarray, rng: np.random.Generator, n_boot: int):
    """One line of :func:`compare_filter` from the paired values off (``a``) and on (``b``)."""
    sides = []
    for v in (a, b):
        f = v[np.isfinite(v)]
        stats = (float(np.median(f)), float(f.max())) if f.size else (math.nan,) * 2
        sides.append((*stats, int(v.size - f.size)))
    both = np.isfinite(a) & np.isfinite(b)
    p90, ratio = _ratio_stats(a, b, rng, n_boot)
    return {
        "runs": int(a.size),
        "a": sides[0],
        "b": sides[1],
        "median_change": _change(sides[0][0], sides[1][0]),
        "worst_change": _change(sides[0][1], sides[1][1]),
        "p90_change": p90,
        "ratio": ratio,
        "worse": int(np.sum(both & (b > (1 + CHANGE) * a))),
        "better": int(np.sum(both & (b < (1 - CHANGE) * a))),
        "identical": int(np.sum((a == b) | (np.isnan(a) & np.isnan(b)))),
        "values": (tuple(a.tolist()), tuple(b.tolist())),
    }


def _checked_rows(rows_a, rows_b, metrics, policies):
    """``(rows_a, rows_b, metrics)`` after the checks of :func:`compare_filter`: both sides
    have rows (of ``policies``, when given) and every metric is a column of both."""
    rows_b = rows_a if rows_b is None else rows_b
    if not rows_a or not rows_b:
        raise ValueError("nothing to compare: a side has no rows")
    metrics = (metrics,) if isinstance(metrics, str) else tuple(metrics)
    for m in metrics:
        if any(m not in r for r in (rows_a[0], rows_b[0])):
            raise ValueError(
                f"metric {m!r} is not a column of both runs; they have "
                f"{sorted(set(rows_a[0]) & set(rows_b[0]) & _RESULT_COLUMNS)}"
            )
    if policies is not None:
        wanted = {policies} if isinstance(policies, str) else {str(p) for p in policies}
        have = sorted({str(r["policy"]) for r in (*rows_a, *rows_b)})
        rows_a = [r for r in rows_a if str(r["policy"]) in wanted]
        rows_b = [r for r in rows_b if str(r["policy"]) in wanted]
        if not rows_a or not rows_b:
            raise ValueError(
                f"policies={sorted(wanted)} is invalid: a side has no run of them; the runs "
                f"have {have}"
            )
    return rows_a, rows_b, metrics


def _one_run_per_group(side_a: Mapping[tuple, Any], keys: Sequence[str]) -> dict[tuple, Any]:
    """The filter-off side by group: one run per group to pair against (``ValueError`` when
    a group has several values of a setting)."""
    off: dict[tuple, dict[tuple[int, int], Row]] = {}
    for (group, variant), runs in side_a.items():
        if group in off:
            raise ValueError(
                f"run A has several values of {sorted(dict(variant))} in the group "
                f"{dict(zip(keys, group, strict=True))}: pass its folders as --against, or "
                "folders that share that setting"
            )
        off[group] = runs
    return off


def _lines(off, side_b, keys: Sequence[str], metrics, base: int, n_boot: int) -> list[dict]:
    """One line per (group, variant, metric) that pairs: controllers in order of appearance,
    each with its settings in order (as the table)."""
    first = {p: i for i, p in reversed(list(enumerate(g[0] for g, _ in side_b)))}
    order = sorted(side_b, key=lambda gv: first[gv[0][0]])  # stable: settings keep order
    out: list[dict[str, Any]] = []
    for group, variant in order:
        runs_b = side_b[group, variant]
        runs_a = off.get(group)
        shared = sorted(set(runs_a) & set(runs_b)) if runs_a is not None else []
        for m in metrics if shared else ():
            a = np.array([_value(runs_a[k], m) for k in shared])
            b = np.array([_value(runs_b[k], m) for k in shared])
            line = zlib.crc32(repr((group, variant, m)).encode())
            stats = _line_stats(a, b, np.random.default_rng([base, line]), n_boot)
            head = {"group": dict(zip(keys, group, strict=True)), "variant": dict(variant)}
            out.append({**head, "metric": m, **stats})
    return out


def compare_filter(
    rows_a: Sequence[Row],
    rows_b: Sequence[Row] | None = None,
    *,
    metrics: Sequence[str] = PAIRED_METRICS,
    policies: Sequence[str] | None = None,
    filters: tuple[str, str] = ("none", "cbf"),
    rng: np.random.Generator,
    n_boot: int = 2000,
) -> list[dict[str, Any]]:
    """Pair the filter-off runs of ``rows_a`` with the filter-on runs of ``rows_b`` (default:
    ``rows_a`` too, i.e. a benchmark that swept ``safety_filter``).

    ``filters`` are the ``safety_filter`` values of the two sides: ``("none", "none")``
    compares two filter-off runs, e.g. against a small random disturbance (a placebo that
    moves the trajectories without avoiding anything).

    Runs pair on every setting column the two sides share (policy, N, init, ...) and on
    (seed, pair). Settings that only ``rows_b`` has (e.g. a swept ``safety_other_accel``) make
    separate *variants*, each compared with the same filter-off runs. Returns one dict per
    (group, variant, metric): ``group`` {column: value}, ``variant`` {column: value},
    ``metric``, ``runs`` (paired), ``a``/``b`` the sides' (median, worst, runs with no
    value), ``median_change``, ``worst_change``, ``p90_change`` (value, CI low, high),
    ``ratio`` (median per-run on/off, CI low, high), ``worse``/``better`` (runs changed by
    more than 10 %), ``identical`` (runs whose value is the same bit for bit) and ``values``
    (the paired runs' values, off and on, NaN where there is none).

    Raises ``ValueError`` naming what is missing when nothing pairs, ``TypeError`` for a
    ``rng`` that is not a ``numpy.random.Generator``.
    """
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng={rng!r} is invalid: must be a numpy.random.Generator")
    if isinstance(n_boot, bool) or not isinstance(n_boot, int) or n_boot < 1:
        raise ValueError(f"n_boot={n_boot!r} is invalid: must be an integer >= 1")
    if len(filters) != 2 or any(f not in ("none", "cbf") for f in filters):
        raise ValueError(f"filters={filters!r} is invalid: must be two of 'none', 'cbf'")
    rows_a, rows_b, metrics = _checked_rows(rows_a, rows_b, metrics, policies)
    common = _settings(rows_a[0]) & _settings(rows_b[0])
    keys = ["policy", *(k for k in rows_a[0] if k in common and k != "policy")]
    off = _one_run_per_group(_side(rows_a, filters[0], keys, "A"), keys)
    side_b = _side(rows_b, filters[1], keys, "B")
    base = int(rng.integers(2**63))  # each line resamples with its own stream, so that its
    # interval does not depend on which other lines are compared
    out = _lines(off, side_b, keys, metrics, base, n_boot)
    if not out:
        raise ValueError(
            f"no run of A with safety_filter={filters[0]} pairs with a run of B with "
            f"safety_filter={filters[1]}: they share no setting group and seed"
        )
    return out


def _pct(x: float) -> str:
    return "-" if not math.isfinite(x) else f"{100 * x:+.1f} %"


def _num(x: float) -> str:
    return "never" if not math.isfinite(x) else f"{x:.3g}"


def paired_filter_lines(result: Sequence[Mapping[str, Any]]) -> list[str]:
    """A markdown table of :func:`compare_filter`'s result; leading columns only for the
    settings that differ between its lines."""
    lead = [
        k
        for k in result[0]["group"]
        if k == "policy" or len({str(r["group"][k]) for r in result}) > 1
    ]
    variants = any(r["variant"] for r in result)
    head = [*lead, *(["variant"] if variants else []), "metric", "runs"]
    head += [
        "off: median / worst",
        "on: median / worst",
        "median change",
        "worst change",
        "90th pct change [95 % CI]",
        "per-run on/off, median [95 % CI]",
        "runs > +10 % / < -10 % / identical",
    ]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in result:
        cells = [str(r["group"][k]) for k in lead]
        if variants:
            cells.append(", ".join(f"{k}={v}" for k, v in r["variant"].items()) or "-")
        p, plo, phi = r["p90_change"]
        q, qlo, qhi = r["ratio"]
        sides = []
        for med, worst, never in (r["a"], r["b"]):
            extra = f" (never in {never})" if never else ""
            sides.append(f"{_num(med)} / {_num(worst)}{extra}")
        cells += [
            r["metric"],
            str(r["runs"]),
            *sides,
            _pct(r["median_change"]),
            _pct(r["worst_change"]),
            f"{_pct(p)} [{_pct(plo)}, {_pct(phi)}]",
            f"{q:.3f} [{qlo:.3f}, {qhi:.3f}]" if math.isfinite(q) else "-",
            f"{r['worse']} / {r['better']} / {r['identical']}",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def _line_label(r: Mapping[str, Any], lead: Sequence[str]) -> str:
    parts = [f"{k}={r['group'][k]}" for k in lead if k != "policy"]
    parts += [f"{k}={v}" for k, v in r["variant"].items()]
    return ", ".join(parts) or "all runs"


def paired_figure(result: Sequence[Mapping[str, Any]], path, dpi: int = 110):
    """Every paired run as a dot, filter off (x) against on (y), one panel per (controller,
    metric), one colour per setting, with y = x and the +-10 % lines; returns ``path``."""
    lead = [k for k in result[0]["group"] if len({str(r["group"][k]) for r in result}) > 1]
    panels = list(dict.fromkeys((r["group"]["policy"], r["metric"]) for r in result))
    fig = Figure(figsize=(4.0 * len(panels), 4.0))
    axes = fig.subplots(1, len(panels), squeeze=False)
    for ax, (pol, metric) in zip(axes[0], panels, strict=True):
        lo, hi = math.inf, -math.inf
        for r in result:
            if (r["group"]["policy"], r["metric"]) != (pol, metric):
                continue
            a, b = (np.asarray(v, dtype=float) for v in r["values"])
            ok = np.isfinite(a) & np.isfinite(b)
            if ok.any():
                ax.plot(a[ok], b[ok], ".", ms=3, alpha=0.6, label=_line_label(r, lead))
                lo = min(lo, a[ok].min(), b[ok].min())
                hi = max(hi, a[ok].max(), b[ok].max())
        if math.isfinite(lo):
            x = np.array([lo, hi])
            ax.plot(x, x, "k-", lw=0.8)
            for f in (1 - CHANGE, 1 + CHANGE):
                ax.plot(x, f * x, "k--", lw=0.6)
        ax.set_xlabel(f"{metric}, filter off")
        ax.set_ylabel(f"{metric}, filter on")
        ax.set_title(pol, fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6, loc="upper left")
    fig.suptitle("Per run, filter off against on (solid: equal; dashed: +-10 %)")
    fig.tight_layout()
    return save_figure(fig, path, dpi)
