"""Smoke test of the reproduction CLI with a tiny set-up (subprocess, like a user)."""

from __future__ import annotations

import csv
import subprocess
import sys

import numpy as np


def test_reproduce_cli_writes_table_csv_and_figures(tmp_path):
    out = tmp_path / "rep"
    cmd = [
        sys.executable,
        "-m",
        "baselines.reproduce",
        "--n-uavs",
        "12",
        "--seeds",
        "2",
        "--horizon",
        "12",
        "--out",
        str(out),
        "--workers",
        "1",
        "--quiet",
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    with open(out / "results.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 * 3  # seeds x policies
    err = {
        r["policy"]: np.median(
            [float(x["ss_mean_error"]) for x in rows if x["policy"] == r["policy"]]
        )
        for r in rows
    }
    assert err["smc"] < err["proportional"] < err["zero"]
    assert "| 12 | smc |" in (out / "summary.md").read_text()
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert "pair_error.png" in pngs and "sliding_surface.png" in pngs
    assert all((out / p).read_bytes()[:4] == b"\x89PNG" for p in pngs)


def test_reproduce_help():
    proc = subprocess.run(
        [sys.executable, "-m", "baselines.reproduce", "--help"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 0 and "--seeds" in proc.stdout and "--check" in proc.stdout
