"""Filter off against filter on, run by run (``baselines.safety_compare``): runs pair by
setting and seed, the changes and counts are the ones computed by hand, a setting swept only
on one side makes variants, an unreached band counts as "never", and bad input is refused
clearly."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from result_files import write_results

from baselines.experiments.safety.paired import compare_filter, paired_filter_lines


def _row(policy, n, flt, seed, err, band=3.0, **extra):
    """One benchmark row as read back from a results.csv (every value text)."""
    row = {
        "scenario": f"n_uavs={n}, safety_filter={flt}",
        "preset": "paper",
        "n_uavs": str(n),
        "init": "corners",
        "safety_filter": flt,
        **{k: str(v) for k, v in extra.items()},
        "policy": policy,
        "seed": str(seed),
        "pair": "0",
        "band_time": "" if band is None else str(band),
        "ss_mean_error": str(err),
        "closest_pass": "1.2",
    }
    return row


OFF = np.array([0.10, 0.12, 0.08, 0.20, 0.09])
ON = np.array([0.10, 0.15, 0.07, 0.19, 0.12])  # identical, +25 %, -12.5 %, -5 %, +33 %


def _suite(policy="smc", n=50, on=ON, off=OFF, seeds=None, **extra):
    seeds = range(len(off)) if seeds is None else seeds
    rows = [_row(policy, n, "none", s, e, **extra) for s, e in zip(seeds, off, strict=True)]
    rows += [_row(policy, n, "cbf", s, e, **extra) for s, e in zip(seeds, on, strict=True)]
    return rows


def test_changes_and_counts_match_a_hand_computation():
    rows = _suite() + _suite(n=100, on=OFF)  # at N = 100 the filter changed nothing
    res = compare_filter(rows, rng=np.random.default_rng(0), n_boot=200)
    by = {(r["group"]["n_uavs"], r["metric"]): r for r in res}
    assert set(by) == {(n, m) for n in ("50", "100") for m in ("ss_mean_error", "band_time")}
    r = by["50", "ss_mean_error"]
    assert r["runs"] == 5 and r["group"]["policy"] == "smc" and r["variant"] == {}
    assert r["a"] == (pytest.approx(0.10), pytest.approx(0.20), 0)
    assert r["b"] == (pytest.approx(0.12), pytest.approx(0.19), 0)
    assert r["median_change"] == pytest.approx(0.2)
    assert r["worst_change"] == pytest.approx(0.19 / 0.20 - 1)
    assert (r["worse"], r["better"], r["identical"]) == (2, 1, 1)
    assert r["ratio"][0] == pytest.approx(np.median(ON / OFF))
    assert r["ratio"][1] <= r["ratio"][0] <= r["ratio"][2]
    p90 = np.percentile(ON, 90) / np.percentile(OFF, 90) - 1
    assert r["p90_change"][0] == pytest.approx(p90)
    same = by["100", "ss_mean_error"]
    assert same["median_change"] == 0 and same["identical"] == 5 and same["ratio"][1:] == (1, 1)
    assert by["50", "band_time"]["identical"] == 5
    # the table leads with what differs between lines (N), not with what is constant
    lines = paired_filter_lines(res)
    assert lines[0].startswith("| policy | n_uavs | metric | runs |") and "preset" not in lines[0]
    assert len(lines) == 2 + 4 and "| 2 / 1 / 1 |" in lines[2] and "+20.0 %" in lines[2]


def test_bootstrap_is_seeded_and_covers_the_estimate():
    rng_rows = np.random.default_rng(5)
    off = rng_rows.uniform(0.05, 0.15, 60)
    on = off * rng_rows.uniform(0.8, 1.3, 60)
    rows = _suite(off=off, on=on)
    one = compare_filter(rows, rng=np.random.default_rng(3), metrics=["ss_mean_error"])
    two = compare_filter(rows, rng=np.random.default_rng(3), metrics=["ss_mean_error"])
    assert one == two
    lo, hi = one[0]["p90_change"][1:]
    assert lo < one[0]["p90_change"][0] < hi


def test_a_setting_swept_on_the_filter_side_only_makes_variants():
    off = [r for r in _suite() if r["safety_filter"] == "none"]
    on = []
    for ao, scale in (("40", 1.5), ("100", 1.0)):
        on += [
            _row("smc", 50, "cbf", s, e * scale, safety_other_accel=ao) for s, e in enumerate(OFF)
        ]
    res = compare_filter(off, on, metrics=["ss_mean_error"], rng=np.random.default_rng(0))
    by = {r["variant"]["safety_other_accel"]: r for r in res}
    assert set(by) == {"40", "100"}
    assert by["40"]["median_change"] == pytest.approx(0.5) and by["40"]["worse"] == 5
    assert by["100"]["identical"] == 5
    assert "| safety_other_accel=40 |" in "\n".join(paired_filter_lines(res))


def test_a_filter_off_side_with_several_variants_is_refused():
    on = [r for r in _suite() if r["safety_filter"] == "cbf"]
    off = []
    for d in ("0.1", "1"):
        off += [_row("smc", 50, "none", s, e, disturbance_std=d) for s, e in enumerate(OFF)]
    with pytest.raises(ValueError, match=r"run A has several values of \['disturbance_std'\]"):
        compare_filter(off, on, rng=np.random.default_rng(0))


def test_two_filter_off_runs_compare_as_a_placebo():
    off = [r for r in _suite() if r["safety_filter"] == "none"]
    moved = [_row("smc", 50, "none", s, e * 1.2, disturbance_std=1) for s, e in enumerate(OFF)]
    res = compare_filter(off, moved, filters=("none", "none"), rng=np.random.default_rng(0))
    assert res[0]["variant"] == {"disturbance_std": "1"} and res[0]["worse"] == 5
    assert res[0]["median_change"] == pytest.approx(0.2)


def test_runs_pair_only_within_their_controller_and_shared_seeds():
    rows = _suite() + _suite(policy="proportional", on=OFF * 2, seeds=range(3, 8))
    rows += [_row("smc", 50, "cbf", 99, 5.0)]  # a filter-on seed with no filter-off partner
    res = compare_filter(rows, rng=np.random.default_rng(0), metrics=["ss_mean_error"])
    by = {r["group"]["policy"]: r for r in res}
    assert by["smc"]["runs"] == 5 and by["smc"]["b"][1] == pytest.approx(0.19)
    assert by["proportional"]["runs"] == 5 and by["proportional"]["median_change"] == 1.0
    only = compare_filter(rows, policies=["proportional"], rng=np.random.default_rng(0))
    assert {r["group"]["policy"] for r in only} == {"proportional"}


def test_a_band_never_entered_counts_as_never():
    rows = _suite()
    rows[5 + 1]["band_time"] = ""  # filter on, seed 1: never entered the band
    res = compare_filter(rows, metrics=["band_time"], rng=np.random.default_rng(0))
    assert res[0]["b"][2] == 1 and res[0]["a"][2] == 0 and res[0]["identical"] == 4
    assert "3 / 3 (never in 1)" in paired_filter_lines(res)[2]


def test_bad_input_is_refused_clearly():
    rows = _suite()
    rng = np.random.default_rng(0)
    with pytest.raises(TypeError, match="rng=0 is invalid"):
        compare_filter(rows, rng=0)
    with pytest.raises(ValueError, match="n_boot=0 is invalid"):
        compare_filter(rows, rng=rng, n_boot=0)
    with pytest.raises(ValueError, match="metric 'steady' is not a column"):
        compare_filter(rows, rng=rng, metrics=["steady"])
    with pytest.raises(ValueError, match="seed 2, pair 0 twice"):
        compare_filter([*rows, rows[2]], rng=rng)
    with pytest.raises(ValueError, match=r"filters=\('none', 'on'\) is invalid"):
        compare_filter(rows, rng=rng, filters=("none", "on"))
    with pytest.raises(ValueError, match="no run of A with safety_filter=none pairs"):
        compare_filter([r for r in rows if r["safety_filter"] == "cbf"], rng=rng)
    with pytest.raises(ValueError, match=r"policies=\['sac'\] is invalid: .* have \['smc'\]"):
        compare_filter(rows, rng=rng, policies=["sac"])
    one = compare_filter(rows, rng=rng, policies="smc", metrics="band_time")  # one name
    assert [r["metric"] for r in one] == ["band_time"]
    with pytest.raises(ValueError, match="no rows"):
        compare_filter([], rng=rng)


def test_cli_pools_folders_and_names_bad_input(tmp_path):
    rows = _suite()
    write_results(tmp_path / "a", rows[:3] + rows[5:8])
    write_results(tmp_path / "b", rows[3:5] + rows[8:])
    cmd = [sys.executable, "-m", "baselines.safety_compare"]
    out = subprocess.run(
        [*cmd, str(tmp_path / "a"), str(tmp_path / "b"), "--metrics", "ss_mean_error"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert "| smc | ss_mean_error | 5 |" in out and "| 2 / 1 / 1 |" in out
    png = tmp_path / "paired.png"
    drawn = subprocess.run(
        [*cmd, str(tmp_path / "a"), str(tmp_path / "b"), "--figure", str(png)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert f"wrote {png}" in drawn and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    off = subprocess.run(
        [*cmd, str(tmp_path / "a"), "--against", str(tmp_path / "nowhere")],
        capture_output=True,
        text=True,
    )
    assert off.returncode != 0 and "--against" in off.stderr and "no results.csv" in off.stderr
    bad = subprocess.run(
        [*cmd, str(tmp_path / "a"), "--metrics", "steady"], capture_output=True, text=True
    )
    assert bad.returncode != 0 and "metric 'steady' is not a column" in bad.stderr
    neg = subprocess.run([*cmd, str(tmp_path / "a"), "--bootstrap", "0"], capture_output=True)
    assert neg.returncode == 2 and b"--bootstrap 0 is invalid" in neg.stderr


def test_a_lines_interval_does_not_depend_on_the_other_lines():
    rng_rows = np.random.default_rng(7)
    off = rng_rows.uniform(0.05, 0.15, 40)
    rows = _suite(off=off, on=off * rng_rows.uniform(0.8, 1.3, 40))
    rows += _suite(policy="proportional", off=off, on=off * rng_rows.uniform(0.8, 1.3, 40))
    both = compare_filter(rows, rng=np.random.default_rng(1))  # smc's lines resample first
    one = compare_filter(rows, rng=np.random.default_rng(1), policies=["proportional"])
    assert [r for r in both if r["group"]["policy"] == "proportional"] == one
