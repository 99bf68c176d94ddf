"""The learned policies' targets (baselines.reporting.criteria): LEARNED at N = 20, corners,
GENERALIST on every evaluated (N, start), and the selection score built from them."""

import math
from types import SimpleNamespace

import pytest

from baselines.reporting.criteria import (
    GENERALIST,
    LEARNED,
    TARGETS,
    all_passed,
    check_learned,
    check_learned_all,
    learned_score,
)

pytest.importorskip("stable_baselines3")

from train.mix.evaluation import score_function
from train.settings import RunSettings
from train.sweep.trial import aims


def _rows(n, init, errs, bands, seps, peaks):
    keys = ("ss_mean_error", "band_time", "min_pair_separation", "peak_accel")
    return [
        {"policy": "learned", "n_uavs": n, "init": init, **dict(zip(keys, v, strict=True))}
        for v in zip(errs, bands, seps, peaks, strict=True)
    ]


def _good(n, init):
    return _rows(n, init, [0.004, 0.006, 0.008], [4.0, 4.5, 5.5], [1.2, 2.0, 3.0], [49, 50, 50])


def test_generalist_checks_every_setting_and_every_target():
    rows = _good(20, "corners") + _good(100, "random")
    checks = check_learned_all(rows, GENERALIST)
    assert all_passed(checks)
    assert {c.split(":")[0] for c, _, _ in checks} == {"N=20 corners", "N=100 random"}
    assert not any(c.endswith("(aim)") for c, _, _ in checks)  # separation is a target here
    assert len(checks) == 2 * 6  # median, worst, band max, band median, separation, peak


@pytest.mark.parametrize(
    "field, values, failing",
    [
        ("ss_mean_error", [0.02, 0.02, 0.02], "median steady-state"),
        ("ss_mean_error", [0.004, 0.006, 0.06], "no seed above"),
        ("band_time", [5.5, 5.5, 5.9], "median time into"),
        ("band_time", [4.0, 4.5, math.nan], "within 6 s"),
        ("min_pair_separation", [1.2, 0.99, 3.0], "min pair-to-other"),
        ("peak_accel", [49, 50, 50.5], "peak pair acceleration"),
    ],
)
def test_one_missed_generalist_target_fails_the_check(field, values, failing):
    rows = _good(50, "corners")
    for r, v in zip(rows, values, strict=True):
        r[field] = v
    checks = check_learned_all(rows, GENERALIST)
    assert not all_passed(checks)
    assert [c for c, ok, _ in checks if not ok] == [c for c, _, _ in checks if failing in c]


def test_learned_keeps_separation_as_an_aim_and_its_score_is_unchanged():
    rows = _good(20, "corners")
    rows[0]["min_pair_separation"] = 0.1
    assert all_passed(check_learned(rows, targets=LEARNED))  # an aim never fails the check
    assert not all_passed(check_learned(rows, targets=GENERALIST))
    s = {
        "ss_error_median": 0.07,
        "ss_error_max": 0.2,
        "band_time_max": 7.0,
        "band_time_median": 6.5,
        "min_separation_min": 0.5,
        "peak_accel_max": 60.0,
    }
    base = 0.02 / 0.05 + 0.1 / 0.1 + 1.0 / 6.0 + 0.5 + 0.07
    assert learned_score(s) == pytest.approx(base)
    extra = (6.5 - 5.0) / 5.0 + (60.0 - 50.0) / 50.0
    strict = (0.07 - 0.01) / 0.01 + (0.2 - 0.05) / 0.05 + 1.0 / 6.0 + 0.5 + 0.07 + extra
    assert learned_score(s, GENERALIST) == pytest.approx(strict)
    assert set(TARGETS) == {"learned", "generalist"}


def test_eval_targets_setting_is_validated_and_selects_the_score():
    with pytest.raises(ValueError, match="eval_targets='strict' is invalid"):
        RunSettings(eval_targets="strict", total_steps=64, eval_every=0)
    s = RunSettings(eval_targets="generalist")
    summary = {
        "ss_error_median": 0.02,
        "ss_error_max": 0.02,
        "band_time_max": 5.0,
        "band_time_median": 5.0,
        "min_separation_min": 2.0,
        "peak_accel_max": 50.0,
    }
    assert score_function(s)(summary) == pytest.approx(1.0 + 0.02)
    assert score_function(RunSettings())(summary) == pytest.approx(0.02)
    assert "eval_targets" not in RunSettings().to_dict()  # old runs store what they stored


def test_sweep_aims_judge_by_the_runs_targets():

    cfg = SimpleNamespace(n_uavs=50, init="random")
    rows = [
        {k: v for k, v in r.items() if k not in ("policy", "n_uavs", "init")}
        for r in _good(50, "random")
    ]
    learned = aims(rows, cfg)
    strict = aims(rows, cfg, GENERALIST)
    assert [a["criterion"] for a in learned][-1].endswith("(aim)") and len(learned) == 4
    assert len(strict) == 6 and all(a["met"] for a in strict)
    assert any("0.01 m" in a["criterion"] for a in strict)
