"""Per-run comparison of two quadrotor-experiment runs (``baselines.quadrotor_compare``):
the per-run outcomes are the ones ``check_quadrotor`` decides sets with, seeds are paired,
discordant runs and the exact McNemar p are counted right, and bad input is refused clearly."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from quadrotor_rows import quad_row
from result_files import write_results
from scipy.stats import binomtest

from baselines.experiments.quadrotor.criteria import (
    CRITERIA_KEYS,
    QUADROTOR,
    check_quadrotor,
    run_outcomes,
)
from baselines.experiments.quadrotor.paired import compare_runs, paired_lines
from baselines.reporting.stats import mcnemar_exact

C = QUADROTOR


def _row(policy: str, dynamics: str, seed: int, **over) -> dict:
    return quad_row(policy, dynamics, str(seed), **over)  # seeds as read back from a CSV


def _runs(turn_miss: set[int], sep_miss: set[int], seeds=range(20), policy="smc", turn=None):
    """Quadrotor and particle rows; seeds in ``turn_miss`` / ``sep_miss`` miss those."""
    rows = []
    for s in seeds:
        tp = (turn or 2 * C.turn_peak_max) if s in turn_miss else C.turn_peak_max / 2 + 1e-3 * s
        md = C.min_distance / 2 if s in sep_miss else 2 * C.min_distance
        rows.append(_row(policy, "quadrotor", s, turn_peak_error=tp, min_distance=md))
        rows.append(_row(policy, "particle", s))
    return rows


def test_run_outcomes_are_what_the_set_check_decides_on():
    rows = _runs({3, 7}, {5})
    ok = run_outcomes(rows, "smc")
    assert list(ok["seed"]) == list(range(20))  # in numeric order, from CSV text
    assert set(ok) == {"seed", *CRITERIA_KEYS}
    assert {int(s) for s in ok["seed"][~ok["turn_peak"]]} == {3, 7}
    assert {int(s) for s in ok["seed"][~ok["separation"]]} == {5}
    checks = check_quadrotor(rows)
    assert [ok_ for _, ok_, _ in checks] == [bool(ok[k].all()) for k in CRITERIA_KEYS]
    # without the particle runs the attitude cost is left out, in both
    quad = [r for r in rows if r["dynamics"] == "quadrotor"]
    assert "attitude_cost" not in run_outcomes(quad, "smc") and len(check_quadrotor(quad)) == 6
    assert run_outcomes(rows, "proportional") == {}


def test_a_run_cut_short_fails_no_crash_even_when_it_is_the_first():
    rows = _runs(set(), set(), seeds=range(3))
    rows[0]["steps_run"] = 4  # seed 0's quadrotor run ended early
    ok = run_outcomes(rows, "smc")
    assert ok["no_crash"].tolist() == [False, True, True]


def test_exact_mcnemar_matches_scipy():
    for a in range(0, 25, 3):
        for b in range(0, 25, 4):
            ref = binomtest(a, a + b, 0.5).pvalue if a + b else 1.0
            assert mcnemar_exact(a, b) == pytest.approx(ref, rel=1e-12, abs=1e-15)
    assert mcnemar_exact(3, 10) == pytest.approx(0.09228515625)
    with pytest.raises(ValueError, match="only_a=-1 is invalid"):
        mcnemar_exact(-1, 2)
    with pytest.raises(ValueError, match=r"only_b=1\.5 is invalid"):
        mcnemar_exact(1, 1.5)


def test_compare_counts_discordant_runs_and_pairs_by_seed():
    a = _runs({1, 2, 3}, {4, 5}, seeds=range(30))
    b = _runs({2, 3, 10, 11, 12}, set(), seeds=range(5, 40), policy="smc_b", turn=0.9)
    res = compare_runs(a, b, "smc", "smc_b", rng=np.random.default_rng(0), n_boot=200)
    assert list(res["seeds"]) == list(range(5, 30))  # only the shared seeds
    # on seeds 5-29: A misses the turn on none, separation on 5; B misses the turn on 10-12
    assert res["misses"]["turn_peak"] == (0, 3) and res["misses"]["separation"] == (1, 0)
    oa, ob, p = res["discordant"]["turn_peak"]
    assert (oa, ob) == (0, 3) and p == pytest.approx(binomtest(0, 3, 0.5).pvalue)
    assert res["discordant"]["band_entry"] == (0, 0, 1.0)
    assert res["all_pass"] == (24, 22)
    # any criterion: A fails seed 5 only, B fails 10-12 only
    assert res["all_discordant"] == (1, 3, pytest.approx(binomtest(1, 4, 0.5).pvalue))
    med, lo, hi = res["change"]["turn_peak_error"]
    base = C.turn_peak_max / 2 + 1e-3 * np.arange(5, 30)
    d = np.where(np.isin(np.arange(5, 30), [10, 11, 12]), 0.9, base) - base
    assert med == pytest.approx(np.median(d)) and lo <= med <= hi
    text = "\n".join(paired_lines(res, "off", "on"))
    assert "| turn_peak | 0 | 3 | 0 | 3 |" in text and "25 seeds in both runs" in text
    assert "| any criterion | 1 | 3 | 1 | 3 | 0.625 |" in text
    # the same generator seed gives the same intervals
    again = compare_runs(a, b, "smc", "smc_b", rng=np.random.default_rng(0), n_boot=200)
    assert again["change"] == res["change"]


def test_compare_splits_turn_peaks_by_when_the_filter_last_acted():
    a = _runs({1}, set(), seeds=range(10))
    b = _runs({2, 3, 7}, set(), seeds=range(10), turn=0.9)
    since = {2: "0.2", 3: "1.5", 7: "20.0", 8: ""}  # "": it never acted before the peak
    for r in b:
        if r["dynamics"] == "quadrotor":
            r["turn_peak_since_filter"] = since.get(int(r["seed"]), "30.0")
            r["safety_active_steps"] = "5"  # the experiment writes it with the filter on
    for r in a:  # filter off: the column is there (NaN), the safety columns are not
        r["turn_peak_since_filter"] = "nan"
    res = compare_runs(a, b, rng=np.random.default_rng(0), n_boot=50)
    recent, other = res["turn_peak_by_filter"]
    assert "within 1.5 s" in recent[0]
    # seeds 2 and 3 acted recently (both miss in B); the other 8 hold A's miss (1) and B's (7)
    assert recent[1:4] == (2, 0, 2) and other[1:4] == (8, 1, 1)
    assert "Turn peaks by when on's safety filter" in "\n".join(paired_lines(res, "off", "on"))
    assert compare_runs(a, a, rng=np.random.default_rng(0), n_boot=5)["turn_peak_by_filter"] is None


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        (dict(rng=0), TypeError, "rng=0 is invalid"),
        (dict(rng=np.random.default_rng(0), n_boot=0), ValueError, "n_boot=0 is invalid"),
        (
            dict(rng=np.random.default_rng(0), policy_a="zero"),
            ValueError,
            r"policy 'zero'; it has \['smc'\]",
        ),
    ],
)
def test_compare_refuses_bad_input(kwargs, exc, match):
    a = _runs(set(), set())
    with pytest.raises(exc, match=match):
        compare_runs(a, a, **kwargs)
    with pytest.raises(ValueError, match="share no seed"):
        compare_runs(a, _runs(set(), set(), seeds=range(50, 60)), rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="run B has seed 3 more than once"):
        compare_runs(a, a + _runs(set(), set(), seeds=[3]), rng=np.random.default_rng(0))


def test_cli_pools_folders_and_names_a_folder_without_results(tmp_path):
    write_results(tmp_path / "off1", _runs({1}, {2}, seeds=range(0, 10)))
    write_results(tmp_path / "off2", _runs(set(), {12}, seeds=range(10, 20)))
    write_results(tmp_path / "on", _runs({1, 15}, set(), seeds=range(20)))
    cmd = [sys.executable, "-m", "baselines.quadrotor_compare"]
    args = [str(tmp_path / "off1"), str(tmp_path / "off2"), "--against", str(tmp_path / "on")]
    out = subprocess.run(
        [*cmd, *args, "--label", "off", "--against-label", "on"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert "20 seeds in both runs" in out
    assert "| separation | 2 | 0 | 2 | 0 |" in out and "| turn_peak | 1 | 2 | 0 | 1 |" in out
    bad = subprocess.run(
        [*cmd, str(tmp_path / "nowhere"), "--against", str(tmp_path / "on")],
        capture_output=True,
        text=True,
    )
    assert bad.returncode != 0 and "nowhere" in bad.stderr and "no results.csv" in bad.stderr
    neg = subprocess.run([*cmd, *args, "--bootstrap", "0"], capture_output=True, text=True)
    assert neg.returncode == 2 and "--bootstrap 0 is invalid" in neg.stderr
