"""The whole-flight benchmark runs, as a user runs it, in its quick mode (seconds): an API
change breaks this test instead of the documented command."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_bench_flight_quick_runs_every_section():
    env = {**os.environ, "OMP_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}
    cmd = [sys.executable, str(ROOT / "benchmarks" / "bench_flight.py"), "--quick", "--cpu-time"]
    out = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    text = out.stdout
    assert "| `large`, 1,000 UAVs" in text
    assert "| `paper`, 100 UAVs, B = 1" in text and "B = 4" in text
    assert "shuffled / lattice" in text
