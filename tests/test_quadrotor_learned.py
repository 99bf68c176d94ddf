"""A learned pair policy in the quadrotor experiment (Sec. VI-B): ``--policies sb3:<name>``
runs it next to sliding mode on both vehicle models, the criteria are checked for it with the
same thresholds, sliding mode's lines stay those of the smc-only check, and a model that cannot
fly the 3-D scenario (the 2-D ``pair_n20_a50``) is refused before any run."""

from __future__ import annotations

import csv
import dataclasses

import pytest
from quadrotor_rows import quad_row as _row

from baselines.experiments.quadrotor.criteria import QUADROTOR, check_quadrotor
from baselines.experiments.quadrotor.experiment import main

LEARNED = "sb3:pair_quad3d"  # the packaged 3-D policy (train/configs/pair_quad3d.yaml)


def test_the_criteria_apply_to_any_named_controller_and_keep_smc_lines():
    seeds = range(3)
    rows = [
        _row(p, d, s) for p in ("smc", LEARNED) for d in ("quadrotor", "particle") for s in seeds
    ]
    rows.append(_row(LEARNED, "quadrotor", 3, turn_peak_error=2 * QUADROTOR.turn_peak_max))
    rows.append(_row(LEARNED, "particle", 3))
    smc_only = check_quadrotor(rows)
    assert smc_only and all(c.startswith("smc: ") for c, _, _ in smc_only)
    both = check_quadrotor(rows, policies=("smc", LEARNED))
    assert both[: len(smc_only)] == smc_only  # smc's output does not change
    learned = both[len(smc_only) :]
    assert [c.removeprefix(f"{LEARNED}: ") for c, _, _ in learned] == [
        c.removeprefix("smc: ") for c, _, _ in smc_only
    ]
    failed = [c for c, ok, _ in learned if not ok]
    assert len(failed) == 1 and "turns" in failed[0]  # the one seed out of the turn bound
    # each detail counts the runs that miss: one of the learned policy's four in the turns
    detail = {c.removeprefix(f"{LEARNED}: "): d for c, _, d in learned}
    assert [d.rsplit("; ", 1)[1] for d in detail.values()].count("0/4 runs miss") == 6  # of 7
    assert next(d for c, d in detail.items() if "turns" in c).endswith("; 1/4 runs miss")
    assert check_quadrotor(rows, policies=("proportional",)) == []  # no rows: no checks
    strict = dataclasses.replace(QUADROTOR, min_distance=3 * QUADROTOR.min_distance)
    assert not all(ok for _, ok, _ in check_quadrotor(rows, strict, policies=(LEARNED,)))
    with pytest.raises(TypeError, match="policies='smc'"):
        check_quadrotor(rows, policies="smc")


def test_the_experiment_runs_a_learned_policy_by_its_packaged_name(tmp_path):
    out = tmp_path / "q"
    common = ["--seeds", "1", "--horizon", "1", "--workers", "1", "--no-figures", "--quiet"]
    assert main(["--policies", "smc", LEARNED, *common, "--out", str(out)]) == 0
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert {(r["dynamics"], r["policy"]) for r in rows} == {
        (d, p) for d in ("quadrotor", "particle") for p in ("smc", LEARNED)
    }
    summary = (out / "summary.md").read_text()
    assert f"| {LEARNED}: first in the 0.5 m band" in summary
    assert "| smc: first in the 0.5 m band" in summary
    bad = [*common, "--out", str(tmp_path / "bad")]
    with pytest.raises(SystemExit, match=r"sb3:pair_n20_a50.*observes shape"):
        main(["--policies", "sb3:pair_n20_a50", *bad])  # a 2-D model in the 3-D scenario
    with pytest.raises(SystemExit, match=r"no_such_model.*does not exist"):
        main(["--policies", "sb3:no_such_model", *bad])
    with pytest.raises(SystemExit, match="--criteria-for 'zero' is invalid"):
        main(["--policies", "smc", "--criteria-for", "zero", *bad])
    assert not (tmp_path / "bad").exists()  # refused before anything was written
