"""The acceptance thresholds of the benchmark and of training, and the checks that apply them.

* :data:`PAPER` - the Sec. VI-A reproduction (particle swarm, ``python -m
  baselines.reproduce --check``; docs/benchmark.md);
* :data:`LEARNED` - the trained pair policy (``python -m train.evaluate --check``, and the
  score training keeps its best model by; docs/learning.md);
* :data:`GENERALIST` - the safe generalist pair policy of docs/safety-results.md, on every evaluated
  (N, start) (``python -m train.evaluate --targets generalist --check``; ``eval_targets:
  generalist`` in a run config selects the best model by them).

A check returns a list of ``(criterion, ok, measured)``; a criterion whose text ends in
``(aim)`` is reported (met / missed) but never fails a ``--check``. The Sec. VI-B criteria
of the quadrotor experiment live with it (:mod:`baselines.experiments.quadrotor.criteria`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from baselines.reporting.tables import md_escape, stat_cell

__all__ = [
    "GENERALIST",
    "LEARNED",
    "PAPER",
    "TARGETS",
    "Check",
    "LearnedTargets",
    "PaperCriteria",
    "all_passed",
    "check_learned",
    "check_learned_all",
    "check_paper_claims",
    "criteria_lines",
    "criteria_table",
    "learned_score",
    "verdict",
]

#: (criterion, ok, measured)
Check = tuple[str, bool, str]


@dataclasses.dataclass(frozen=True)
class PaperCriteria:
    """Sec. VI-A, per scenario and every seed (times in s, distances in m)."""

    settle: tuple[float, float] = (1.5, 3.0)  # sliding mode: s settles within this window
    band: tuple[float, float] = (3.0, 5.0)  # ... and is in the 0.5 m band for good within this
    steady_mean_error: float = 0.20  # ... steady mean |error| at most this
    proportional_ratio: float = 5.0  # proportional median error >= this x sliding mode's
    zero_error: float = 10.0  # without a pair term the pair stays at least this far off


@dataclasses.dataclass(frozen=True)
class LearnedTargets:
    """Targets of a learned pair policy per (N, start) (distances in m, times in s); the
    defaults are those of the N = 20, corners policy (:data:`LEARNED`)."""

    median_error: float = 0.05  # median over seeds of the steady mean |error|
    max_error: float = 0.1  # no seed's steady mean |error| above this
    band_by: float = 6.0  # in the 0.5 m band for good by this time on every seed
    min_separation: float = 1.0  # paired UAVs keep this far from every other UAV ...
    separation_is_aim: bool = True  # ... as an aim (reported, never failing a --check)
    band_median_by: float | None = None  # median band time at most this (None: no target)
    peak_accel: float | None = None  # m/s^2: peak pair acceleration on every seed (None: none)


PAPER = PaperCriteria()
LEARNED = LearnedTargets()
#: the safe generalist (docs/safety-results.md): every N in 20-100, both starts, filter on
GENERALIST = LearnedTargets(
    median_error=0.01,
    max_error=0.05,
    band_by=6.0,
    min_separation=1.0,
    separation_is_aim=False,
    band_median_by=5.0,
    peak_accel=50.0,
)
#: targets by name (``train.evaluate --targets``, the ``eval_targets`` run setting)
TARGETS = {"learned": LEARNED, "generalist": GENERALIST}


# --------------------------------------------------------------------------- reporting
def verdict(criterion: str, ok: bool) -> str:
    """pass/FAIL for a criterion; met/missed for an aim (an aim never fails ``--check``)."""
    if criterion.endswith("(aim)"):
        return "met" if ok else "missed"
    return "pass" if ok else "FAIL"


def all_passed(checks: Sequence[Check]) -> bool:
    """True when there are checks and none but aims failed."""
    return bool(checks) and all(ok for c, ok, _ in checks if not c.endswith("(aim)"))


def criteria_table(checks: Sequence[Check]) -> list[str]:
    """Markdown lines of a ``| criterion | result | measured |`` table."""
    lines = ["| criterion | result | measured |", "|---|---|---|"]
    return lines + [f"| {md_escape(c)} | {verdict(c, ok)} | {d} |" for c, ok, d in checks]


def criteria_lines(checks: Sequence[Check]) -> list[str]:
    """``[pass] criterion: measured`` lines for the terminal."""
    return [f"[{verdict(c, ok)}] {c}: {d}" for c, ok, d in checks]


# --------------------------------------------------------------------------- Sec. VI-A
def _scenario(r: Mapping[str, Any]) -> str:
    return r["scenario"] if "scenario" in r else f"N={r['n_uavs']}"


def _values(rows: Sequence[Mapping[str, Any]], key: str) -> np.ndarray:
    return np.array([r[key] for r in rows])


def _paper_smc(sc: str, smc, prop, c: PaperCriteria) -> list[Check]:
    s, b, e = (_values(smc, k) for k in ("s_settle_time", "band_time", "ss_mean_error"))
    (s_lo, s_hi), (b_lo, b_hi) = c.settle, c.band
    out = [
        (
            f"{sc} smc: s settles in {s_lo}-{s_hi} s on every seed",
            bool(np.all((s >= s_lo) & (s <= s_hi))),
            stat_cell(s, "{:.2f}") + " s",
        ),
        (
            f"{sc} smc: in the 0.5 m band for good at {b_lo}-{b_hi} s on every seed",
            bool(np.all((b >= b_lo) & (b <= b_hi))),
            stat_cell(b, "{:.2f}") + " s",
        ),
        (
            f"{sc} smc: steady mean error <= {c.steady_mean_error:.2f} m on every seed",
            bool(np.all(e <= c.steady_mean_error)),
            f"max {np.max(e):.3f} m",
        ),
    ]
    if prop:
        pm = float(np.median(_values(prop, "ss_mean_error")))
        sm = float(np.median(e))
        out.append(
            (
                f"{sc} proportional median error >= {c.proportional_ratio:g}x smc median",
                pm >= c.proportional_ratio * sm,
                f"{pm:.3f} m vs {sm:.3f} m ({pm / sm:.1f}x)",
            )
        )
    return out


def check_paper_claims(
    rows: Sequence[Mapping[str, Any]], criteria: PaperCriteria = PAPER
) -> list[Check]:
    """The acceptance criteria of the Sec. VI-A reproduction, per scenario (every seed)."""
    out: list[Check] = []
    for sc in dict.fromkeys(_scenario(r) for r in rows):
        sel = [r for r in rows if _scenario(r) == sc]
        by = {p: [r for r in sel if r["policy"] == p] for p in ("smc", "proportional", "zero")}
        if by["smc"]:
            out += _paper_smc(sc, by["smc"], by["proportional"], criteria)
        if by["zero"]:
            z = _values(by["zero"], "ss_mean_error")
            out.append(
                (
                    f"{sc} zero: steady mean error >= {criteria.zero_error:g} m on every seed",
                    bool(np.all(z >= criteria.zero_error)),
                    f"min {np.min(z):.1f} m",
                )
            )
    return out


# --------------------------------------------------------------------------- learned policy
def check_learned(
    rows: Sequence[Mapping[str, Any]],
    n_uavs: int = 20,
    init: str = "corners",
    targets: LearnedTargets = LEARNED,
) -> list[Check]:
    """The targets for the learned policy (rows of ``policy == "learned"``) at (N, init)."""
    sel = [
        r for r in rows if r["policy"] == "learned" and r["n_uavs"] == n_uavs and r["init"] == init
    ]
    if not sel:
        return []
    t = targets
    e = _values(sel, "ss_mean_error")
    b = np.array([r["band_time"] for r in sel], dtype=float)
    never = int(np.sum(~np.isfinite(b)))
    band_max = np.nanmax(b) if np.isfinite(b).any() else math.nan
    where = f"N={n_uavs} {init}"
    out = [
        (
            f"{where}: median steady-state abs error <= {t.median_error:g} m",
            bool(np.median(e) <= t.median_error),
            f"{np.median(e):.4f} m",
        ),
        (
            f"{where}: no seed above {t.max_error:g} m",
            bool(np.all(e <= t.max_error)),
            f"max {e.max():.4f} m",
        ),
        (
            f"{where}: in the 0.5 m band for good within {t.band_by:g} s on every seed",
            bool(never == 0 and np.all(b <= t.band_by)),
            f"max {band_max:.2f} s" + (f", never on {never} seeds" if never else ""),
        ),
    ]
    return out + _strict_checks(sel, b, where, t)


def _strict_checks(sel, b: np.ndarray, where: str, t: LearnedTargets) -> list[Check]:
    """The separation check and the optional median band and peak acceleration targets."""
    out: list[Check] = []
    s = _values(sel, "min_pair_separation")
    aim = " (aim)" if t.separation_is_aim else ""
    if t.band_median_by is not None:
        med = float(np.median(np.where(np.isfinite(b), b, np.inf)))
        out.append(
            (
                f"{where}: median time into the 0.5 m band <= {t.band_median_by:g} s",
                med <= t.band_median_by,
                f"{med:.2f} s",
            )
        )
    out.append(
        (
            f"{where}: min pair-to-other distance >= {t.min_separation:g} m on every seed{aim}",
            bool(np.all(s >= t.min_separation)),
            f"min {s.min():.2f} m; {int(np.sum(s < t.min_separation))}/{len(s)} seeds below",
        )
    )
    if t.peak_accel is not None:
        pk = _values(sel, "peak_accel")
        out.append(
            (
                f"{where}: peak pair acceleration <= {t.peak_accel:g} m/s^2 on every seed",
                bool(np.all(pk <= t.peak_accel * (1 + 1e-9))),
                f"max {pk.max():.1f} m/s^2",
            )
        )
    return out


def check_learned_all(
    rows: Sequence[Mapping[str, Any]], targets: LearnedTargets = GENERALIST
) -> list[Check]:
    """:func:`check_learned` on every (N, init) the learned rows hold."""
    keys = dict.fromkeys((r["n_uavs"], r["init"]) for r in rows if r["policy"] == "learned")
    return [c for n, init in sorted(keys) for c in check_learned(rows, n, init, targets)]


#: score of a run that never enters the band (every other term is at most a few units)
NEVER_IN_BAND_PENALTY = 10.0


def learned_score(summary: Mapping[str, float], targets: LearnedTargets = LEARNED) -> float:
    """Lower is better: the learned policy's targets as one number (0 = every target met).

    ``max(0, median err - 0.05)/0.05 + max(0, max err - 0.1)/0.1 + max(0, band - 6)/6
    + max(0, 1 - min separation)`` plus the median error itself as a tie-breaker, over the
    summary of :func:`train.callbacks.summarize_metrics` (the numbers are those of
    ``targets``; a median band target and a peak acceleration target add terms of the same
    form).
    """
    t = targets
    band = summary["band_time_max"]
    if math.isfinite(band):
        band_pen = max(0.0, band - t.band_by) / t.band_by
    else:
        band_pen = NEVER_IN_BAND_PENALTY
    extra = 0.0
    if t.band_median_by is not None:
        med = summary["band_time_median"]
        extra += (
            max(0.0, med - t.band_median_by) / t.band_median_by
            if math.isfinite(med)
            else NEVER_IN_BAND_PENALTY
        )
    if t.peak_accel is not None:
        extra += max(0.0, summary["peak_accel_max"] - t.peak_accel) / t.peak_accel
    return (
        extra
        + max(0.0, summary["ss_error_median"] - t.median_error) / t.median_error
        + max(0.0, summary["ss_error_max"] - t.max_error) / t.max_error
        + band_pen
        + max(0.0, t.min_separation - summary["min_separation_min"])
        + summary["ss_error_median"]
    )
