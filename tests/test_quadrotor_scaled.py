"""The Sec. VI-B criteria on a scaled scenario (the ``crazyflie`` preset): the paper's
thresholds times the scenario's length scale, its own windows, one implementation."""

from __future__ import annotations

import csv
import dataclasses

import pytest

from baselines.experiments.quadrotor.criteria import (
    LENGTH_FIELDS,
    QUADROTOR,
    SCENARIO_WINDOWS,
    check_quadrotor,
    criteria_for,
    length_scale,
)
from baselines.experiments.quadrotor.experiment import main
from pairflock_env import make_config


def test_crazyflie_criteria_are_the_paper_s_with_lengths_scaled_by_d_m():
    assert criteria_for("paper-quadrotor") == QUADROTOR
    cf, ref = make_config("crazyflie"), make_config("paper-quadrotor")
    scale = length_scale("crazyflie")
    assert scale == pytest.approx(0.25)
    # the preset is scaled as a whole: d_m, spacing and radius by the same factor
    assert cf.spacing / ref.spacing == pytest.approx(scale)
    assert cf.radius / ref.radius == pytest.approx(scale)
    crit = criteria_for("crazyflie")
    assert crit.vehicle == "crazyflie"
    for f in dataclasses.fields(QUADROTOR):
        want = getattr(QUADROTOR, f.name)
        if f.name in LENGTH_FIELDS:
            assert getattr(crit, f.name) == pytest.approx(scale * want), f.name
        elif f.name == "band_entry_by":
            assert crit.band_entry_by == want  # seconds stay seconds
    assert crit.min_distance == pytest.approx(cf.collision_distance)  # 0.125 m either way
    with pytest.raises(ValueError, match=r"'paper' has no Sec\. VI-B criteria"):
        criteria_for("paper")
    with pytest.raises(ValueError, match="must be a positive number"):
        QUADROTOR.scaled(0.0)


@pytest.mark.parametrize("preset", list(SCENARIO_WINDOWS))
def test_windows_follow_the_leader_s_turns(preset):
    """From 15 s on, every turn lies in a turn window; straight flight never overlaps one;
    the velocity check looks only at straight flight; everything within the episode."""
    cfg, c = make_config(preset), criteria_for(preset)

    def inside(a, b, windows):
        return any(lo <= a and b <= hi for lo, hi in windows)

    for t0, dur, _ in cfg.leader_turns:
        if t0 + dur <= cfg.horizon:
            assert inside(max(t0, 15.0), t0 + dur, c.turn_windows), (t0, dur)
    for a, b in c.straight_windows:
        assert 15.0 <= a < b <= cfg.horizon
        assert all(b <= lo or a >= hi for lo, hi in c.turn_windows), (a, b)
    for a, b in c.velocity_windows:
        assert inside(a, b, c.straight_windows), (a, b)


def _row(crit, seed, **over):
    row = {
        "dynamics": crit.vehicle,
        "policy": "smc",
        "seed": seed,
        "band_entry_time": crit.band_entry_by / 2,
        "straight_max_error": crit.straight_max / 2,
        "turn_peak_error": crit.turn_peak_max / 2,
        "min_distance": 2 * crit.min_distance,
        "velocity_mismatch": crit.velocity_tolerance / 2,
        "crashed": 0,
        "steps_run": 10,
    }
    return {**row, **over}


def test_the_check_reads_the_scenario_s_vehicle_and_thresholds():
    crit = criteria_for("crazyflie")
    rows = [_row(crit, 0), _row(crit, 1, min_distance=0.1)]  # 0.1 m < 0.125 m
    rows.append({**_row(crit, 0), "dynamics": "quadrotor", "min_distance": 0.0})  # not read
    checks = {text: (ok, detail) for text, ok, detail in check_quadrotor(rows, crit)}
    ok, detail = checks["smc: no two UAVs closer than 0.125 m"]
    assert not ok and detail == "min 0.100 m; 1/2 runs miss"
    assert checks["smc: first in the 0.125 m band within 10 s"][0]
    assert not any("attitude" in text for text in checks)  # no particle rows
    assert all(ok for text, (ok, _) in checks.items() if "closer" not in text)
    # the paper's criteria read the quadrotor rows only
    assert check_quadrotor(rows) == check_quadrotor(rows[2:])


def test_cli_runs_the_crazyflie_scenario_with_its_criteria(tmp_path):
    out = tmp_path / "cf"
    args = ["--preset", "crazyflie", "--policies", "smc", "--seeds", "1", "--horizon", "2"]
    assert main([*args, "--workers", "1", "--no-figures", "--quiet", "--out", str(out)]) == 0
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert sorted(r["dynamics"] for r in rows) == ["crazyflie", "particle"]
    # the closest pass also in the collision ellipsoid's measure (the preset sets it)
    assert all(float(r["min_ellipsoid_separation"]) > 0 for r in rows)
    assert all(int(r["ellipsoid_contact_steps"]) >= 0 for r in rows)
    summary = (out / "summary.md").read_text()
    assert "min ellipsoid separation" in summary
    assert "Preset `crazyflie`" in summary and "Band 0.125 m" in summary
    assert "[17,20], [27,30]" in summary and "on the crazyflie, every seed" in summary


def test_the_separation_line_reports_the_ellipsoid_measure_beside_it():
    crit = criteria_for("crazyflie")
    e = dict(min_ellipsoid_separation=1.5, ellipsoid_contact_steps=0)
    rows = [
        _row(crit, 0, **e),
        _row(crit, 1, min_ellipsoid_separation=0.8, ellipsoid_contact_steps=3),
    ]
    checks = {text: (ok, detail) for text, ok, detail in check_quadrotor(rows, crit)}
    ok, detail = checks["smc: no two UAVs closer than 0.125 m"]
    assert ok  # the criterion is the distance's; the ellipsoid is reported, not judged
    assert detail == (
        "min 0.250 m; ellipsoid: min 0.80 (>= 1: no contact), contact in 1/2 runs, 3 steps; "
        "0/2 runs miss"
    )
